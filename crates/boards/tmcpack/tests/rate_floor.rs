//! The driver's smallest representable velocity and acceleration ([`Driver::rate_floor`]),
//! from the board's datasheet (the SIXpack / QUADpack manual V2.43, as docs/ARCHITECTURE.md "The boards" names it);
//! the engine refuses slower goals (`motion_ipc::rules`: `VelocityLimit`, `AccelLimit`)
//! instead of letting the board round them to nothing or up to its step.

use board_tmcpack::driver::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
use motion_drivers::{Driver, RateFloor};

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
