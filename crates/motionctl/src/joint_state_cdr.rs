//! ROS 2 `sensor_msgs/msg/JointState` in CDR, written by hand for `record --out x.mcap`.
//!
//! The encoding is the one ROS 2's default middleware puts on the wire and in bags (OMG
//! "Extensible and Dynamic Topic Types for DDS" 1.3, section 7.4.3.5 "XCDR version 1",
//! little-endian, plain CDR): a 4-byte encapsulation header `00 01 00 00` (CDR_LE, options
//! 0), then the fields in declaration order, each primitive aligned to its own size counted
//! from the first byte *after* the header. A string is a `uint32` length that counts its
//! terminating NUL, the bytes and the NUL; a sequence is a `uint32` element count and the
//! elements (no padding before an empty sequence's absent first element).

/// The message definition in ROS 2's `ros2msg` schema format: the message's own text, then
/// each dependency under a line of 80 `=` and a `MSG: pkg/Type` line, as ROS 2 bags and
/// Foxglove's writers concatenate them.
pub const JOINT_STATE_DEFINITION: &str = "\
# The state of a set of joints (motiond: the recorded axes, in their configured units).
std_msgs/Header header

string[] name
float64[] position
float64[] velocity
float64[] effort

================================================================================
MSG: std_msgs/Header
# Standard metadata for higher-level stamped data types.
builtin_interfaces/Time stamp
string frame_id

================================================================================
MSG: builtin_interfaces/Time
# Time as seconds and nanoseconds since an epoch.
int32 sec
uint32 nanosec
";

/// The schema's name, as ROS 2 tools spell the type.
pub const JOINT_STATE_SCHEMA_NAME: &str = "sensor_msgs/msg/JointState";

/// The encapsulation header of little-endian plain CDR (XCDR1).
const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// `builtin_interfaces/Time`: seconds and nanoseconds since the epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamp {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds within the second, `0..1_000_000_000`.
    pub nanosec: u32,
}

/// A time that does not fit `builtin_interfaces/Time` (seconds past `i32::MAX`, 2038).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("time {0} ns since the epoch does not fit a ROS 2 stamp (int32 seconds)")]
pub struct StampOutOfRange(pub u64);

impl Stamp {
    /// Nanoseconds since the epoch, split.
    pub fn from_ns(ns: u64) -> Result<Self, StampOutOfRange> {
        let sec = i32::try_from(ns / 1_000_000_000).map_err(|_| StampOutOfRange(ns))?;
        // The remainder is below 10^9, which fits u32.
        let nanosec = (ns % 1_000_000_000) as u32;
        Ok(Self { sec, nanosec })
    }
}

/// One `sensor_msgs/msg/JointState`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointState<'a> {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// `header.frame_id`.
    pub frame_id: &'a str,
    /// The joints' names.
    pub name: &'a [&'a str],
    /// Positions, one per name.
    pub position: &'a [f64],
    /// Velocities, one per name.
    pub velocity: &'a [f64],
    /// Efforts: one per name, or empty when unknown.
    pub effort: &'a [f64],
}

/// Little-endian CDR into a byte vector, alignment counted after the encapsulation header.
#[derive(Debug)]
struct CdrWriter {
    bytes: Vec<u8>,
}

impl CdrWriter {
    fn new(capacity: usize) -> Self {
        let mut bytes = Vec::with_capacity(capacity + CDR_LE_HEADER.len());
        bytes.extend_from_slice(&CDR_LE_HEADER);
        Self { bytes }
    }

    fn align(&mut self, size: usize) {
        let offset = self.bytes.len() - CDR_LE_HEADER.len();
        let padding = (size - offset % size) % size;
        self.bytes.resize(self.bytes.len() + padding, 0);
    }

