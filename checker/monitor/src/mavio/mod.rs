//! MAVLink input and output: frames read from logs and links.

pub mod frame;
pub use frame::Frame;
