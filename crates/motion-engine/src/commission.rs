//! Commissioning a device (`Commission` with `target` = device): a change of the board's
//! own settings — its bus address, its line rate, a factory reset — that its driver sends
//! and then finds the board again where it now answers
//! ([`Driver::commission`](motion_drivers::Driver::commission)).
//!
//! The rules, in the order a client sees them:
//! 1. `UnknownTarget` for any other kind with `target` = device; `ShuttingDown`;
//!    `UnknownDevice`;
//! 2. `EstopLatched` while the e-stop is latched: a commission re-parameterises the board
//!    (a Trinamic pack's `$CC` sets every parameter back to the factory's, its `$40` and
//!    `$42` have it answer elsewhere) while it is meant to hold — reset the e-stop first;
//! 3. `OutOfRange` for a `values[0]` that is no [`CommissionWhat`], a value that is no
//!    whole number in `u32`, or a new address another device on the same link has;
//! 4. authorisation: `NoClientId` without a client, then every axis and every signal of
//!    the device must be claimed by the sender (`ClaimedByOther` with the holder, or
//!    `NotClaimed`, naming the axis) — the client that commissions holds the whole board;
//! 5. `GroupBusy` (naming the axis) while an axis of the device moves: a goal that is not
//!    done, a stop or search in progress, a group's motion, or the board reporting motion;
//! 6. a line rate (`CommissionWhat::Baud`) on a link other devices share: until a rate
//!    change keeps the neighbours reachable (they stay at the old rate), it is refused while
//!    another device on the link is in use — `GroupBusy` while one of its axes moves or has
//!    a goal (one not done, or a held move to resume), `ClaimedByOther` while another
//!    client holds a claim on one of its axes or signals (the sender's own claims there do
//!    not count: nobody else relies on that device). The reply names the axis (`at_axis`,
//!    for a signal none) and the claimant (`holder`);
//! 7. the device must be online (`DeviceStarting`, `DeviceOffline`, `LinkDown`);
//! 8. the driver's own refusal: `Unsupported` (a board without the setting), `OutOfRange`
//!    (a value the board does not take), `DeviceStarting` (busy with an earlier change).
//!
//! A refusal of rules 4 to 6 also names the device at fault: `value` is its index (the
//! device commissioned, or the neighbour on its link).
//!
//! Accepted, the device is `Starting` in the frame of this very tick (the board is being
//! found again); `Online` again once found, `Offline` when it does not answer. After a new
//! address the server's info names it (`DeviceInfo::address`); the config still has the
//! old one, which the client tells its user to change.

use motion_drivers::{Commission, CommissionError, Driver};
use motion_ipc::{AxisMode, ClientId, CommandKind, CommandRequest, CommissionWhat, DeviceState};
use motion_ipc::{Reason, Target};

use crate::Engine;

/// Below this speed (units/s, a fraction of the axis's max) an axis counts as at rest.
const REST_FRACTION_OF_MAX: f64 = 1e-3;

impl<D: Driver> Engine<D> {
    /// Applies a request with `target` = device from `client` (see the module docs).
    pub(crate) fn apply_device_command(
        &mut self,
        request: &CommandRequest,
        client: ClientId,
    ) -> Reason {
        debug_assert_eq!(request.target, Target::Device as u32);
        if request.kind() != Ok(CommandKind::Commission) {
            return Reason::UnknownTarget;
        }
        if self.shutting_down {
            return Reason::ShuttingDown;
        }
        let index = request.axis as usize;
        let Some(device) = self.devices.get(index) else {
            return Reason::UnknownDevice;
        };
        let (bus, slot) = (device.bus, device.slot);
        if self.estop {
            return Reason::EstopLatched;
        }
        let Some(change) = change_of(request.values) else {
            return Reason::OutOfRange;
        };
        if let Commission::Address(address) = change {
            let taken = self
                .config
                .devices
                .iter()
                .enumerate()
                .any(|(other, d)| other != index && d.link == bus && d.address == address);
            if taken {
                return Reason::OutOfRange;
            }
        }
        if client.is_none() {
            return Reason::NoClientId;
        }
        self.reply_detail.value = index as f64;
        if let Err(reason) = self.holds_device(index, client) {
            return reason;
        }
        if let Some(axis) =
            (0..self.axes.len()).find(|&a| self.axes[a].device == index && self.moves(a))
        {
            self.reply_detail.at_axis = Some(axis);
            return Reason::GroupBusy;
        }
        if let Commission::Baud(_) = change
            && let Err(reason) = self.link_in_use(index, bus, client)
        {
            return reason;
        }
        self.reply_detail.value = 0.0;
        match self.devices[index].state {
            DeviceState::Online | DeviceState::Faulted => {}
            DeviceState::Starting => return Reason::DeviceStarting,
            DeviceState::Offline if !self.link_up[bus] => return Reason::LinkDown,
            DeviceState::Offline => return Reason::DeviceOffline,
        }
        let now = self.now;
        let result = match self.buses[bus].driver_mut(slot) {
            Some(driver) => driver.commission(now, change),
            None => Err(CommissionError::Offline),
        };
        match result {
            Ok(()) => {
                // The address the server talks to it at from now on (the info says it).
                let address = match change {
                    Commission::Address(address) => Some(address),
                    // Back to its rotary switches, taken to be the configured address.
                    Commission::FactoryReset => self.config_addresses.get(index).copied(),
                    Commission::Baud(_) => None,
                };
                if let (Some(address), Some(config)) = (address, self.config.devices.get_mut(index))
                {
                    config.address = address;
                }
                // Being found again: no goal is taken for it from this tick on.
                self.devices[index].state = DeviceState::Starting;
                self.reply_detail.value = request.values[1];
                Reason::Accepted
            }
            Err(CommissionError::Unsupported) => Reason::Unsupported,
            Err(CommissionError::OutOfRange) => Reason::OutOfRange,
            Err(CommissionError::Starting) => Reason::DeviceStarting,
            Err(CommissionError::Offline) if !self.link_up[bus] => Reason::LinkDown,
            Err(CommissionError::Offline) => Reason::DeviceOffline,
        }
    }

