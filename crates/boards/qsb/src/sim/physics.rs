//! The signals the board measures: the encoder (on the -M's stepper shaft, or moving by
//! itself on the -S/-D), its index pulse, the analog input, and their effect on the counter.

use core::time::Duration;

use qsb::{CountMode, EncoderMode, effective_rate};

use super::QsbSim;
use super::counter::Events;

/// Longest physics step while something moves: short enough that the encoder motion is
/// monotonic within a step and index pulses are seen in order.
const MAX_STEP: Duration = Duration::from_millis(1);

impl QsbSim {
    /// Encoder position at model time `t`, quadrature cycles.
    pub(super) fn encoder_at(&self, t: Duration) -> f64 {
        let base = if self.config.variant == super::Variant::M {
            self.motor.position * self.config.cycles_per_step
        } else {
            self.config.motion.position(t.as_secs_f64())
        };
        base + self.encoder_offset
    }

    fn moves_by_itself(&self) -> bool {
        if self.config.variant == super::Variant::M {
            self.motor.moving()
        } else {
            let m = self.config.motion;
            m.velocity != 0.0 || (m.amplitude != 0.0 && m.frequency_hz != 0.0)
        }
    }

    /// Move rate and acceleration in force, steps/s and steps/s² (16-step increments).
    pub(super) fn motor_limits_internal(&self) -> (f64, f64) {
        let rate = effective_rate(self.regs.step_rate).max(32);
        let accel = effective_rate(self.regs.accel).max(64);
        (f64::from(rate), f64::from(accel))
    }

    /// Advances motor and encoder from the model time to `to`.
    pub(super) fn advance_physics(&mut self, to: Duration) {
        while self.t < to {
            let step = if self.moves_by_itself() {
                let f = self.config.motion.frequency_hz.abs();
                let limit = if self.config.variant != super::Variant::M && f > 0.0 {
                    MAX_STEP.min(Duration::try_from_secs_f64(1.0 / (16.0 * f)).unwrap_or(MAX_STEP))
                } else {
                    MAX_STEP
                };
                limit.max(Duration::from_micros(1))
            } else {
                to - self.t
            };
            let next = self.t.saturating_add(step).min(to);
            let p0 = self.encoder_at(self.t);
            if self.config.variant == super::Variant::M {
                let (vmax, accel) = self.motor_limits_internal();
                let steps_before = self.motor.position;
                self.motor
                    .advance((next - self.t).as_secs_f64(), vmax, accel);
                if !self.drive_energised() {
                    // A disabled driver ignores the pulses: the shaft stays.
                    self.encoder_offset -=
                        (self.motor.position - steps_before) * self.config.cycles_per_step;
                }
                if self.motor.velocity != 0.0 && self.dio.drive.is_some() {
                    self.set_direction(self.motor.velocity > 0.0);
                }
            }
            self.t = next;
            let p1 = self.encoder_at(next);
            self.encoder_moved(p0, p1);
        }
    }

    fn set_direction(&mut self, positive: bool) {
        if self.dio.drive != Some(positive) {
            let before = self.dio.pins();
            self.dio.drive = Some(positive);
            if self.dio.interrupt(before) {
                self.counter.capture_now();
            }
        }
    }

