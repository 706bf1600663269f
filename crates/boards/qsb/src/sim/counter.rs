//! The LS7366R-style 32-bit quadrature counter behind registers 03–0A: CNTR, OTR, DTR,
//! CAPTURE, STR and the MDR0/MDR1 modes.
//!
//! Counts arrive in runs of one direction and are applied in closed form, so a long jump
//! in time costs the same as a short one. Within a run the flags come out as if the counts
//! were applied one by one: carry/borrow when the count wraps (free-running, single-cycle,
//! modulo-n) or reaches a limit (range-limit), compare when CNTR passes through DTR.

use qsb::{ClearTarget, CycleMode, IndexMode, LoadTarget, Mdr0, Mdr1, Str};

const WRAP: u64 = 1 << 32;

/// Counter events of one run, for the MDR1 triggers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Events {
    pub carry: bool,
    pub borrow: bool,
    pub compare: bool,
    pub index: bool,
}

impl Events {
    pub(crate) fn merge(&mut self, other: Self) {
        self.carry |= other.carry;
        self.borrow |= other.borrow;
        self.compare |= other.compare;
        self.index |= other.index;
    }

    /// Whether any event is enabled as a trigger in `mdr1`.
    pub(crate) fn triggers(&self, mdr1: Mdr1) -> bool {
        (self.index && mdr1.trigger_on_index)
            || (self.compare && mdr1.trigger_on_match)
            || (self.borrow && mdr1.trigger_on_underflow)
            || (self.carry && mdr1.trigger_on_overflow)
    }
}

/// The counter registers.
#[derive(Debug, Clone)]
pub(crate) struct Counter {
    pub cntr: u32,
    pub otr: u32,
    pub dtr: u32,
    pub capture: u32,
    pub mdr0: Mdr0,
    pub mdr1: Mdr1,
    /// STR latches; `count_enabled` is derived in [`Counter::status`].
    latches: Str,
    /// Single-cycle mode stopped at a carry or borrow.
    stopped: bool,
    /// Captures made (an input edge, an index with MDR1 B4), for observation.
    pub captures: u64,
}

impl Counter {
    pub(crate) fn new(mdr0: Mdr0, mdr1: Mdr1, dtr: u32, status: Str) -> Self {
        Self {
            cntr: 0,
            otr: 0,
            dtr,
            capture: 0,
            mdr0,
            mdr1,
            latches: status,
            stopped: false,
            captures: 0,
        }
    }

    /// Whether counts are applied (STR CEN).
    pub(crate) fn enabled(&self) -> bool {
        !self.mdr1.disable_counting && !self.stopped
    }

    /// The STR register.
    pub(crate) fn status(&self) -> Str {
        Str {
            count_enabled: self.enabled(),
            ..self.latches
        }
    }

    /// Applies `n` counts in one direction (`up` after the MDR1 count-down inversion).
    pub(crate) fn count(&mut self, n: u64, up: bool) -> Events {
        let mut ev = Events::default();
        if n == 0 || !self.enabled() {
            return ev;
        }
        self.latches.up = up;
        let c = u64::from(self.cntr);
        let dtr = u64::from(self.dtr);
        match self.mdr0.cycle {
            CycleMode::FreeRunning | CycleMode::SingleCycle => {
                // Counts until the wrap, and until CNTR first equals DTR.
                let to_wrap = if up { WRAP - c } else { c + 1 };
                let to_dtr = match if up {
                    (dtr + WRAP - c) % WRAP
                } else {
                    (c + WRAP - dtr) % WRAP
                } {
                    0 => WRAP,
                    d => d,
                };
                let single = self.mdr0.cycle == CycleMode::SingleCycle;
                let steps = if single { n.min(to_wrap) } else { n };
                if n >= to_wrap {
                    if up {
                        ev.carry = true;
                    } else {
                        ev.borrow = true;
                    }
                    self.stopped = single;
                }
                ev.compare = to_dtr <= steps;
                let steps = steps % WRAP;
                self.cntr = if up {
                    ((c + steps) % WRAP) as u32
                } else {
                    ((c + WRAP - steps) % WRAP) as u32
                };
            }
            CycleMode::RangeLimit => {
                if up {
                    if c < dtr {
                        let new = (c + n).min(dtr);
                        ev.carry = new == dtr;
                        ev.compare = new == dtr;
                        self.cntr = new as u32;
                    }
                } else if c > 0 {
                    let new = c.saturating_sub(n);
                    ev.borrow = new == 0;
                    ev.compare = dtr >= new && dtr < c;
                    self.cntr = new as u32;
                }
            }
            CycleMode::ModuloN => {
                let modulus = dtr + 1;
                let c = c % modulus;
                let to_dtr = match if up {
                    (dtr + modulus - c) % modulus
                } else {
                    (c + modulus - dtr) % modulus
                } {
                    0 => modulus,
                    d => d,
                };
                ev.compare = to_dtr <= n;
                if up {
                    ev.carry = c + n > dtr;
                    self.cntr = ((c + n) % modulus) as u32;
                } else {
                    ev.borrow = n > c;
                    self.cntr = ((c + modulus - n % modulus) % modulus) as u32;
                }
            }
        }
        if ev.carry {
            self.latches.carry = true;
            self.latches.sign = false;
        }
        if ev.borrow {
            self.latches.borrow = true;
            self.latches.sign = true;
        }
        self.latches.compare |= ev.compare;
        ev
    }

