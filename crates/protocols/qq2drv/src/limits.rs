//! Documented ranges, defaults, units and rates.

/// Protocol version this crate implements ("Applicable interface protocol version: v1").
pub const PROTOCOL_VERSION: u8 = 1;
/// Fixed-point shift of packets 26 and 34 velocities and of every acceleration (docs/ARCHITECTURE.md).
pub const FIXED_SHIFT: u32 = 12;
/// One Stream Period / Stream Period Timing unit, in nanoseconds (40.96 µs).
pub const STREAM_TICK_NS: u64 = 40_960;
/// One Maximum Averaging Time unit, in nanoseconds (0.64 µs).
pub const AVERAGING_TICK_NS: u64 = 640;
/// PID loop rate.
pub const LOOP_RATE_HZ: u32 = 500;
/// Rated maximum quadrature transitions per second (Features).
pub const RATED_MAX_TRANSITIONS_PER_S: u32 = 50_000;
/// Velocity resolution in transitions/s (Features).
pub const VELOCITY_RESOLUTION: u32 = 4;
/// Quadrature transitions per detent.
pub const TRANSITIONS_PER_DETENT: u32 = 4;
/// PWM frequency of the motor outputs.
pub const PWM_HZ: u32 = 11_000;

/// Packet 18 Power range: −8191..=8191.
pub const POWER_MAX: i16 = 8_191;
/// Packet 24 Power Limit range: 0..=8191.
pub const POWER_LIMIT_MAX: u16 = 8_191;
/// Packets 22 and 36 velocity targets: ±100 000 transitions/s.
pub const VELOCITY_TARGET_MAX: i32 = 100_000;
/// Packets 26 and 34 velocities: 0..=100 000 shl 12.
pub const VELOCITY_LIMIT_MAX: u32 = 100_000 << FIXED_SHIFT;
/// Packets 28, 34, 36 accelerations: 0..=1 000 000 shl 12.
pub const ACCELERATION_MAX: u32 = 1_000_000 << FIXED_SHIFT;
/// Packet 30 Windup Limit range: 0..=8191.
pub const WINDUP_MAX: u16 = 8_191;
/// Packet 12 History Length range.
pub const HISTORY_LENGTH_RANGE: core::ops::RangeInclusive<u8> = 2..=127;
/// Packet 12 Maximum Averaging Time in Bits range.
pub const AVERAGING_BITS_RANGE: core::ops::RangeInclusive<u8> = 14..=32;

/// Packet 30 defaults: P, I, D, Windup Limit.
pub const POSITION_PID_DEFAULT: (u16, u16, u16, u16) = (100, 500, 500, 600);
/// Packet 32 defaults: P, I, D.
pub const VELOCITY_PID_DEFAULT: (u16, u16, u16) = (100, 200, 500);

/// A shl-12 fixed-point value (packets 26, 34 velocities; 28, 34, 36 accelerations) as a
/// plain number of transitions/s or transitions/s².
pub fn from_fixed(value: u32) -> f64 {
    f64::from(value) / f64::from(1u32 << FIXED_SHIFT)
}

/// Transitions/s (or /s²) as a shl-12 fixed-point value, rounded; `None` when negative,
/// not finite or beyond `u32`.
pub fn to_fixed(value: f64) -> Option<u32> {
    let scaled = (value * f64::from(1u32 << FIXED_SHIFT)).round();
    (scaled.is_finite() && (0.0..=f64::from(u32::MAX)).contains(&scaled)).then_some(scaled as u32)
}

/// A Stream Period / Stream Period Timing value as a duration (units of 40.96 µs).
pub const fn stream_units_to_duration(units: u16) -> core::time::Duration {
    core::time::Duration::from_nanos(units as u64 * STREAM_TICK_NS)
}

/// A duration in whole 40.96 µs units, rounded to nearest and clipped at 0xFFFF (as Stream
/// Period Timing clips).
pub fn duration_to_stream_units(d: core::time::Duration) -> u16 {
    let units = (d.as_nanos() + u128::from(STREAM_TICK_NS / 2)) / u128::from(STREAM_TICK_NS);
    u16::try_from(units).unwrap_or(u16::MAX)
}

/// How the board's firmware reads packet 36's Velocity. The datasheet gives two readings
/// (docs/ARCHITECTURE.md): the field is an I32, where packet 34's Velocity is a U32, and
/// packet 22's I32 Velocity Target ranges "-100,000 shl 12 - 100,000 shl 12"; yet packet
/// 36's text says "Range: 0 - 100,000". A board that reads it as unsigned may answer a
/// negative value with an error, clamp it, or run forward at full speed: nothing on the
/// wire tells the readings apart safely, so it is a per-device setting (`velocity_ramp`,
/// docs/keys/qq2drv.md).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum VelocityRampSign {
    /// A signed velocity, negative for reverse (the field's I32, packet 22's range). The
    /// default.
    #[default]
    Signed,
    /// Forward only, "Range: 0 - 100,000": a reverse velocity target goes out as packet 22.
    Unsigned,
}

impl VelocityRampSign {
    /// Whether packet 36 can carry `velocity` (transitions/s) under this reading.
    pub const fn carries(self, velocity: i32) -> bool {
        match self {
            Self::Signed => velocity.unsigned_abs() <= VELOCITY_TARGET_MAX.unsigned_abs(),
            Self::Unsigned => 0 <= velocity && velocity <= VELOCITY_TARGET_MAX,
        }
    }
}

/// Maximum Averaging Time for a "Maximum Averaging Time in Bits" value (2^bits × 0.64 µs).
pub fn averaging_time(bits: u8) -> core::time::Duration {
    let ticks = 1u128 << bits.min(64);
    let nanos = ticks.saturating_mul(u128::from(AVERAGING_TICK_NS));
    core::time::Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_conversions() {
        // Packet 26: "Velocity Limit = <transitions/s> shl 12".
        assert_eq!(to_fixed(2000.0), Some(2000 << 12));
        assert_eq!(from_fixed(2000 << 12), 2000.0);
        assert_eq!(to_fixed(-1.0), None);
        assert_eq!(to_fixed(0.5), Some(2048));
        // Packet 4: "Stream Period in Microseconds = Stream Period x 40.96".
        assert_eq!(stream_units_to_duration(100).as_nanos(), 4_096_000);
        assert_eq!(duration_to_stream_units(stream_units_to_duration(108)), 108);
        assert_eq!(
            duration_to_stream_units(core::time::Duration::from_secs(10)),
            0xFFFF
        );
        // Packet 12 table: 20 bits → 671.1 ms, 14 bits → 10.5 ms.
        assert_eq!(averaging_time(20).as_micros(), 671_088);
        assert_eq!(averaging_time(14).as_micros(), 10_485);
    }

    /// Packet 36: an I32 "Velocity" with "Range: 0 - 100,000".
    #[test]
    fn packet_36_velocity_readings() {
        assert_eq!(VelocityRampSign::default(), VelocityRampSign::Signed);
        for v in [0, 1, 100_000] {
            assert!(VelocityRampSign::Signed.carries(v));
            assert!(VelocityRampSign::Unsigned.carries(v));
        }
        for v in [-1, -100_000] {
            assert!(VelocityRampSign::Signed.carries(v));
            assert!(!VelocityRampSign::Unsigned.carries(v));
        }
        for v in [100_001, -100_001, i32::MIN, i32::MAX] {
            assert!(!VelocityRampSign::Signed.carries(v));
            assert!(!VelocityRampSign::Unsigned.carries(v));
        }
    }
}
