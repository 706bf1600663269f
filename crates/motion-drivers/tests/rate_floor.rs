//! Every driver's smallest representable velocity and acceleration ([`Driver::rate_floor`]),
//! from its board's datasheet (the documents docs/ARCHITECTURE.md "The boards" names by
//! title and version: "QuadQuad2Drv PCB Datasheet", the SIXpack / QUADpack manual V2.43,
//! the SPI_motor "Motor protocol" page, the "QSB Command List" v1.28); the engine refuses
//! slower goals
//! (`motion_ipc::rules`: `VelocityLimit`, `AccelLimit`) instead of letting a board round
//! them to nothing or up to its step.

use motion_drivers::qq2drv::{Qq2drvDriver, Qq2drvDriverConfig};
use motion_drivers::qsb::{QsbDriver, QsbDriverConfig};
use motion_drivers::spimotor::{SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};
use motion_drivers::tmcpack::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
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

/// SIXpack/QUADpack manual, "Instruction Set": f_micro-step = f_clk / (clkdiv + 1) · v_i /
/// 2^(14 + div_i), f_clk = 20 MHz, v_i in −511..+511 — velocity 1 is the step; `$14`: "1/64
/// amax is accumulated with 500Hz during acceleration" — amax 1 is 500/64 velocity units/s².
/// Counts are microsteps.
#[test]
fn tmcpack_one_velocity_unit_and_one_amax_unit_of_the_motor_s_clock() {
    let mut config = TmcpackDriverConfig::default();
    config.channels[0] = Some(TmcpackChannel {
        max_velocity: 6_400.0,
        max_accel: 32_000.0,
        ..TmcpackChannel::default()
    });
    config.channels[1] = Some(TmcpackChannel {
        max_velocity: 200.0,
        max_accel: 1_000.0,
        ..TmcpackChannel::default()
    });
    let driver = TmcpackDriver::new(config);
    let steps: Vec<f64> = (0..=255u32)
        .flat_map(|clkdiv| {
            (0..=3u32).map(move |div| 20e6 / f64::from(clkdiv + 1) / f64::from(1u32 << (14 + div)))
        })
        .collect();
    for (channel, max_velocity) in [(0, 6_400.0), (1, 200.0)] {
        let floor = driver.rate_floor(channel);
        assert!(
            steps
                .iter()
                .any(|step| (step - floor.velocity).abs() <= 1e-9 * step),
            "channel {channel}: {} µsteps/s is no f_clk/(clkdiv+1)/2^(14+div)",
            floor.velocity
        );
        // The manual's choice of scale: the axis's limit is reachable with v ≤ 511.
        assert!(511.0 * floor.velocity >= max_velocity, "{floor:?}");
        assert!(
            (floor.accel - floor.velocity * 500.0 / 64.0).abs() <= 1e-9 * floor.accel,
            "{floor:?}"
        );
        assert_eq!(floor.profile_velocity, floor.velocity);
    }
    // The slower motor has the finer step (a larger divider).
    assert!(driver.rate_floor(1).velocity < driver.rate_floor(0).velocity);
    assert_eq!(driver.rate_floor(2), RateFloor::NONE, "no motor configured");
}