    /// Counts the quadrature edges and index pulses between encoder positions `p0` and
    /// `p1` (a monotonic motion).
    pub(super) fn encoder_moved(&mut self, p0: f64, p1: f64) {
        if p0 == p1 || self.regs.mode.encoder != EncoderMode::Quadrature {
            return;
        }
        let up = p1 > p0;
        let cpr = f64::from(self.config.cycles_per_rev.max(1));
        // The index is high for the first quarter cycle of each revolution; it acts on its
        // leading edge in the direction of motion (trailing edge when inverted).
        let leading = if up { 0.0 } else { 0.25 };
        let edge = if self.counter.mdr1.invert_index {
            0.25 - leading
        } else {
            leading
        };
        let mut from = p0;
        let mut k = if up {
            ((p0 - edge) / cpr).floor() + 1.0
        } else {
            ((p0 - edge) / cpr).ceil() - 1.0
        };
        let mut events = Events::default();
        for _ in 0..4096 {
            let x = k * cpr + edge;
            let crossed = if up { x <= p1 } else { x >= p1 };
            if !crossed {
                break;
            }
            events.merge(self.count_between(from, x));
            events.merge(self.counter.index());
            from = x;
            k += if up { 1.0 } else { -1.0 };
        }
        events.merge(self.count_between(from, p1));
        if events.triggers(self.counter.mdr1) {
            self.trigger_pulse();
        }
    }

    fn count_between(&mut self, a: f64, b: f64) -> Events {
        let mdr0 = self.counter.mdr0;
        let m = f64::from(mdr0.counts_per_cycle());
        let n = ((m * b).floor() - (m * a).floor()).abs();
        if !n.is_finite() || n < 1.0 {
            return Events::default();
        }
        let forward = b > a;
        let quadrature = mdr0.count != CountMode::NonQuadrature;
        let up = forward != (quadrature && self.counter.mdr1.count_down);
        self.counter.count(n.min(u64::MAX as f64) as u64, up)
    }

    /// A trigger event: pulse digital I/O bit 0 for INTERVAL RATE (DIG I/O CONFIG B12):
    /// bit 0 toggles and toggles back when the pulse ends ("The output pulse polarity
    /// depends on the initial output state of digital I/O bit 0"); INTERVAL RATE 0 "only
    /// toggles". The command list does not say what an event during a pulse does: here it
    /// lengthens the pulse (the line stays at its active level), so that the line always
    /// ends at its resting level.
    fn trigger_pulse(&mut self) {
        if !self.dio.config.trigger_pulse || self.config.variant.digital_io_bits() == 0 {
            return;
        }
        self.trigger_pulses += 1;
        let ticks = u32::from(self.regs.interval.0);
        if self.pulse_end.is_none() || ticks == 0 {
            self.toggle_bit0();
        }
        self.pulse_end = (ticks > 0).then(|| self.t.saturating_add(qsb::TICK * ticks));
    }

    pub(super) fn toggle_bit0(&mut self) {
        let before = self.dio.pins();
        self.dio.latch ^= 1;
        if self.dio.interrupt(before) {
            self.counter.capture_now();
        }
    }

    /// The PWM encoder's reading: the position within a revolution at 10 or 12 bits.
    pub(super) fn pwm_value(&self) -> u32 {
        let cpr = f64::from(self.config.cycles_per_rev.max(1));
        let full = if self.config.pwm_12bit {
            4096.0
        } else {
            1024.0
        };
        let turn = (self.encoder_at(self.t) / cpr).rem_euclid(1.0);
        ((turn * full) as u32).min(full as u32 - 1)
    }

    /// A 10-bit conversion of the analog input.
    pub(super) fn analog_value(&mut self) -> u16 {
        let a = self.config.analog;
        let t = self.t.as_secs_f64();
        let noise = self.rng.range_f64(-a.noise_volts, a.noise_volts);
        let volts = a.offset_volts
            + a.amplitude_volts * (core::f64::consts::TAU * a.frequency_hz * t).sin()
            + noise;
        let code = (volts / 5.0 * 1023.0).round().clamp(0.0, 1023.0);
        code as u16
    }
}

#[cfg(test)]
mod tests {
    use core::time::Duration;

    use qsb::{CountMode, CycleMode, IndexMode, Mdr0};

    use super::super::{EncoderMotion, QsbSim, QsbSimConfig, Variant};

