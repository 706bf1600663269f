//! The pack's power-down mode, `$45` (manual 8.6 "Power-Down modus", "Version 1.46 and since
//! Version 1.49"): "These versions store the actual motor positions as soon as the power
//! supply goes below 13V, if enabled. The motors are stopped, as soon as undervoltage is
//! detected." Key `power_down` (docs/keys/tmcpack.md):
//!
//! - `"off"` (default): no `$45` is sent, as before.
//! - `"save"`: after the configuration, `$45` bit 2 ("activate Power down (stop motors &
//!   autosave position on undervoltage)") with bit 3 ("Reset powerdown state and re-enable
//!   the motors"), then bit 1 ("set positions in EEprom as invalid").
//! - `"restore"`: as `"save"`, but when the pack booted since the driver last configured it
//!   (the `$43` reset flag: "during first read out 1, afterwards 0"), first bit 0 ("Read
//!   positions from EEprom, and copy them to the motor position registers, if they contain
//!   valid values").
//!
//! What counts as referenced: the pack saves positions, not references. The loaded
//! positions always become the axes' positions, but an axis counts as referenced from them
//! only when all of these hold: the answer to the bit-0 request says "loaded valid position
//! from EEprom" (P0 bit 0), and from the first poll after it; the driver knew the axis as
//! referenced when it lost the pack (the server ran through the outage, on a UPS or another
//! supply) — a server that starts afresh knows only what its previous run saved (module
//! `restore`: an axis saved referenced and at rest whose position the pack reports
//! unchanged), else its axes need a search or a set-position (`motionctl set-position AXIS
//! <the restored position>` is the operator's word for it); the driver did not last see the motor moving (or command it to
//! move) before it lost the pack, nor moving since the last check before it found the pack
//! in its power-down state (the pack stops the motors at once at undervoltage; a motor
//! stopped abruptly from speed may have lost steps, and its saved position with them); and
//! its `reference.restore` is not false. Positions are only ever loaded after a boot
//! and are invalidated right after every configuration and after every recovered
//! undervoltage, so the EEPROM never holds positions older than the last undervoltage: a
//! later reset without one (`$CC`, a watchdog) finds nothing valid and claims nothing. The
//! positions are restored only after a boot the driver saw (a `$43` reset flag it read):
//! a pack that kept running kept its registers, and the EEPROM's would be stale.
//!
//! While online the state is read every [`POWER_CHECK_PERIOD`] (`$45` with no bit set: its
//! answer is the state "before" and "after" a command that changes nothing). A pack in the
//! power-down state (undervoltage seen; with the mode active its motors are stopped and held)
//! is a [`DeviceFault::BoardError`]: the engine stops and faults every axis of the pack,
//! axes with `reference.restore = false` or whose motor moved since the last check lose their
//! reference, and the driver asks bit 3 every period; once the supply is back above the
//! level the pack re-enables its motors, the fault clears (axes need a new command) and the
//! saved positions are invalidated. A firmware without `$45` (V1.4.7, V1.4.8, before V1.4.6)
//! gets no `$45` and is a `BoardError` as long as the key asks for the mode.
//!
//! The state shows in the device's description (`DeviceStatus::firmware`, `motionctl list`,
//! the Python package's `firmware`): `SIXpack V1.4.9 #1001 PD armed` (or `PD loaded` after a
//! restore, `PD DOWN` in the power-down state, `PD n/a` without `$45`); without the key the
//! description stays `SIXpack V1.4.9 s/n 1001`.

use core::fmt::Write as _;
use core::time::Duration;

use tmcpack::{Command, PowerDownRequest, PowerDownStatus, Request, Variant, power_down_supported};

use super::wire::{Pick, Purpose};
use super::{Phase, TmcpackDriver};
use crate::PowerDownMode;
use motion_drivers::{DeviceFault, Driver as _, FIRMWARE_LEN, SavedReference};

/// How often an online pack's power-down state is read (`$45`, no bit set).
pub const POWER_CHECK_PERIOD: Duration = Duration::from_secs(1);

/// The `$45` requests after the configuration, in order.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    /// Bit 0: load the saved positions.
    Load,
    /// Bits 2 and 3: activate the mode, reset the power-down state.
    Arm,
    /// Bit 1: invalidate the saved positions.
    Invalidate,
}

