//! The reference search of manual 8.4 ($22) and 7.1, for one motor.
//!
//! "First the motor is stopped. The motor optionally drives fast (vrefmax), searching for
//! the position of the switch. When the switch is found, the motor is driven back to the
//! point, where the switch becomes inactive. Then it is slowly driven with vmin towards the
//! switch to find the exact position. If the switch cannot be found again at slow speed
//! where it had been found before, or if no switch is seen during 125% of the drive
//! limit-range, the whole procedure repeats by first stopping again. After the reference
//! point has been identified … the position is set to null respectively to null-offset and
//! the motor resumes its previous operation".
//!
//! The manual numbers the search actions 20–29 without naming them; we report:
//! 20 stopping, 21 seeking the switch (vrefmax with FastRef, else vmin), 22 backing off
//! (vstart) until the switch releases, 23 slow approach (vmin, divider 3), 24 crossing the
//! switch for its far edge (NullCenter), 25 driving to the new zero point (when $16 asks to
//! stop after the search); 30 the mechanical reference (MechRef: 5/4 · poslimit towards the
//! zero point, against the end stop).
//!
//! Our choices where the manual is silent: the fast search stops abruptly on the switch; the
//! zero point lies `nulloffset` beyond the switch edge in the search direction ("the
//! reference search will drive further into the null point and the null point is set
//! there"); the slow approach gives up (and repeats) after the back-off distance plus a
//! quarter plus four full steps; "stop after reference search" drives to the new zero.

use tmcpack::convert::StepClock;
use tmcpack::{Action, MotorOptions, MotorType, ReferenceFlags};

use super::params::MotorParams;

/// What a search needs of its motor (implemented by the motor module, so that this module
/// does not depend on it): its parameters, the switch, and the motions a search makes. The
/// tick's context (clock divider) is the implementor's.
pub(crate) trait SearchDrive {
    /// The motor's parameters.
    fn params(&self) -> &MotorParams;
    /// The pack's clock divider this tick.
    fn clkdiv(&self) -> u8;
    /// The position counter.
    fn position(&self) -> i64;
    /// The reference switch, de-bounced.
    fn switch_active(&self) -> bool;
    /// The motor stands still.
    fn at_rest(&self) -> bool;
    /// The velocity divider in use.
    fn current_div(&self) -> u8;
    /// One tick heading for `velocity` (units of `div`); the microsteps moved.
    fn drive(&mut self, velocity: i64, div: u8) -> i64;
    /// Stops at once.
    fn halt_now(&mut self);
    /// One ramp tick to `target` at most `vmax`; `true` on arrival.
    fn ramp_step(&mut self, target: i64, vmax: u16) -> bool;
    /// Counter value `zero` becomes 0.
    fn rezero(&mut self, zero: i64);
}

/// What the motor does after one tick of its search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Still searching, in this state.
    Searching(RefSearch),
    /// Stopped at the new zero point ("stop after reference search").
    Inactive,
    /// Found: the previous operation resumes.
    Resume(Resume),
}

/// What the motor does after the search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Resume {
    /// Drive to this (internal) position: the target of an interrupted ramp, or where the
    /// search started.
    Ramp(i64),
    Rotation(i16),
    Pi(i64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Phase {
    Stop,
    Seek,
    Backoff,
    Approach,
    Through { edge: i64 },
    Final,
    Mech { target: i64 },
}

/// A running reference search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RefSearch {
    pub phase: Phase,
    pub resume: Resume,
    /// Microsteps driven in the current phase.
    travelled: i64,
    /// Microsteps the back-off took.
    backoff: i64,
}

impl RefSearch {
    pub fn new(resume: Resume) -> Self {
        Self {
            phase: Phase::Stop,
            resume,
            travelled: 0,
            backoff: 0,
        }
    }

    pub fn action(&self) -> Action {
        match self.phase {
            Phase::Stop => Action::ReferenceSearch(0),
            Phase::Seek => Action::ReferenceSearch(1),
            Phase::Backoff => Action::ReferenceSearch(2),
            Phase::Approach => Action::ReferenceSearch(3),
            Phase::Through { .. } => Action::ReferenceSearch(4),
            Phase::Final => Action::ReferenceSearch(5),
            Phase::Mech { .. } => Action::MechanicalReference,
        }
    }

