//! Streaming setpoints to a group (not yet measured).

use core::time::Duration;

use crate::group_client::{GroupClient, GroupDesc};
use crate::report::Row;

/// What the streaming phase measured.
#[derive(Debug)]
pub struct StreamRun {}

/// Streams velocity setpoints to `base`.
pub fn run(
    _client: &mut GroupClient,
    _base: &GroupDesc,
    _tick_hz: u32,
    _priority: Option<u8>,
    _duration: Duration,
) -> Result<StreamRun, String> {
    Err("not measured yet".to_owned())
}

/// The streaming rows.
pub fn rows(_run: &StreamRun) -> Vec<Row> {
    Vec::new()
}

/// The streaming distribution files.
pub fn files(_run: &StreamRun) -> Vec<(String, String, &crate::dist::Dist)> {
    Vec::new()
}