/// What the driver knows of the pack's power-down mode.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct PowerDown {
    pub mode: PowerDownMode,
    /// Firmware revision and serial number from the last `$43`.
    pub firmware: Option<(u8, u16)>,
    /// A `$43` showed the reset flag since the last configuration: the pack booted.
    pub booted: bool,
    step: Step,
    /// The mode is active (bit 2 answered since the pack was configured).
    pub armed: bool,
    /// The pack loaded valid positions at this start-up.
    pub loaded: bool,
    /// The pack is in its power-down state.
    pub down: bool,
    /// The firmware has no `$45`.
    pub unsupported: bool,
    /// The saved positions are to be invalidated (the state was reset while online).
    invalidate: bool,
    /// When the next `$45` check goes.
    pub check_at: Duration,
    /// The bits of the `$45` last sent.
    sent: PowerDownRequest,
}

impl PowerDown {
    pub fn new(mode: PowerDownMode) -> Self {
        Self {
            mode,
            firmware: None,
            booted: false,
            step: Step::Arm,
            armed: false,
            loaded: false,
            down: false,
            unsupported: false,
            invalidate: false,
            check_at: Duration::ZERO,
            sent: PowerDownRequest::EMPTY,
        }
    }

    /// The pack lost what it was told (reset, silence, link): known again after the next
    /// configuration.
    pub fn forget(&mut self) {
        self.armed = false;
        self.loaded = false;
        self.down = false;
        self.invalidate = false;
    }

    /// The bits of the start-up request `step`.
    fn flags(step: Step) -> PowerDownRequest {
        match step {
            Step::Load => PowerDownRequest::LOAD_POSITIONS,
            Step::Arm => PowerDownRequest::ACTIVATE | PowerDownRequest::RESET_STATE,
            Step::Invalidate => PowerDownRequest::INVALIDATE_POSITIONS,
        }
    }

    /// The word the description ends with: `armed`, `loaded`, `DOWN`, `n/a`, or nothing
    /// while not known.
    fn state(&self) -> Option<&'static str> {
        if self.unsupported {
            Some("n/a")
        } else if self.down {
            Some("DOWN")
        } else if self.loaded {
            Some("loaded")
        } else if self.armed {
            Some("armed")
        } else {
            None
        }
    }
}

impl TmcpackDriver {
    /// The `$43` answer: firmware and serial for the description, the reset flag for a
    /// restore.
    pub(super) fn on_unit_info(&mut self, revision: u8, reset: bool, serial: u16) {
        self.power.firmware = Some((revision, serial));
        self.power.booted |= reset;
        self.describe();
    }

    /// The description: variant, firmware revision ("148=V1.4.8"), serial number, and with
    /// the key the power-down state (at most [`FIRMWARE_LEN`] bytes: `QUADpack V1.4.9
    /// #65535 PD loaded` is 32).
    pub(super) fn describe(&mut self) {
        let Some((revision, serial)) = self.power.firmware else {
            return;
        };
        let mut text = motion_base::FixedText::<FIRMWARE_LEN>::new();
        let name = match self.variant {
            Variant::SixPack => "SIXpack",
            Variant::QuadPack => "QUADpack",
        };
        let (a, b, c) = (revision / 100, revision / 10 % 10, revision % 10);
        let _ = if self.power.mode == PowerDownMode::Off {
            write!(text, "{name} V{a}.{b}.{c} s/n {serial}")
        } else {
            match self.power.state() {
                Some(state) => write!(text, "{name} V{a}.{b}.{c} #{serial} PD {state}"),
                None => write!(text, "{name} V{a}.{b}.{c} #{serial}"),
            }
        };
        self.status.set_firmware(text.as_str());
    }

    /// [`Driver::restore_references`](motion_drivers::Driver::restore_references): with
    /// `power_down = "restore"`, the positions a previous run of the server saved, kept
    /// for the first configuration (module `restore`).
    pub(super) fn take_saved_references(&mut self, saved: &[SavedReference]) {
        if self.power.mode != PowerDownMode::Restore {
            return;
        }
        for record in saved {
            if record.channel >= self.channel_count() {
                continue;
            }
            if let Some(Some(channel)) = self.channels.get_mut(record.channel) {
                channel.saved = i32::try_from(record.counts).ok();
            }
        }
    }

    /// The configuration plan is out: the `$45` steps, or online.
    pub(super) fn configured(&mut self, now: Duration) {
        if self.power.mode == PowerDownMode::Off {
            self.go_online(now);
            return;
        }
        let revision = self.power.firmware.map(|(revision, _)| revision);
        if revision.is_some_and(|r| !power_down_supported(r)) {
            // No `$45` on this firmware: the mode the config asks for is missing.
            self.power.unsupported = true;
            self.go_online(now);
            self.status.fault = Some(DeviceFault::BoardError);
            self.describe();
            return;
        }
        self.power.unsupported = false;
        self.power.loaded = false;
        let restore = self.power.mode == PowerDownMode::Restore;
        self.power.step = if restore && self.power.booted {
            Step::Load
        } else {
            Step::Arm
        };
        if restore && !self.power.booted {
            // The pack kept running since it was last asked: its registers are where the
            // previous server left them, if nothing moved the motors since (module
            // `restore`).
            let seq = self.seq;
            for channel in self.channels.iter_mut().flatten() {
                channel.kept(seq);
            }
        }
        self.phase = Phase::PowerDown;
    }

