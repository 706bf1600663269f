//! A frame's digest: one 64-bit hash per region of the frame the engine wrote — the
//! header, the device states, each axis's state, each axis's wire stamps, each signal and
//! each group — so that a replay names the first region that differs, not only the tick.
//! The tick's own stamps (`time_ns`, `publish_ns`, written after the step) are left out.

use motion_ipc::schema::{Fields, each_number};
use motion_ipc::{MAX_AXES, MAX_GROUPS, MAX_SIGNALS, MotionFrame};

/// The most regions a frame has.
pub const MAX_REGIONS: usize = 2 + 2 * MAX_AXES + MAX_SIGNALS + MAX_GROUPS;

/// A region of the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Schema, counts, tick and flags.
    Header,
    /// The device states.
    Devices,
    /// `axes[i]`.
    Axis(usize),
    /// `wire[i]`.
    Wire(usize),
    /// `signals[i]`.
    Signal(usize),
    /// `groups[i]`.
    Group(usize),
}

/// The digest of one frame, region by region.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameDigest {
    values: [u64; MAX_REGIONS],
    len: usize,
    axes: usize,
    signals: usize,
}

/// A 64-bit hash fed each number whole with its offset (one multiply per number: the tick
/// pays for it), and raw bytes for the device states.
struct Fnv(u64);

impl Fnv {
    const START: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0100_0000_01b3;
    fn feed(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            self.0 ^= u64::from(byte);
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }
    fn number(&mut self, at: usize, bits: u64) {
        self.0 = (self.0 ^ bits)
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .rotate_left(29);
        self.0 = (self.0 ^ at as u64).wrapping_mul(Self::PRIME);
    }
}

fn hash_of<T: Fields>(value: &T) -> u64 {
    let mut fnv = Fnv(Fnv::START);
    each_number(value, |at, bits| fnv.number(at, bits));
    fnv.0
}

impl FrameDigest {
    /// The digest of `frame` as the engine wrote it.
    pub fn of(frame: &MotionFrame) -> Self {
        let axes = (frame.axis_count as usize).min(MAX_AXES);
        let signals = (frame.signal_count as usize).min(MAX_SIGNALS);
        let groups = (frame.group_count as usize).min(MAX_GROUPS);
        let mut digest = Self {
            values: [0; MAX_REGIONS],
            len: 0,
            axes,
            signals,
        };
        let mut header = Fnv(Fnv::START);
        for (at, bits) in [
            (0, u64::from(frame.schema_version)),
            (1, u64::from(frame.axis_count)),
            (2, frame.tick),
            (3, u64::from(frame.flags)),
            (4, u64::from(frame.signal_count)),
            (5, u64::from(frame.device_count)),
            (6, u64::from(frame.group_count)),
        ] {
            header.number(at, bits);
        }
        digest.push(header.0);
        let mut devices = Fnv(Fnv::START);
        devices.feed(&frame.devices);
        digest.push(devices.0);
        for axis in &frame.axes[..axes] {
            digest.push(hash_of(axis));
        }
        for wire in &frame.wire[..axes] {
            digest.push(hash_of(wire));
        }
        for signal in &frame.signals[..signals] {
            digest.push(hash_of(signal));
        }
        for group in &frame.groups[..groups] {
            digest.push(hash_of(group));
        }
        digest
    }

    fn push(&mut self, value: u64) {
        if let Some(slot) = self.values.get_mut(self.len) {
            *slot = value;
            self.len += 1;
        }
    }

    /// The region hashes, in order.
    pub fn values(&self) -> &[u64] {
        &self.values[..self.len]
    }

    /// The region of hash `index` in this frame's layout.
    pub fn region(&self, index: usize) -> Region {
        let (axes, signals) = (self.axes, self.signals);
        match index {
            0 => Region::Header,
            1 => Region::Devices,
            i if i < 2 + axes => Region::Axis(i - 2),
            i if i < 2 + 2 * axes => Region::Wire(i - 2 - axes),
            i if i < 2 + 2 * axes + signals => Region::Signal(i - 2 - 2 * axes),
            i => Region::Group(i - 2 - 2 * axes - signals),
        }
    }

    /// The first region where `recorded` (as a record's payload) differs from this
    /// digest; `None` when they are the same.
    pub fn first_difference(&self, recorded: &[u8]) -> Option<Region> {
        let mut recorded = recorded.chunks_exact(8).map(|bytes| {
            let mut word = [0u8; 8];
            word.copy_from_slice(bytes);
            u64::from_le_bytes(word)
        });
        for (index, value) in self.values().iter().enumerate() {
            if recorded.next() != Some(*value) {
                return Some(self.region(index));
            }
        }
        // A recording with more regions than this frame differs past its end.
        recorded.next().map(|_| self.region(self.len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> Box<MotionFrame> {
        let mut frame = Box::new(MotionFrame::EMPTY);
        frame.axis_count = 3;
        frame.signal_count = 1;
        frame.group_count = 1;
        frame.tick = 7;
        frame
    }

    fn bytes(digest: &FrameDigest) -> Vec<u8> {
        digest
            .values()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    #[test]
    fn a_change_in_one_axis_is_named_by_that_axis() {
        let recorded = FrameDigest::of(&frame());
        assert_eq!(recorded.values().len(), 2 + 3 + 3 + 1 + 1);
        let same = FrameDigest::of(&frame());
        assert_eq!(same.first_difference(&bytes(&recorded)), None);
        let mut changed = frame();
        changed.axes[1].position += 1e-9;
        assert_eq!(
            FrameDigest::of(&changed).first_difference(&bytes(&recorded)),
            Some(Region::Axis(1))
        );
        let mut changed = frame();
        changed.groups[0].time += 0.5;
        assert_eq!(
            FrameDigest::of(&changed).first_difference(&bytes(&recorded)),
            Some(Region::Group(0))
        );
    }

    #[test]
    fn the_ticks_own_stamps_are_not_in_the_digest() {
        let recorded = FrameDigest::of(&frame());
        let mut stamped = frame();
        stamped.time_ns = 123;
        stamped.publish_ns = 456;
        assert_eq!(
            FrameDigest::of(&stamped).first_difference(&bytes(&recorded)),
            None
        );
        let mut flagged = frame();
        flagged.flags ^= 1;
        assert_eq!(
            FrameDigest::of(&flagged).first_difference(&bytes(&recorded)),
            Some(Region::Header)
        );
    }
}
