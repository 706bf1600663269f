//! The driver's smallest representable velocity and acceleration ([`Driver::rate_floor`]),
//! from the board's datasheet (the "QSB Command List" v1.28, as docs/ARCHITECTURE.md "The boards" names it);
//! the engine refuses slower goals (`motion_ipc::rules`: `VelocityLimit`, `AccelLimit`)
//! instead of letting the board round them to nothing or up to its step.

use board_qsb::driver::{QsbDriver, QsbDriverConfig};
use motion_drivers::{Driver, RateFloor};

/// QSB Command List 1.28: MD JOG RATE "Motor rate will change in increments of 16
/// steps/second"; MD STEP RATE "Set motor step rate from 32 – 13000 steps/second"; MD ACCEL
/// "Set motor step acceleration from 64 – 360000 steps/second^2". In counts: times
/// `counts_per_step`, whatever its sign.
#[test]
fn qsb_16_and_32_steps_per_second_and_64_steps_per_second_squared_in_counts() {
    for counts_per_step in [10.0, -4.0, 0.5] {
        let driver = QsbDriver::new(QsbDriverConfig {
            counts_per_step,
            ..QsbDriverConfig::default()
        });
        let per_step = f64::abs(counts_per_step);
        assert_eq!(
            driver.rate_floor(0),
            RateFloor {
                velocity: 16.0 * per_step,
                profile_velocity: 32.0 * per_step,
                accel: 64.0 * per_step,
            },
            "{counts_per_step} counts/step"
        );
        assert_eq!(driver.rate_floor(1), RateFloor::NONE);
    }
}