    fn u32(&mut self, value: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    fn i32(&mut self, value: i32) {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    fn f64(&mut self, value: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// A sequence's or a string's length (CDR lengths are `uint32`).
    fn length(&mut self, length: usize) -> Result<(), TooLong> {
        self.u32(u32::try_from(length).map_err(|_| TooLong(length))?);
        Ok(())
    }

    fn string(&mut self, text: &str) -> Result<(), TooLong> {
        self.length(text.len() + 1)?;
        self.bytes.extend_from_slice(text.as_bytes());
        self.bytes.push(0);
        Ok(())
    }

    fn strings(&mut self, texts: &[&str]) -> Result<(), TooLong> {
        self.length(texts.len())?;
        texts.iter().try_for_each(|text| self.string(text))
    }

    fn f64s(&mut self, values: &[f64]) -> Result<(), TooLong> {
        self.length(values.len())?;
        values.iter().for_each(|&value| self.f64(value));
        Ok(())
    }
}

/// A string or sequence longer than CDR's `uint32` length can say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{0} elements do not fit a CDR length (uint32)")]
pub struct TooLong(pub usize);

impl JointState<'_> {
    /// The message in little-endian CDR, encapsulation header first.
    pub fn to_cdr(self) -> Result<Vec<u8>, TooLong> {
        let names: usize = self.name.iter().map(|name| name.len() + 8).sum();
        let numbers = 8 * (self.position.len() + self.velocity.len() + self.effort.len());
        let mut cdr = CdrWriter::new(32 + self.frame_id.len() + names + numbers);
        cdr.i32(self.stamp.sec);
        cdr.u32(self.stamp.nanosec);
        cdr.string(self.frame_id)?;
        cdr.strings(self.name)?;
        cdr.f64s(self.position)?;
        cdr.f64s(self.velocity)?;
        cdr.f64s(self.effort)?;
        Ok(cdr.bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_joint_pins_every_byte_and_pad() {
        let message = JointState {
            stamp: Stamp { sec: 1, nanosec: 2 },
            frame_id: "",
            name: &["x"],
            position: &[1.5],
            velocity: &[-2.0],
            effort: &[],
        };
        #[rustfmt::skip]
        let expected: Vec<u8> = vec![
            0x00, 0x01, 0x00, 0x00, // encapsulation: CDR_LE, options 0
            1, 0, 0, 0, // 0: stamp.sec
            2, 0, 0, 0, // 4: stamp.nanosec
            1, 0, 0, 0, 0, // 8: frame_id: length 1 (the NUL), NUL
            0, 0, 0, // 13: pad to 16
            1, 0, 0, 0, // 16: name: 1 element
            2, 0, 0, 0, b'x', 0, // 20: "x": length 2, 'x', NUL
            0, 0, // 26: pad to 28
            1, 0, 0, 0, // 28: position: 1 element
            0, 0, 0, 0, 0, 0, 0xf8, 0x3f, // 32: 1.5
            1, 0, 0, 0, // 40: velocity: 1 element
            0, 0, 0, 0, // 44: pad to 48
            0, 0, 0, 0, 0, 0, 0, 0xc0, // 48: -2.0
            0, 0, 0, 0, // 56: effort: empty
        ];
        assert_eq!(message.to_cdr(), Ok(expected));
    }

    #[test]
    fn two_joints_with_a_frame_id_and_efforts() {
        let message = JointState {
            stamp: Stamp {
                sec: 0x0102_0304,
                nanosec: 999_999_999,
            },
            frame_id: "base",
            name: &["a", "bc"],
            position: &[0.0, 1.0],
            velocity: &[0.0, 0.0],
            effort: &[0.25, 0.0],
        };
        #[rustfmt::skip]
        let expected: Vec<u8> = vec![
            0x00, 0x01, 0x00, 0x00,
            0x04, 0x03, 0x02, 0x01, // 0: sec
            0xff, 0xc9, 0x9a, 0x3b, // 4: 999 999 999
            5, 0, 0, 0, b'b', b'a', b's', b'e', 0, // 8: "base"
            0, 0, 0, // 17: pad to 20
            2, 0, 0, 0, // 20: two names
            2, 0, 0, 0, b'a', 0, // 24: "a"
            0, 0, // 30: pad to 32
            3, 0, 0, 0, b'b', b'c', 0, // 32: "bc"
            0, // 39: pad to 40
            2, 0, 0, 0, // 40: two positions
            0, 0, 0, 0, // 44: pad to 48
            0, 0, 0, 0, 0, 0, 0, 0, // 48: 0.0
            0, 0, 0, 0, 0, 0, 0xf0, 0x3f, // 56: 1.0
            2, 0, 0, 0, // 64: two velocities
            0, 0, 0, 0, // 68: pad to 72
            0, 0, 0, 0, 0, 0, 0, 0, // 72
            0, 0, 0, 0, 0, 0, 0, 0, // 80
            2, 0, 0, 0, // 88: two efforts
            0, 0, 0, 0, // 92: pad to 96
            0, 0, 0, 0, 0, 0, 0xd0, 0x3f, // 96: 0.25
            0, 0, 0, 0, 0, 0, 0, 0, // 104: 0.0
        ];
        assert_eq!(message.to_cdr(), Ok(expected));
    }

    #[test]
    fn no_joints_is_a_header_and_four_empty_sequences() {
        let message = JointState {
            stamp: Stamp { sec: 0, nanosec: 0 },
            frame_id: "",
            name: &[],
            position: &[],
            velocity: &[],
            effort: &[],
        };
        let cdr = message.to_cdr().expect("short");
        #[rustfmt::skip]
        let expected = [
            0, 1, 0, 0,
            0, 0, 0, 0, 0, 0, 0, 0, // stamp
            1, 0, 0, 0, 0, 0, 0, 0, // "" and pad
            0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, // four empty sequences
        ];
        assert_eq!(cdr, expected);
    }

    #[test]
    fn stamps_split_nanoseconds_and_refuse_2038() {
        assert_eq!(
            Stamp::from_ns(1_700_000_000_123_456_789),
            Ok(Stamp {
                sec: 1_700_000_000,
                nanosec: 123_456_789
            })
        );
        let past_2038 = (i32::MAX as u64 + 1) * 1_000_000_000;
        assert_eq!(Stamp::from_ns(past_2038), Err(StampOutOfRange(past_2038)));
    }

    #[test]
    fn the_definition_names_both_dependencies_once() {
        let separator = format!("\n{}\n", "=".repeat(80));
        let parts: Vec<&str> = JOINT_STATE_DEFINITION.split(&separator).collect();
        assert_eq!(parts.len(), 3);
        assert!(parts[1].starts_with("MSG: std_msgs/Header\n"));
        assert!(parts[2].starts_with("MSG: builtin_interfaces/Time\n"));
    }
}
