//! Documented ranges, defaults, units and rates.

/// Protocol version this crate implements ("Applicable interface protocol version: v1").
pub const PROTOCOL_VERSION: u8 = 1;
/// Fixed-point shift of packets 26 and 34 velocities and of every acceleration (DESIGN.md).
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