    /// An index pulse: the MDR0 index function and the MDR1 capture-on-index.
    pub(crate) fn index(&mut self) -> Events {
        let function = self.mdr0.index != IndexMode::Disabled;
        if !function && !self.mdr1.trigger_on_index {
            return Events::default();
        }
        self.latches.index = true;
        if self.mdr1.trigger_on_index {
            self.capture = self.cntr;
            self.captures += 1;
        }
        match self.mdr0.index {
            IndexMode::Disabled => {}
            IndexMode::LoadCntr => self.load(LoadTarget::DtrToCntr),
            IndexMode::ResetCntr => self.clear(ClearTarget::Cntr),
            IndexMode::LoadOtr => self.load(LoadTarget::CntrToOtr),
        }
        Events {
            index: true,
            ..Events::default()
        }
    }

    /// CLEAR REG.
    pub(crate) fn clear(&mut self, target: ClearTarget) {
        match target {
            ClearTarget::Mdr0 => self.mdr0 = Mdr0::from_data(0).unwrap_or_default(),
            ClearTarget::Mdr1 => self.mdr1 = Mdr1::default(),
            ClearTarget::Cntr => {
                self.cntr = 0;
                self.stopped = false;
            }
            ClearTarget::Str => {
                self.latches = Str {
                    up: self.latches.up,
                    ..Str::default()
                }
            }
        }
    }

    /// LOAD REG.
    pub(crate) fn load(&mut self, target: LoadTarget) {
        match target {
            LoadTarget::DtrToCntr => {
                self.cntr = self.dtr;
                self.stopped = false;
            }
            LoadTarget::CntrToOtr => self.otr = self.cntr,
        }
    }

    /// Loads CNTR into CAPTURE (a digital input interrupt).
    pub(crate) fn capture_now(&mut self) {
        self.capture = self.cntr;
        self.captures += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsb::CountMode;

    fn counter(cycle: CycleMode, dtr: u32) -> Counter {
        let mdr0 = Mdr0 {
            count: CountMode::X4,
            cycle,
            ..Mdr0::default()
        };
        Counter::new(mdr0, Mdr1::default(), dtr, Str::default())
    }

    /// The closed form agrees with counting one by one.
    fn one_by_one(mut c: Counter, n: u64, up: bool) -> (Counter, Events) {
        let mut ev = Events::default();
        for _ in 0..n {
            ev.merge(c.count(1, up));
        }
        (c, ev)
    }

    #[test]
    fn closed_form_matches_single_counts() {
        let cycles = [
            CycleMode::FreeRunning,
            CycleMode::SingleCycle,
            CycleMode::RangeLimit,
            CycleMode::ModuloN,
        ];
        let starts = [0u32, 1, 5, 9, 10, 11, u32::MAX - 3, u32::MAX];
        for cycle in cycles {
            for &start in &starts {
                for n in 0..25u64 {
                    for up in [true, false] {
                        let mut c = counter(cycle, 10);
                        c.cntr = if cycle == CycleMode::ModuloN {
                            start % 11
                        } else {
                            start
                        };
                        let (slow, slow_ev) = one_by_one(c.clone(), n, up);
                        let fast_ev = c.count(n, up);
                        let what = format!("{cycle:?} start {start} n {n} up {up}");
                        assert_eq!(c.cntr, slow.cntr, "{what}");
                        assert_eq!(c.status(), slow.status(), "{what}");
                        assert_eq!(fast_ev, slow_ev, "{what}");
                    }
                }
            }
        }
    }

    #[test]
    fn modes_behave_as_the_command_list_says() {
        // Free-running: wraps through zero with a borrow and sets the sign.
        let mut c = counter(CycleMode::FreeRunning, 0x1F3);
        assert!(c.count(1, false).borrow);
        assert_eq!(c.cntr as i32, -1);
        assert!(c.status().sign && c.status().borrow);
        // Single-cycle: disabled by the borrow, re-enabled by a reset.
        let mut c = counter(CycleMode::SingleCycle, 0x1F3);
        c.count(3, false);
        assert!(!c.status().count_enabled);
        let frozen = c.cntr;
        c.count(100, true);
        assert_eq!(c.cntr, frozen);
        c.clear(ClearTarget::Cntr);
        assert!(c.status().count_enabled);
        // Range-limit: freezes at DTR and zero, resumes when the direction reverses.
        let mut c = counter(CycleMode::RangeLimit, 100);
        c.count(250, true);
        assert_eq!(c.cntr, 100);
        c.count(30, false);
        assert_eq!(c.cntr, 70);
        c.count(500, false);
        assert_eq!(c.cntr, 0);
        // Modulo-n: divides by DTR + 1.
        let mut c = counter(CycleMode::ModuloN, 499);
        assert!(c.count(1234, true).carry);
        assert_eq!(c.cntr, 1234 % 500);
        // Index functions.
        let mut c = counter(CycleMode::FreeRunning, 7);
        c.mdr0.index = IndexMode::LoadCntr;
        c.mdr1.trigger_on_index = true;
        c.count(42, true);
        assert!(c.index().index);
        assert_eq!((c.cntr, c.capture), (7, 42));
        assert!(c.status().index);
    }
}
