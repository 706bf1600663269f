//! Configuration of a simulated pack: what the rotary switches, jumpers, DIP switches and
//! the machine around the pack would decide on real hardware.

use core::time::Duration;

use tmcpack::{AmaxDivisor, CanBitrate, OptionsLayout, Variant};

/// A reference switch in the motor's *physical* coordinates (microsteps of the rotor, which
/// $27 and reference searches do not move).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RefSwitch {
    /// First physical position at which the switch is actuated.
    pub from: i64,
    /// Last physical position at which the switch is actuated (inclusive).
    pub to: i64,
    /// `true` for an opener (normally closed: high level when actuated, the wiring manual
    /// section 4 recommends, which needs the *NullPositive* flag); `false` for a closer
    /// (low level when actuated, which matches the default flags).
    pub opener: bool,
}

impl RefSwitch {
    /// `true` when the rotor at `phys` actuates the switch.
    pub fn actuated(&self, phys: i64) -> bool {
        (self.from..=self.to).contains(&phys)
    }

    /// The electrical level at Ref_In (`true` = high).
    pub fn level(&self, phys: i64) -> bool {
        self.actuated(phys) == self.opener
    }
}

/// What is connected to one motor connector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorConfig {
    /// The reference switch, if any (none: Ref_In floats high).
    pub ref_switch: Option<RefSwitch>,
    /// Mechanical end stops `(low, high)` in physical microsteps: the rotor cannot leave
    /// this range and loses steps instead (what a mechanical reference, $15 MechRef, drives
    /// against). `None`: free travel.
    pub travel: Option<(i64, i64)>,
    /// The value at the motor's analogue input A_In, 0..=1023.
    pub analog: u16,
}

impl Default for MotorConfig {
    fn default() -> Self {
        Self {
            // Half a revolution (3200 microsteps) from the start, in the positive direction:
            // where the default flags (NullLeft clear) search for it.
            ref_switch: Some(RefSwitch {
                from: 3200,
                to: 3519,
                opener: false,
            }),
            travel: None,
            analog: 512,
        }
    }
}

/// Everything that parameterises a [`TmcpackSim`](super::TmcpackSim).
#[derive(Debug, Clone, PartialEq)]
pub struct TmcpackSimConfig {
    /// RS-232 / RS-485 address set on the rotary switches (scanned on reset).
    pub address: u8,
    /// SIXpack (6 motors, default) or QUADpack (4).
    pub variant: Variant,
    /// Seed of the analogue noise.
    pub seed: u64,
    /// Firmware revision reported by $43 (149 = V1.4.9, which has $45 power-down).
    pub firmware_revision: u8,
    /// Serial number reported by $43.
    pub serial_number: u16,
    /// Board temperature reported by $43, °C.
    pub temperature_c: i8,
    /// Supply voltage (channel 7; power-down below `power_down_volts`).
    pub supply_volts: f64,
    /// Undervoltage level of the power-down mode ($45: "below 13V").
    pub power_down_volts: f64,
    /// Extra time from the firmware's cycle that takes a request to the start of the
    /// switch-over delay. The firmware acts on a word in its next 2 ms cycle (up to 2 ms:
    /// the manual's "approx. 2 ms per command" for CAN, read for the serial line too);
    /// the default adds nothing to that.
    pub processing_time: Duration,
    /// Processing time of one CAN command taken from the 16-command cache (manual 6.2:
    /// "approx. 2 ms per command").
    pub can_command_time: Duration,
    /// Start-up after $CC or a power cycle, during which the pack hears nothing
    /// ($CC: "This command needs about 1 second"; 5.1: "after a second").
    pub boot_time: Duration,
    /// Peak-to-peak half-width of the uniform noise added to analogue reads, in LSB.
    pub analog_noise_lsb: u16,
    /// Value at the external analogue input (channel 6).
    pub external_analog: u16,
    /// The CAN bit-rate jumpers (reported in $30 P4 bits 6 and 7).
    pub can_bitrate: CanBitrate,
    /// State of the CTS line as $44 reports it.
    pub cts: bool,
    /// QUADpack DIP current setting per motor, percent (0, 33, 66 or 100).
    pub quadpack_dip_percent: [u8; 4],
    /// The six motor connectors (a QUADpack uses the first four).
    pub motors: [MotorConfig; 6],
    /// Size of the simulated flash ($F3–$F5).
    pub flash_size: usize,
    /// Magic code $F2 wants (the manual does not publish it; ours is invented).
    pub flash_magic: u32,
    /// "Magic Code 2" $F6/$F7 want (invented likewise).
    pub eeprom_magic: u16,
    /// How this firmware reads `$14` amax: /64 per 2 ms tick (the `$14` text, default) or
    /// /16 (manual 7.1's defaults).
    pub amax_divisor: AmaxDivisor,
    /// Where this firmware has StopNoRef in `$15` P6: bit 5 (the table, default) or bit 6
    /// (the prose; NullPositive then bit 5).
    pub options_layout: OptionsLayout,
}

impl Default for TmcpackSimConfig {
    fn default() -> Self {
        Self {
            address: 1,
            variant: Variant::SixPack,
            seed: 0x5349_5850_4143_4b31,
            firmware_revision: 149,
            serial_number: 1001,
            temperature_c: 35,
            supply_volts: 24.0,
            power_down_volts: 13.0,
            processing_time: Duration::ZERO,
            can_command_time: tmcpack::CAN_COMMAND_TIME,
            boot_time: Duration::from_secs(1),
            analog_noise_lsb: 1,
            external_analog: 0,
            can_bitrate: CanBitrate::Kbit250,
            cts: false,
            quadpack_dip_percent: [100; 4],
            motors: [MotorConfig::default(); 6],
            flash_size: 32 * 1024,
            flash_magic: 0x4641_4C53,
            eeprom_magic: 0xEE57,
            amax_divisor: AmaxDivisor::By64,
            options_layout: OptionsLayout::Table,
        }
    }
}
