//! Typed values of the LS7366R-style counter registers: MDR0, MDR1, STR, CLEAR REG and
//! LOAD REG.

use crate::Error;

/// MDR0 B1 B0: count mode.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum CountMode {
    /// 00: non-quadrature (A = clock, B = direction).
    NonQuadrature,
    /// 01: one count per quadrature cycle.
    X1,
    /// 10: two counts per quadrature cycle.
    X2,
    /// 11: four counts per quadrature cycle.
    #[default]
    X4,
}

/// MDR0 B3 B2: count cycle.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum CycleMode {
    /// 00: free-running 32-bit counter.
    #[default]
    FreeRunning,
    /// 01: disabled by a carry or borrow, re-enabled by reset or load.
    SingleCycle,
    /// 10: counts between zero and DTR, freezing at the limits.
    RangeLimit,
    /// 11: counts modulo DTR + 1.
    ModuloN,
}

/// MDR0 B5 B4: what the index input does.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum IndexMode {
    /// 00: index disabled.
    #[default]
    Disabled,
    /// 01: index loads CNTR from DTR.
    LoadCntr,
    /// 10: index clears CNTR.
    ResetCntr,
    /// 11: index transfers CNTR to OTR.
    LoadOtr,
}

/// MDR0 register (03).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct Mdr0 {
    /// B1 B0.
    pub count: CountMode,
    /// B3 B2.
    pub cycle: CycleMode,
    /// B5 B4.
    pub index: IndexMode,
    /// B6: synchronous index (else asynchronous).
    pub synchronous_index: bool,
    /// B7: filter clock division factor 2 (else 1).
    pub filter_div2: bool,
}

impl Mdr0 {
    /// Decodes an MDR0 value (data range 00–FF).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > 0xFF {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            count: match data & 3 {
                0 => CountMode::NonQuadrature,
                1 => CountMode::X1,
                2 => CountMode::X2,
                _ => CountMode::X4,
            },
            cycle: match (data >> 2) & 3 {
                0 => CycleMode::FreeRunning,
                1 => CycleMode::SingleCycle,
                2 => CycleMode::RangeLimit,
                _ => CycleMode::ModuloN,
            },
            index: match (data >> 4) & 3 {
                0 => IndexMode::Disabled,
                1 => IndexMode::LoadCntr,
                2 => IndexMode::ResetCntr,
                _ => IndexMode::LoadOtr,
            },
            synchronous_index: data & 0x40 != 0,
            filter_div2: data & 0x80 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        let count = match self.count {
            CountMode::NonQuadrature => 0,
            CountMode::X1 => 1,
            CountMode::X2 => 2,
            CountMode::X4 => 3,
        };
        let cycle = match self.cycle {
            CycleMode::FreeRunning => 0,
            CycleMode::SingleCycle => 1,
            CycleMode::RangeLimit => 2,
            CycleMode::ModuloN => 3,
        };
        let index = match self.index {
            IndexMode::Disabled => 0,
            IndexMode::LoadCntr => 1,
            IndexMode::ResetCntr => 2,
            IndexMode::LoadOtr => 3,
        };
        count
            | cycle << 2
            | index << 4
            | (self.synchronous_index as u32) << 6
            | (self.filter_div2 as u32) << 7
    }

    /// Counts per quadrature cycle (non-quadrature mode counts one per A clock).
    pub const fn counts_per_cycle(self) -> u32 {
        match self.count {
            CountMode::NonQuadrature | CountMode::X1 => 1,
            CountMode::X2 => 2,
            CountMode::X4 => 4,
        }
    }
}

/// MDR1 register (04), appended to MDR0. B1 B0 are reserved and always 00.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct Mdr1 {
    /// B2: counting disabled.
    pub disable_counting: bool,
    /// B3: inverted index polarity.
    pub invert_index: bool,
    /// B4: trigger / capture on index.
    pub trigger_on_index: bool,
    /// B5: trigger on match (CNTR = DTR).
    pub trigger_on_match: bool,
    /// B6: trigger on underflow (borrow).
    pub trigger_on_underflow: bool,
    /// B7: trigger on overflow (carry).
    pub trigger_on_overflow: bool,
    /// B8: count-down mode (quadrature only): the count direction is inverted.
    pub count_down: bool,
}

