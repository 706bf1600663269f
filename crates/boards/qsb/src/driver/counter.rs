//! The counter mode the driver writes (MDR0, and DTR where the mode needs it), and how
//! it reads count differences: across the 32-bit wrap of a free-running counter, or
//! modulo DTR + 1 in modulo-n mode.
//!
//! Counts are the counter's counts in the configured mode: `counts_per_unit` and
//! `counts_per_step` are counted the way MDR0 B1 B0 says (a 500-cycle encoder is 2000
//! counts per revolution in x4, 500 in x1), so the driver never scales by the multiplier.

use ::qsb::{CountMode, CycleMode, IndexMode, Mdr0};

/// What the counter is set to in normal operation (`count_mode`, `count_range`,
/// `count_limit`, `index_action`, `index_sync`; docs/keys/qsb.md).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct CounterSetup {
    /// MDR0 B1 B0: x4 (default), x2, x1 quadrature, or non-quadrature (A = clock, B =
    /// direction).
    pub count: CountMode,
    /// MDR0 B3 B2: free-running (default), single-cycle, range-limit, modulo-n.
    pub cycle: CycleMode,
    /// DTR in range-limit (the upper limit) and modulo-n (the counter runs 0..=limit)
    /// modes, at most `i32::MAX` so that every count is a positive signed count.
    pub limit: u32,
    /// MDR0 B5 B4 in normal operation (a home search sets its own): disabled (default),
    /// reset CNTR or load CNTR from DTR (modulo-n only: the index re-synchronises the
    /// wrap).
    pub index: IndexMode,
    /// MDR0 B6: synchronous index (default in quadrature; "Asynchronous index mode is set
    /// in non-quadrature modes").
    pub synchronous_index: bool,
}

impl Default for CounterSetup {
    /// x4, free-running, index disabled, synchronous index (MDR0 0x43).
    fn default() -> Self {
        Self {
            count: CountMode::X4,
            cycle: CycleMode::FreeRunning,
            limit: 0,
            index: IndexMode::Disabled,
            synchronous_index: true,
        }
    }
}

impl CounterSetup {
    /// MDR0 in normal operation.
    pub fn mdr0(&self) -> Mdr0 {
        Mdr0 {
            count: self.count,
            cycle: self.cycle,
            index: self.index,
            synchronous_index: self.synchronous_index && self.count != CountMode::NonQuadrature,
            filter_div2: false,
        }
    }

    /// MDR0 during a home search: the normal mode with the index acting on CNTR as
    /// `index` says.
    pub(crate) fn homing_mdr0(&self, index: IndexMode) -> Mdr0 {
        Mdr0 {
            index,
            ..self.mdr0()
        }
    }

    /// DTR the mode needs (range-limit, modulo-n), written before MDR0.
    pub fn dtr(&self) -> Option<u32> {
        matches!(self.cycle, CycleMode::RangeLimit | CycleMode::ModuloN).then_some(self.limit)
    }

    /// How count differences are read.
    pub(crate) fn wrap(&self) -> Wrap {
        match self.cycle {
            CycleMode::ModuloN => Wrap::Modulo(u64::from(self.limit) + 1),
            _ => Wrap::Bits32,
        }
    }

    /// The mode as `motionctl list` shows it (`count_range`): "modulo-n 1999".
    pub fn range_text(&self) -> String {
        match self.cycle {
            CycleMode::FreeRunning => "free-running".to_owned(),
            CycleMode::SingleCycle => "single-cycle".to_owned(),
            CycleMode::RangeLimit => format!("range-limit 0..={}", self.limit),
            CycleMode::ModuloN => format!("modulo-n 0..={}", self.limit),
        }
    }

    /// `count_mode` as the config names it.
    pub fn count_text(&self) -> &'static str {
        match self.count {
            CountMode::NonQuadrature => "step-direction",
            CountMode::X1 => "x1",
            CountMode::X2 => "x2",
            CountMode::X4 => "x4",
        }
    }

    /// `index_action` as the config names it.
    pub fn index_text(&self) -> &'static str {
        match self.index {
            IndexMode::Disabled => "none",
            IndexMode::ResetCntr => "reset",
            IndexMode::LoadCntr => "load",
            IndexMode::LoadOtr => "load-otr",
        }
    }
}

/// How the difference of two streamed counts is read.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wrap {
    /// The 32-bit counter wraps through zero: the two's-complement difference.
    Bits32,
    /// Modulo-n: the counter runs 0..n-1; the difference is the shortest way round (a
    /// motion of less than half a cycle between two samples).
    Modulo(u64),
}

impl Wrap {
    /// Counts from `from` to `to`.
    pub(crate) fn diff(self, from: i32, to: i32) -> i64 {
        match self {
            Self::Bits32 => i64::from(to.wrapping_sub(from)),
            Self::Modulo(n) => {
                let n = i64::try_from(n.max(1)).unwrap_or(i64::MAX);
                let d = (i64::from(to) - i64::from(from)).rem_euclid(n);
                if d > n / 2 { d - n } else { d }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mdr0_follows_the_mode_and_step_direction_forces_an_asynchronous_index() {
        assert_eq!(CounterSetup::default().mdr0().data(), 0x43);
        let modulo = CounterSetup {
            count: CountMode::X1,
            cycle: CycleMode::ModuloN,
            limit: 499,
            index: IndexMode::ResetCntr,
            synchronous_index: true,
        };
        // B6 sync, B5 B4 = 10 reset, B3 B2 = 11 modulo-n, B1 B0 = 01 x1.
        assert_eq!(modulo.mdr0().data(), 0x6D);
        assert_eq!(modulo.dtr(), Some(499));
        assert_eq!(modulo.homing_mdr0(IndexMode::LoadCntr).data(), 0x5D);
        let steps = CounterSetup {
            count: CountMode::NonQuadrature,
            ..CounterSetup::default()
        };
        assert_eq!(steps.mdr0().data(), 0x00);
        assert_eq!(steps.dtr(), None);
        let range = CounterSetup {
            count: CountMode::X2,
            cycle: CycleMode::RangeLimit,
            limit: 1000,
            ..CounterSetup::default()
        };
        assert_eq!(range.mdr0().data(), 0x4A);
        assert_eq!(range.range_text(), "range-limit 0..=1000");
    }

    #[test]
    fn differences_wrap_at_32_bits_or_modulo_n() {
        assert_eq!(Wrap::Bits32.diff(i32::MAX, i32::MIN), 1);
        assert_eq!(Wrap::Bits32.diff(0, -5), -5);
        let m = Wrap::Modulo(500);
        assert_eq!(m.diff(498, 3), 5, "forward through the wrap");
        assert_eq!(m.diff(3, 498), -5, "backward through the wrap");
        assert_eq!(m.diff(100, 200), 100);
        assert_eq!(m.diff(0, 250), 250);
        assert_eq!(m.diff(0, 251), -249);
    }
}
