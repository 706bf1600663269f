//! Per-motor parameters as the firmware holds them, with the manual's 7.1 defaults.

use tmcpack::{CurrentLevel, MotorOptions, MotorType, ReferenceFlags};

/// Everything $11, $13–$16, $18, $19 and $31 set for one motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MotorParams {
    pub i0: CurrentLevel,
    pub i1: CurrentLevel,
    pub i2: CurrentLevel,
    pub i3: CurrentLevel,
    pub t0: u16,
    pub vmin: u16,
    pub vstart: u16,
    pub div: u8,
    pub amax: u16,
    pub vmax: u16,
    pub poslimit: u32,
    pub motor_type: MotorType,
    pub options: MotorOptions,
    pub vrefmax: u16,
    pub debounce_mask: u16,
    pub ref_flags: ReferenceFlags,
    pub nulloffset: i32,
    pub testnullrange: u16,
    pub propdiv: u8,
    pub intdiv: u16,
    pub intclip: u16,
    pub intinpclip: u8,
    pub stop_left_min: u16,
    pub stop_right_max: u16,
}

impl Default for MotorParams {
    /// Manual 7.1 "Default Values": vstart=5, amax=128, vmax=511, vmin=4, vrefmax=100,
    /// div=2, poslimit=400·16, testnullrange=15·16, T0=500, I0=0 %, I1=50 %, I2=75 %,
    /// I3=100 %, motortype = DelayedTest0 | NullCenter | FilterSwitch | FastRef, de-bounce
    /// mask $0FFF, propdiv=8, intdiv=129, intclip=129, intinpclip=1; "All other values are
    /// set to 0". The $31 limits default to "no function".
    fn default() -> Self {
        Self {
            i0: CurrentLevel::Off,
            i1: CurrentLevel::P50,
            i2: CurrentLevel::P75,
            i3: CurrentLevel::P100,
            t0: 500,
            vmin: 4,
            vstart: 5,
            div: 2,
            amax: 128,
            vmax: 511,
            poslimit: 400 * 16,
            motor_type: MotorType::NULL_CENTER | MotorType::FILTER_SWITCH,
            options: MotorOptions::DELAY_TEST_NULL | MotorOptions::FAST_REF,
            vrefmax: 100,
            debounce_mask: 0x0FFF,
            ref_flags: ReferenceFlags::EMPTY,
            nulloffset: 0,
            testnullrange: 15 * 16,
            propdiv: 8,
            intdiv: 129,
            intclip: 129,
            intinpclip: 1,
            stop_left_min: 0,
            stop_right_max: 1023,
        }
    }
}

impl MotorParams {
    /// +1 when the zero point (and the reference switch) lies in the positive direction
    /// (NullLeft clear: "the driving range is in the area of negative numbers"), −1 when it
    /// lies left (NullLeft set).
    pub fn toward_zero(&self) -> i64 {
        if self.motor_type.contains(MotorType::NULL_LEFT) {
            -1
        } else {
            1
        }
    }

    /// `true` for a rotary axis with a usable poslimit.
    pub fn cyclic(&self) -> bool {
        self.motor_type.contains(MotorType::ROTARY) && self.poslimit > 0
    }

    /// De-bounce delay in ticks when FilterSwitch is set (mask $0FFF: "12-1 cycles").
    pub fn filter_ticks(&self) -> u32 {
        if self.motor_type.contains(MotorType::FILTER_SWITCH) {
            self.debounce_mask.count_ones().saturating_sub(1)
        } else {
            0
        }
    }
}
