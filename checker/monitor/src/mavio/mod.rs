//! MAVLink input and output: frames read from logs and links.

pub mod frame;
pub use frame::Frame;

pub mod census;
pub mod log;
pub mod mission;
pub mod parse;
pub mod pcap;
pub mod upload;