    /// The `$45` of the current start-up step.
    pub(super) fn pick_power_down(&mut self) -> Pick {
        let flags = PowerDown::flags(self.power.step);
        self.power_query(flags)
    }

    fn power_query(&mut self, flags: PowerDownRequest) -> Pick {
        self.power.sent = flags;
        self.query(
            Request::PowerDown {
                reply_to: self.reply_address,
                flags,
            },
            Command::PowerDown,
            None,
            Purpose::PowerDown,
        )
    }

    /// The `$45` check of an online pack, when due: bit 3 while it is in the power-down
    /// state, bit 1 after it left it, else no bit.
    pub(super) fn pick_power_check(&mut self, now: Duration) -> Option<Pick> {
        if !self.power_check_due(now) {
            return None;
        }
        self.power.check_at = now + POWER_CHECK_PERIOD;
        let flags = if self.power.down {
            PowerDownRequest::RESET_STATE
        } else if self.power.invalidate {
            PowerDownRequest::INVALIDATE_POSITIONS
        } else {
            PowerDownRequest::EMPTY
        };
        Some(self.power_query(flags))
    }

    /// Whether a `$45` check is due at `now`.
    pub(super) fn power_check_due(&self, now: Duration) -> bool {
        self.power_check_at().is_some_and(|at| now >= at)
    }

    /// When the next `$45` check is due (`None` without the mode).
    pub(super) fn power_check_at(&self) -> Option<Duration> {
        let p = &self.power;
        (p.mode != PowerDownMode::Off && !p.unsupported && self.phase == Phase::Online)
            .then_some(p.check_at)
    }

    /// A `$45` answer.
    pub(super) fn on_power_down(&mut self, now: Duration, status: PowerDownStatus) {
        match self.phase {
            Phase::PowerDown => self.on_startup_step(now, status),
            Phase::Online => self.on_power_check(now, status),
            _ => {}
        }
        self.describe();
    }

    fn on_startup_step(&mut self, now: Duration, status: PowerDownStatus) {
        match self.power.step {
            Step::Load => {
                // "1 = loaded valid position from EEprom": only then is any axis referenced.
                self.power.loaded = status.contains(PowerDownStatus::LOADED);
                if self.power.loaded {
                    let seq = self.seq;
                    for channel in self.channels.iter_mut().flatten() {
                        channel.restored(seq);
                    }
                }
                self.power.step = Step::Arm;
            }
            Step::Arm => {
                self.power.armed = true;
                self.power.down = status.contains(PowerDownStatus::DOWN_AFTER);
                if self.power.down {
                    // Below the level already: the saved positions stay, the state is
                    // reset once the supply is back.
                    self.power_online(now);
                } else {
                    self.power.step = Step::Invalidate;
                }
            }
            Step::Invalidate => self.power_online(now),
        }
    }

    fn power_online(&mut self, now: Duration) {
        self.go_online(now);
        self.power.booted = false;
        self.power.check_at = now + POWER_CHECK_PERIOD / 2;
        for channel in self.channels.iter_mut().flatten() {
            channel.loss_consumed();
        }
        if self.power.down {
            self.went_down();
        }
    }

    fn on_power_check(&mut self, now: Duration, status: PowerDownStatus) {
        if status.contains(PowerDownStatus::DOWN_AFTER) {
            if !self.power.down {
                self.power.down = true;
                self.went_down();
            }
            return;
        }
        if self.power.down {
            // Re-enabled: the positions saved at the undervoltage are stale from now on.
            self.power.down = false;
            self.power.invalidate = true;
            self.power.check_at = now;
            self.status.fault = None;
            for channel in self.channels.iter_mut().flatten() {
                channel.loss_consumed();
            }
        } else if self
            .power
            .sent
            .contains(PowerDownRequest::INVALIDATE_POSITIONS)
        {
            self.power.invalidate = false;
        }
        for channel in self.channels.iter_mut().flatten() {
            channel.checked();
        }
    }

    /// The pack is in its power-down state: a device fault, and the axes that may have lost
    /// their position lose their reference.
    fn went_down(&mut self) {
        self.status.fault = Some(DeviceFault::BoardError);
        for channel in self.channels.iter_mut().flatten() {
            channel.power_went_down();
        }
    }
}
