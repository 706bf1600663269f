//! Unit tests of the two firmware readings a pack is configured with ("SIXpack / QUADpack
//! manual" V2.43; docs/ARCHITECTURE.md): `amax_divisor` (`$14`) and `stop_no_ref_bit`
//! (`$15` P6), on the fake clock.

use tmcpack::{Action, AmaxDivisor, MotorOptions, OptionsLayout, Request};

use super::bench::*;
use super::*;

fn with(amax_divisor: AmaxDivisor, options_layout: OptionsLayout) -> TmcpackDriverConfig {
    TmcpackDriverConfig {
        amax_divisor,
        options_layout,
        ..config()
    }
}

fn p6_of_motor_0(sent: &[Request]) -> u8 {
    sent.iter()
        .find_map(|r| match r {
            Request::MotorParameters {
                motor: 0, options, ..
            } => Some(options.bits()),
            _ => None,
        })
        .expect("$15 of motor 0")
}

/// 7.1 "Default Values": "amax=128; // increments v by 128/16=8 each 2 ms". The axis's
/// 160000 µsteps/s² at 64.25 µsteps/s per unit is 160000 · 16 / 500 / 64.25 = 79.7 → 79
/// (against 318 under the `$14` text's /64); vstart keeps one tick's change within it.
#[test]
fn the_7_1_reading_programs_a_quarter_of_the_amax() {
    let mut bench = Bench::new(with(AmaxDivisor::By16, OptionsLayout::Table));
    let sent = bench.online();
    assert!(sent.contains(&Request::VelocityAcceleration {
        motor: 0,
        amax: 79,
        vmax: 498
    }));
    assert!(sent.contains(&Request::StartingVelocity {
        motor: 0,
        vmin: 0,
        vstart: 5,
        div: 0
    }));
    // A stop at the axis limit is rounded up: 80 (319 under /64), right after the `$25`.
    bench.serve(40, |m| position(m, 0, Action::Inactive));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    let (_, w) = bench.next(20).expect("$25");
    assert_eq!(w, [0x01, 0x25, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        bench.request(),
        Request::VelocityAcceleration {
            motor: 0,
            amax: 80,
            vmax: 498
        }
    );
    // The smallest acceleration the axis represents is four times coarser.
    let by64 = Bench::new(config()).driver.rate_floor(0).accel;
    assert!((bench.driver.rate_floor(0).accel - 4.0 * by64).abs() < 1e-9);
}

/// 8.3 `$15`: the table has "Bit 5: StopNoRef", "Bit 6: NullPositive"; the prose
/// "StopNoRef(P6, Bit 6)". The driver always sets StopNoRef; the byte puts it where the
/// configured reading has it, and NullPositive in the other bit.
#[test]
fn stop_no_ref_goes_where_the_reading_puts_it() {
    let mut table = Bench::new(with(AmaxDivisor::By64, OptionsLayout::Table));
    assert_eq!(p6_of_motor_0(&table.online()) & 0x60, 0x20);
    let prose = Bench::new(with(AmaxDivisor::By64, OptionsLayout::Prose)).online();
    assert_eq!(p6_of_motor_0(&prose) & 0x60, 0x40);
    // With NullPositive ("reference.active = high") both bits are set in either reading.
    let mut high = with(AmaxDivisor::By64, OptionsLayout::Prose);
    if let Some(Some(c)) = high.channels.get_mut(0) {
        c.options = c.options | MotorOptions::NULL_POSITIVE;
    }
    let mut prose_high = Bench::new(high);
    assert_eq!(p6_of_motor_0(&prose_high.online()) & 0x60, 0x60);
    // FastRef (bit 1), the driver's default, stays where it is.
    assert_eq!(p6_of_motor_0(&prose) & 0x02, 0x02);
}