    /// Whether `client` holds the claim of every axis and signal of device `index`.
    fn holds_device(&mut self, index: usize, client: ClientId) -> Result<(), Reason> {
        for (a, axis) in self.axes.iter().enumerate() {
            if axis.device != index || axis.claimed_by == client {
                continue;
            }
            self.reply_detail.at_axis = Some(a);
            if axis.claimed_by.is_none() {
                return Err(Reason::NotClaimed);
            }
            self.reply_detail.holder = axis.claimed_by;
            return Err(Reason::ClaimedByOther);
        }
        for signal in &self.signals {
            if signal.config.device != index || signal.claimed_by == client {
                continue;
            }
            if signal.claimed_by.is_none() {
                return Err(Reason::NotClaimed);
            }
            self.reply_detail.holder = signal.claimed_by;
            return Err(Reason::ClaimedByOther);
        }
        Ok(())
    }

    /// For a line-rate change of device `index` on link `bus`: whether another device on the
    /// link is in use (rule 6 of the module docs), named in the reply.
    fn link_in_use(&mut self, index: usize, bus: usize, client: ClientId) -> Result<(), Reason> {
        let neighbour = |devices: &[crate::device::Device], d: usize| {
            d != index && devices.get(d).is_some_and(|device| device.bus == bus)
        };
        for a in 0..self.axes.len() {
            let device = self.axes[a].device;
            if !neighbour(&self.devices, device) {
                continue;
            }
            let holder = self.axes[a].claimed_by;
            let claimed = !holder.is_none() && holder != client;
            let busy = self.moves(a) || self.axes[a].held.is_some();
            if busy || claimed {
                self.reply_detail.at_axis = Some(a);
                self.reply_detail.holder = holder;
                self.reply_detail.value = device as f64;
                return Err(if busy {
                    Reason::GroupBusy
                } else {
                    Reason::ClaimedByOther
                });
            }
        }
        let claimed_signal = self.signals.iter().find(|signal| {
            neighbour(&self.devices, signal.config.device)
                && !signal.claimed_by.is_none()
                && signal.claimed_by != client
        });
        if let Some(signal) = claimed_signal {
            self.reply_detail.holder = signal.claimed_by;
            self.reply_detail.value = signal.config.device as f64;
            return Err(Reason::ClaimedByOther);
        }
        Ok(())
    }

    /// Whether axis `index` moves or may still move: a goal not done, a stop or search in
    /// progress, a group's motion, or its board reporting motion or speed.
    fn moves(&self, index: usize) -> bool {
        let axis = &self.axes[index];
        let pending = match axis.mode {
            AxisMode::Stopping | AxisMode::Homing | AxisMode::Group => true,
            AxisMode::Power | AxisMode::Velocity | AxisMode::RampVelocity => true,
            // Arrived as the frame says it (supervision's own `arrived` is only kept with
            // a `following_error`: with 0 an axis at its target would count as moving for
            // ever).
            AxisMode::Position | AxisMode::RampPosition => {
                let at_target =
                    !axis.state.moving && (axis.position() - axis.target).abs() <= axis.tolerance;
                !(axis.arrived || at_target)
            }
            _ => false,
        };
        pending
            || axis.group.is_some()
            || axis.state.moving
            || axis.velocity().abs() > axis.max_velocity * REST_FRACTION_OF_MAX
    }
}

/// The change `values` ask for: `values[0]` a [`CommissionWhat`], `values[1]` a whole
/// number in `u32` (ignored for a factory reset).
fn change_of(values: [f64; 3]) -> Option<Commission> {
    let what = CommissionWhat::from_value(values[0]).ok()?;
    let value = values[1];
    let whole = (value.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&value))
        .then_some(value as u32);
    Some(match what {
        CommissionWhat::Address => Commission::Address(whole?),
        CommissionWhat::Baud => Commission::Baud(whole?),
        CommissionWhat::FactoryReset => Commission::FactoryReset,
    })
}