impl Mdr1 {
    /// Largest value of the documented data range (00–1FF).
    pub const MAX: u32 = 0x1FF;

    /// Decodes an MDR1 value. Set reserved bits B1 B0 are `OutOfRange`.
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > Self::MAX || data & 3 != 0 {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            disable_counting: data & 0x004 != 0,
            invert_index: data & 0x008 != 0,
            trigger_on_index: data & 0x010 != 0,
            trigger_on_match: data & 0x020 != 0,
            trigger_on_underflow: data & 0x040 != 0,
            trigger_on_overflow: data & 0x080 != 0,
            count_down: data & 0x100 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.disable_counting as u32) << 2
            | (self.invert_index as u32) << 3
            | (self.trigger_on_index as u32) << 4
            | (self.trigger_on_match as u32) << 5
            | (self.trigger_on_underflow as u32) << 6
            | (self.trigger_on_overflow as u32) << 7
            | (self.count_down as u32) << 8
    }
}

/// STR counter status register (06).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Str {
    /// B7 CY: carry (CNTR overflow) latch.
    pub carry: bool,
    /// B6 BW: borrow (CNTR underflow) latch.
    pub borrow: bool,
    /// B5 CMP: compare (CNTR = DTR) latch.
    pub compare: bool,
    /// B4 IDX: index latch.
    pub index: bool,
    /// B3 CEN: counting enabled.
    pub count_enabled: bool,
    /// B2 PLS: power loss indicator latch.
    pub power_loss: bool,
    /// B1 U/D: last count direction, 1 = up.
    pub up: bool,
    /// B0 S: sign, set on underflow, cleared on overflow.
    pub sign: bool,
}

impl Str {
    /// Decodes an STR value (data range 00–FF).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > 0xFF {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            carry: data & 0x80 != 0,
            borrow: data & 0x40 != 0,
            compare: data & 0x20 != 0,
            index: data & 0x10 != 0,
            count_enabled: data & 0x08 != 0,
            power_loss: data & 0x04 != 0,
            up: data & 0x02 != 0,
            sign: data & 0x01 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.carry as u32) << 7
            | (self.borrow as u32) << 6
            | (self.compare as u32) << 5
            | (self.index as u32) << 4
            | (self.count_enabled as u32) << 3
            | (self.power_loss as u32) << 2
            | (self.up as u32) << 1
            | self.sign as u32
    }
}

/// CLEAR REG (09) data: the register to clear to zero.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClearTarget {
    /// 0 = MDR0.
    Mdr0,
    /// 1 = MDR1.
    Mdr1,
    /// 2 = CNTR.
    Cntr,
    /// 3 = STR.
    Str,
}

impl ClearTarget {
    /// Decodes CLEAR REG data (0–3).
    pub const fn from_data(data: u32) -> Result<Self, Error> {
        match data {
            0 => Ok(Self::Mdr0),
            1 => Ok(Self::Mdr1),
            2 => Ok(Self::Cntr),
            3 => Ok(Self::Str),
            _ => Err(Error::OutOfRange),
        }
    }

    /// The data value.
    pub const fn data(self) -> u32 {
        self as u32
    }
}

/// LOAD REG (0A) data: the transfer to perform.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LoadTarget {
    /// 0 = transfer DTR to CNTR.
    DtrToCntr,
    /// 1 = transfer CNTR to OTR.
    CntrToOtr,
}

impl LoadTarget {
    /// Decodes LOAD REG data (0–1).
    pub const fn from_data(data: u32) -> Result<Self, Error> {
        match data {
            0 => Ok(Self::DtrToCntr),
            1 => Ok(Self::CntrToOtr),
            _ => Err(Error::OutOfRange),
        }
    }

    /// The data value.
    pub const fn data(self) -> u32 {
        self as u32
    }
}