    /// A still -D (one index per 500 cycles, at multiples of 500) counting as `mdr0` with
    /// DTR `dtr`, CNTR at `cntr`.
    fn sim(mdr0: Mdr0, dtr: u32, cntr: u32) -> QsbSim {
        let mut sim = QsbSim::new(QsbSimConfig {
            variant: Variant::D,
            motion: EncoderMotion {
                velocity: 0.0,
                amplitude: 0.0,
                frequency_hz: 0.0,
            },
            ..QsbSimConfig::default()
        });
        // Powered up first (the power-up loads the factory MDR0 0x4F and DTR 0x1F3).
        sim.nudge_encoder(Duration::ZERO, 0.0);
        sim.counter.mdr0 = mdr0;
        sim.counter.dtr = dtr;
        sim.counter.cntr = cntr;
        sim
    }

    fn modulo(index: IndexMode) -> Mdr0 {
        Mdr0 {
            count: CountMode::X1,
            cycle: CycleMode::ModuloN,
            index,
            synchronous_index: true,
            filter_div2: false,
        }
    }

    #[test]
    fn modulo_n_wraps_both_ways_one_count_per_cycle_in_x1() {
        // "modulo-n count mode. The input clock is divided by a factor of (DTR + 1)".
        let mut s = sim(modulo(IndexMode::Disabled), 499, 0);
        s.nudge_encoder(Duration::ZERO, 1234.5);
        assert_eq!(s.counter.cntr, 234);
        s.nudge_encoder(Duration::ZERO, -240.0);
        assert_eq!(s.counter.cntr, 494, "backwards through 0 to DTR");
        assert!(s.counter.status().borrow);
    }

    #[test]
    fn an_index_that_resets_cntr_synchronises_the_modulo_count() {
        // Misaligned by 100 counts: without the index the count stays 100 off.
        let mut plain = sim(modulo(IndexMode::Disabled), 499, 100);
        plain.nudge_encoder(Duration::ZERO, 1234.5);
        assert_eq!(plain.counter.cntr, 334);
        // "configure index as the "reset CNTR" input (clears CNTR to 0)": from the first
        // index (at 500 cycles) on, the count is the position within the revolution.
        let mut synced = sim(modulo(IndexMode::ResetCntr), 499, 100);
        synced.nudge_encoder(Duration::ZERO, 1234.5);
        assert_eq!(synced.counter.cntr, 234);
        assert!(synced.counter.status().index);
        // "load CNTR" (transfers DTR to CNTR): the index is count 499, the next cycle 0.
        let mut loaded = sim(modulo(IndexMode::LoadCntr), 499, 100);
        loaded.nudge_encoder(Duration::ZERO, 1234.5);
        assert_eq!(loaded.counter.cntr, 233);
    }

    #[test]
    fn x2_and_step_direction_count_their_edges_and_range_limit_clamps() {
        let x2 = Mdr0 {
            count: CountMode::X2,
            cycle: CycleMode::RangeLimit,
            ..Mdr0::default()
        };
        // "two counts per quadrature cycle"; "counting freezes at these limits but
        // resumes when direction reverses".
        let mut s = sim(x2, 300, 0);
        s.nudge_encoder(Duration::ZERO, 100.25);
        assert_eq!(s.counter.cntr, 200);
        s.nudge_encoder(Duration::ZERO, 100.0);
        assert_eq!(s.counter.cntr, 300, "frozen at DTR");
        s.nudge_encoder(Duration::ZERO, -10.0);
        assert_eq!(s.counter.cntr, 280, "resumes when the direction reverses");
        s.nudge_encoder(Duration::ZERO, -1000.0);
        assert_eq!(s.counter.cntr, 0, "frozen at zero");
        // "non-quadrature count mode. (A = clock, B = direction)": one count per clock.
        let steps = Mdr0 {
            count: CountMode::NonQuadrature,
            ..Mdr0::default()
        };
        let mut s = sim(steps, 0, 0);
        s.nudge_encoder(Duration::ZERO, 7.0);
        s.nudge_encoder(Duration::ZERO, -3.0);
        assert_eq!(s.counter.cntr, 4);
    }
}
