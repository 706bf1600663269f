//! The stepper section of the firmware (ports 0x10, 0x40–0x44) and the rotor it moves.
//!
//! Step timing: while the current position differs from the target, the firmware makes one
//! full step towards the target every step delay. A move that starts from rest makes its
//! first step one step delay after the command (the coils hold the present step for a full
//! delay first), so no two steps, and no command and the first step, are ever closer than
//! the step delay in force. A step delay of 0 is taken as one tick of the firmware's 0.1 ms
//! timer (the datasheet does not say).

use core::time::Duration;

use spimotor::{Coils, StepDelay, port};

/// The coils a power-on board drives: a zero-initialised setting, 0x00 = one coil (the
/// datasheet gives no default).
pub const POWER_ON_COILS: Coils = Coils::One;

/// Firmware registers of the stepper section and the true rotor position.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Stepper {
    /// Port 0x10.
    pub intensity: u8,
    /// Port 0x43.
    pub delay: StepDelay,
    /// Port 0x44.
    pub coils: Coils,
    /// Port 0x40: the firmware's position counter.
    pub current: i32,
    /// Port 0x41.
    pub target: i32,
    /// Time of the last step, or of the start of the move before its first step.
    origin: Duration,
    /// When the next step is due, while moving.
    next_step_at: Duration,
    /// When the last step was made.
    pub last_step_at: Option<Duration>,
    /// True rotor position: net full steps made since the simulation started. Writing the
    /// current position (0x40) changes the counter, not this.
    pub rotor: i64,
}

impl Stepper {
    /// Registers after power-on (RAM cleared); the rotor stays where it is.
    pub const fn power_on(rotor: i64) -> Self {
        Self {
            intensity: port::DEFAULT_STEPPER_INTENSITY,
            delay: StepDelay::DEFAULT,
            coils: POWER_ON_COILS,
            current: 0,
            target: 0,
            origin: Duration::ZERO,
            next_step_at: Duration::ZERO,
            last_step_at: None,
            rotor,
        }
    }

    /// Time between two steps under the present step delay.
    pub fn interval(&self) -> Duration {
        self.delay.duration().max(StepDelay::UNIT)
    }

    /// Whether the firmware is stepping (current position differs from the target).
    pub const fn is_moving(&self) -> bool {
        self.current != self.target
    }

    /// When the next step is due, if moving.
    pub fn next_step_at(&self) -> Option<Duration> {
        self.is_moving().then_some(self.next_step_at)
    }

    /// Makes every step due at or before `now`.
    pub fn advance(&mut self, now: Duration) {
        if !self.is_moving() || self.next_step_at > now {
            return;
        }
        let interval = self.interval();
        let interval_ns = interval.as_nanos().max(1);
        let gap = i64::from(self.target) - i64::from(self.current);
        let remaining = u128::from(gap.unsigned_abs());
        let due = (now - self.next_step_at).as_nanos() / interval_ns + 1;
        let steps = remaining.min(due);
        // `steps` ≤ |gap| < 2^32 and interval ≤ 25.5 ms: every product fits a u64.
        let steps_i64 = i64::try_from(steps).unwrap_or(0);
        let last = self.next_step_at
            + Duration::from_nanos(
                u64::try_from(interval_ns * steps.saturating_sub(1)).unwrap_or(u64::MAX),
            );
        let moved = gap.signum() * steps_i64;
        self.current = i32::try_from(i64::from(self.current) + moved).unwrap_or(self.target);
        self.rotor = self.rotor.saturating_add(moved);
        self.origin = last;
        self.last_step_at = Some(last);
        self.next_step_at = last + interval;
    }

    /// Port 0x40 at `now` (already advanced to `now`).
    pub fn set_current(&mut self, now: Duration, position: i32) {
        let was_idle = !self.is_moving();
        self.current = position;
        self.started(now, was_idle);
    }

    /// Port 0x41 at `now`.
    pub fn set_target(&mut self, now: Duration, position: i32) {
        let was_idle = !self.is_moving();
        self.target = position;
        self.started(now, was_idle);
    }