    fn enter(&mut self, phase: Phase) {
        self.phase = phase;
        self.travelled = 0;
    }
}

/// vmin, or the fastest vmin when 0 ($13: "vmin <= 250Hz / fminsteps").
pub(crate) fn effective_vmin(p: &MotorParams, clkdiv: u8) -> i64 {
    if p.vmin > 0 {
        return i64::from(p.vmin);
    }
    let f1 = StepClock::new(clkdiv, 3)
        .map(StepClock::hz_per_unit)
        .unwrap_or(1.0);
    ((250.0 / f1).floor() as i64).clamp(1, 511)
}

/// 125 % of the drive range (0: no limit).
fn range_limit(p: &MotorParams) -> i64 {
    i64::from(p.poslimit) * 5 / 4
}

/// One tick of the search.
pub(crate) fn tick(m: &mut impl SearchDrive, mut r: RefSearch) -> Outcome {
    let p = *m.params();
    let toward = p.toward_zero();
    let vmin = effective_vmin(&p, m.clkdiv());
    let limit = range_limit(&p);
    let over = |t: i64| limit > 0 && t > limit;
    match r.phase {
        Phase::Stop => {
            let div = m.current_div();
            m.drive(0, div);
            if m.at_rest() {
                if p.options.contains(MotorOptions::MECH_REF) {
                    r.enter(Phase::Mech {
                        target: m.position() + toward * limit.max(1),
                    });
                } else if m.switch_active() {
                    r.enter(Phase::Backoff);
                } else {
                    r.enter(Phase::Seek);
                }
            }
        }
        Phase::Seek => {
            let (v, div) = if p.options.contains(MotorOptions::FAST_REF) {
                (i64::from(p.vrefmax), p.div)
            } else {
                (vmin, 3)
            };
            r.travelled += m.drive(toward * v, div).abs();
            if m.switch_active() {
                m.halt_now();
                r.enter(Phase::Backoff);
            } else if over(r.travelled) {
                r.enter(Phase::Stop);
            }
        }
        Phase::Backoff => {
            r.travelled += m.drive(-toward * i64::from(p.vstart), p.div).abs();
            if !m.switch_active() {
                m.halt_now();
                r.backoff = r.travelled;
                r.enter(Phase::Approach);
            } else if over(r.travelled) {
                r.enter(Phase::Stop);
            }
        }
        Phase::Approach => {
            r.travelled += m.drive(toward * vmin, 3).abs();
            if m.switch_active() {
                m.halt_now();
                if p.motor_type.contains(MotorType::NULL_CENTER) {
                    let edge = m.position();
                    r.enter(Phase::Through { edge });
                } else {
                    let at = m.position();
                    if let Some(done) = finish(m, &mut r, at) {
                        return done;
                    }
                }
            } else if r.travelled > r.backoff + r.backoff / 4 + 64 {
                r.enter(Phase::Stop);
            }
        }
        Phase::Through { edge } => {
            r.travelled += m.drive(toward * vmin, 3).abs();
            if !m.switch_active() {
                m.halt_now();
                let at = edge + (m.position() - edge) / 2;
                if let Some(done) = finish(m, &mut r, at) {
                    return done;
                }
            } else if over(r.travelled) {
                r.enter(Phase::Stop);
            }
        }
        Phase::Final => {
            if m.ramp_step(0, p.vmax) {
                return Outcome::Inactive;
            }
        }
        Phase::Mech { target } => {
            let vmax = if p.options.contains(MotorOptions::FAST_REF) {
                p.vrefmax
            } else {
                p.vmax
            };
            if m.ramp_step(target, vmax) {
                let at = m.position();
                if let Some(done) = finish(m, &mut r, at) {
                    return done;
                }
            }
        }
    }
    Outcome::Searching(r)
}

/// The zero point is found at counter value `at`: set the coordinates, then stop (the
/// search goes on to its final phase: `None`) or resume.
fn finish(m: &mut impl SearchDrive, r: &mut RefSearch, at: i64) -> Option<Outcome> {
    let p = *m.params();
    let zero = at + p.toward_zero() * i64::from(p.nulloffset);
    m.rezero(zero);
    if p.ref_flags.contains(ReferenceFlags::STOP_AFTER_SEARCH) {
        r.enter(Phase::Final);
        return None;
    }
    Some(Outcome::Resume(r.resume))
}
