//! The driver's smallest representable velocity and acceleration ([`Driver::rate_floor`]),
//! from the board's datasheet (the SPI_motor "Motor protocol" page, as docs/ARCHITECTURE.md "The boards" names it);
//! the engine refuses slower goals (`motion_ipc::rules`: `VelocityLimit`, `AccelLimit`)
//! instead of letting the board round them to nothing or up to its step.

use board_spimotor::driver::{SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};
use motion_drivers::{Driver, RateFloor};

/// SPI_motor "Motor protocol": "0x43 | set stepdelay. (in tenths of a millisecond …)", one
/// byte: the slowest rate is one step per 25.5 ms. The acceleration is the driver's own
/// profile (the board has none): no floor. Brushed motors take power only.
#[test]
fn spimotor_one_step_per_25_5_ms_and_no_acceleration_step() {
    let stepper = SpimotorDriver::new(SpimotorDriverConfig::default());
    let floor = stepper.rate_floor(0);
    assert!((floor.velocity - 1.0 / 0.0255).abs() < 1e-9, "{floor:?}");
    assert_eq!(floor.profile_velocity, floor.velocity);
    assert_eq!(floor.accel, 0.0);
    let brushed = SpimotorDriver::new(SpimotorDriverConfig {
        drive: SpimotorDrive::Brushed,
        ..SpimotorDriverConfig::default()
    });
    assert_eq!(brushed.rate_floor(0), RateFloor::NONE);
    assert_eq!(brushed.rate_floor(1), RateFloor::NONE);
}
