//! The geometry engine: the only module that may name parry3d and nalgebra.
pub mod bnb;
pub mod placement;
