//! The driver's smallest representable velocity and acceleration ([`Driver::rate_floor`]),
//! from the board's datasheet (the "QuadQuad2Drv PCB Datasheet", as docs/ARCHITECTURE.md "The boards" names it);
//! the engine refuses slower goals (`motion_ipc::rules`: `VelocityLimit`, `AccelLimit`)
//! instead of letting the board round them to nothing or up to its step.

use board_qq2drv::driver::{Qq2drvDriver, Qq2drvDriverConfig};
use motion_drivers::{Driver, RateFloor};

/// QuadQuad2Drv datasheet, packet 36 "Velocity Ramp": "Velocity target, specified as:
/// Velocity = <transitions/s>" (plain) and "Acceleration = <transitions/s/s> shl 12";
/// packet 34 "Position Ramp": "Velocity = <transitions/s> shl 12"; packet 28: "The extra
/// bits can be used to specify a fractional acceleration".
#[test]
fn qq2drv_one_transition_per_second_and_4096ths_in_profiles_and_accelerations() {
    let driver = Qq2drvDriver::new(Qq2drvDriverConfig::default());
    for channel in 0..driver.channel_count() {
        assert_eq!(
            driver.rate_floor(channel),
            RateFloor {
                velocity: 1.0,
                profile_velocity: 1.0 / 4096.0,
                accel: 1.0 / 4096.0,
            }
        );
    }
    assert_eq!(driver.rate_floor(4), RateFloor::NONE, "no fifth channel");
}