    /// Port 0x42 at `now`: a target relative to the current position (wrapping like the
    /// firmware's 32-bit arithmetic).
    pub fn set_relative(&mut self, now: Duration, offset: i32) {
        self.set_target(now, self.current.wrapping_add(offset));
    }

    /// Port 0x43 at `now`: the next step comes one new delay after the last one, but not
    /// before `now`.
    pub fn set_delay(&mut self, now: Duration, delay: StepDelay) {
        self.delay = delay;
        if self.is_moving() {
            self.next_step_at = (self.origin + self.interval()).max(now);
        }
    }

    fn started(&mut self, now: Duration, was_idle: bool) {
        if was_idle && self.is_moving() {
            self.origin = now;
            self.next_step_at = now + self.interval();
        }
    }

    /// Step rate while moving, full steps per second (signed), else 0.
    pub fn velocity(&self) -> f64 {
        if self.is_moving() {
            let sign = if self.target > self.current {
                1.0
            } else {
                -1.0
            };
            sign / self.interval().as_secs_f64()
        } else {
            0.0
        }
    }

    /// Drive of coils A and B (+1, 0, −1) at the rotor's present step: wave drive A+, B+,
    /// A−, B− with one coil; A+B+, A−B+, A−B−, A+B− with two. All zero at intensity 0.
    pub fn coil_drive(&self) -> [i8; 2] {
        if self.intensity == 0 {
            return [0, 0];
        }
        let phase = self.rotor.rem_euclid(4);
        match (self.coils, phase) {
            (Coils::One, 0) => [1, 0],
            (Coils::One, 1) => [0, 1],
            (Coils::One, 2) => [-1, 0],
            (Coils::One, _) => [0, -1],
            (Coils::Two, 0) => [1, 1],
            (Coils::Two, 1) => [-1, 1],
            (Coils::Two, 2) => [-1, -1],
            (Coils::Two, _) => [1, -1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn steps_come_one_delay_apart_and_stop_at_the_target() {
        let mut s = Stepper::power_on(0);
        s.set_delay(Duration::ZERO, StepDelay::from_tenths_ms(10));
        s.set_target(Duration::ZERO, 3);
        s.advance(MS - Duration::from_nanos(1));
        assert_eq!(s.current, 0);
        s.advance(MS);
        assert_eq!((s.current, s.last_step_at), (1, Some(MS)));
        s.advance(100 * MS);
        assert_eq!((s.current, s.rotor, s.last_step_at), (3, 3, Some(3 * MS)));
        assert!(!s.is_moving());
    }

    #[test]
    fn one_big_advance_equals_many_small_ones() {
        let mut a = Stepper::power_on(0);
        a.set_delay(Duration::ZERO, StepDelay::from_tenths_ms(0));
        a.set_target(Duration::ZERO, -1000);
        let mut b = a;
        a.advance(Duration::from_millis(70));
        for us in 0..=70_000 {
            b.advance(Duration::from_micros(us));
        }
        assert_eq!(a, b);
        assert_eq!(a.current, -700);
    }

    #[test]
    fn a_long_move_is_computed_in_closed_form() {
        let mut s = Stepper::power_on(0);
        s.set_target(Duration::ZERO, i32::MAX);
        s.advance(Duration::from_secs(1_000_000_000));
        assert_eq!(s.current, i32::MAX);
        assert_eq!(s.rotor, i64::from(i32::MAX));
    }

    #[test]
    fn coil_patterns() {
        let mut s = Stepper::power_on(0);
        let mut one = Vec::new();
        for rotor in 0..4 {
            s.rotor = rotor;
            one.push(s.coil_drive());
        }
        assert_eq!(one, [[1, 0], [0, 1], [-1, 0], [0, -1]]);
        s.coils = Coils::Two;
        s.rotor = -1;
        assert_eq!(s.coil_drive(), [1, -1]);
        s.intensity = 0;
        assert_eq!(s.coil_drive(), [0, 0]);
    }
}
