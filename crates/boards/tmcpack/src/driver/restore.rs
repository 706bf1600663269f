//! References across a restart of the server (`power_down = "restore"`, docs/keys/tmcpack.md
//! "References across a server restart"): the channel's side of the `$45` power-down mode
//! (manual 8.6 "Power-Down modus").
//!
//! The server saves, outside its tick, which axes it saw referenced and at rest and their
//! positions; at its next start it hands them to the driver
//! ([`Driver::restore_references`](motion_drivers::Driver::restore_references)), which
//! keeps them in [`Channel::saved`] until the pack's first configuration. An axis counts as
//! referenced from such a record only when the first poll after that configuration finds
//! the motor at exactly the saved position, `reference.restore` is not false, and
//! the pack either
//! - booted since it was last asked (`$43` reset flag) and answered the bit-0 request with
//!   "loaded valid position from EEprom" (P0 bit 0): the positions it saved at the
//!   undervoltage are in its registers ([`Channel::restored`]); or
//! - did not boot (no reset flag: "during first read out 1, afterwards 0", 8.6 `$43`): it
//!   kept running, and its position registers with it ([`Channel::kept`]);
//!
//! and the start-up's `$28` survey found the motor inactive ([`Channel::surveyed`]).
//!
//! A pack that booted without loading valid positions (the mode was off, the EEPROM
//! invalidated, a `$CC`) claims nothing, even when its position after the boot happens to
//! equal the saved one (0, say).

use tmcpack::Action;

use super::channel::Channel;

impl Channel {
    /// `$45` bit 0 loaded valid positions with the request sent as `seq`: referenced from
    /// the first poll after it if the axis was referenced when the pack was lost, its motor
    /// was not moving then, and it is to be (`reference.restore`). The pack saves positions,
    /// not references: an axis that had none before the outage has none after it.
    ///
    /// A server that started afresh knows no reference of before, only what its previous
    /// run saved ([`Channel::saved`]): such an axis is referenced from the first poll after
    /// it only if that poll finds it inactive at the saved position.
    pub fn restored(&mut self, seq: u64) {
        if !self.cfg.restore {
            return;
        }
        if self.referenced_at_loss && !self.lost_in_motion {
            self.confirm_position = Some(seq);
        } else if let Some(position) = self.saved {
            self.confirm_saved = Some((seq, position));
        }
    }

    /// The pack did not boot since it was last asked (no `$43` reset flag): its position
    /// registers ran on. An axis saved by the previous run of the server is referenced from
    /// the first poll after the request sent as `seq` if it finds the motor inactive at the
    /// saved position.
    pub fn kept(&mut self, seq: u64) {
        if let (true, Some(position)) = (self.cfg.restore, self.saved) {
            self.confirm_saved = Some((seq, position));
        }
    }

    /// The start-up's `$28` survey found the motor doing `action`: one found active (left
    /// running by someone after the previous server stopped) gets nothing from its saved
    /// record.
    pub fn surveyed(&mut self, action: Option<Action>) {
        if action.is_none_or(|a| a.is_active()) {
            self.saved = None;
        }
    }

    /// A poll answer (request `seq`): the check [`restored`](Self::restored) or
    /// [`kept`](Self::kept) asked for. A motor stopped by a switch, or anywhere but the
    /// saved position, stays unreferenced. (It may show the start-up stop's `$25` with
    /// velocity 0 as its action: a motor the survey found active was refused there.)
    pub(super) fn confirm_saved_position(
        &mut self,
        seq: u64,
        position: i32,
        action: Action,
        stopped: bool,
    ) {
        let Some((sent, saved)) = self.confirm_saved else {
            return;
        };
        if seq <= sent {
            return;
        }
        self.confirm_saved = None;
        if position == saved && !action.is_referencing() && !stopped {
            self.state.homed = true;
        }
    }

    /// The pack is in its power-down state: it stopped the motor at once. An axis that may
    /// have moved then (since the last check), or whose position is not to be trusted after
    /// one (`reference.restore = false`: the motors are held without current), loses its
    /// reference.
    pub fn power_went_down(&mut self) {
        self.lost_in_motion |= self.moved_since_check || self.state.moving;
        if self.lost_in_motion || !self.cfg.restore {
            self.state.homed = false;
            self.confirm_position = None;
            self.confirm_saved = None;
        }
        self.referenced_at_loss |= self.state.homed;
    }

    /// The pack was configured (and any restore done): what was known at the loss is
    /// spent.
    pub fn loss_consumed(&mut self) {
        self.lost_in_motion = false;
        self.referenced_at_loss = false;
        self.saved = None;
    }

    /// A `$45` check found the pack outside its power-down state.
    pub fn checked(&mut self) {
        self.moved_since_check = false;
    }
}
