#[path = "metamorphic/common.rs"]
mod common;
