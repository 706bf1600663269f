//! Per-device readiness (offline, starting, online, faulted) and the start-up stop.
//!
//! A board that comes online — at server start, after its link came back, after it was seen
//! to reboot — first gets a stop on every configured channel, whatever the engine believed
//! the axis was doing: a motor left running by a previous server (or by the board's own old
//! ramp) must not keep running. Until the board has acknowledged those stops the device is
//! `Starting` and its axes refuse goals with `DeviceStarting`. So is a device whose link has
//! not opened for the first time yet ([`Engine::link_opening`]): a link that never opened is
//! not down; one that opened and then failed is.

use motion_drivers::DeviceFault;
use motion_drivers::Driver;
use motion_ipc::DeviceState;

use crate::Engine;

/// What the engine knows of one device beyond its driver.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Device {
    /// Link (bus) index and driver index within that bus.
    pub bus: usize,
    pub slot: usize,
    /// The state published in the frame.
    pub state: DeviceState,
    /// The board was online (and its link up) in the previous step.
    was_online: bool,
    /// `DeviceStatus::resets` when last seen.
    resets: u32,
    /// The start-up stop was set and the board has not acknowledged it yet.
    startup_pending: bool,
}

impl Device {
    pub fn new(bus: usize, slot: usize) -> Self {
        Self {
            bus,
            slot,
            state: DeviceState::Starting,
            was_online: false,
            resets: 0,
            startup_pending: false,
        }
    }
}

impl<D: Driver> Engine<D> {
    /// Step 1a: device states from the drivers and the links; start-up stops for boards
    /// that (re)appeared.
    pub(crate) fn update_devices(&mut self) {
        for index in 0..self.devices.len() {
            let (bus, slot) = (self.devices[index].bus, self.devices[index].slot);
            let link_up = self.link_up[bus];
            let opened = self.link_opened[bus];
            let Some(driver) = self.buses[bus].drivers().get(slot) else {
                continue;
            };
            let status = driver.status();
            let online = link_up && status.online;
            let device = &mut self.devices[index];
            let came_online = online && (!device.was_online || status.resets != device.resets);
            device.was_online = online;
            device.resets = status.resets;
            if came_online {
                self.startup_stop(index);
                self.devices[index].startup_pending = true;
                if self.estop {
                    // The board lost its outputs with its reset: the safe states again.
                    self.outputs_to_safe_state();
                }
            }
            let Some(driver) = self.buses[bus].drivers().get(slot) else {
                continue;
            };
            let device = &mut self.devices[index];
            if device.startup_pending && online && !driver.goals_pending() {
                device.startup_pending = false;
            }
            if !online {
                device.startup_pending = false;
            }
            device.state = if !opened {
                DeviceState::Starting
            } else if !link_up || status.fault == Some(DeviceFault::LinkDown) {
                DeviceState::Offline
            } else if !status.online {
                if status.fault == Some(DeviceFault::NotResponding) {
                    DeviceState::Offline
                } else {
                    DeviceState::Starting
                }
            } else if device.startup_pending {
                DeviceState::Starting
            } else if status.fault.is_some() {
                DeviceState::Faulted
            } else {
                DeviceState::Online
            };
        }
    }

    /// A stop on every configured channel of `device`, whatever the axis's mode; an axis
    /// that was switched off on purpose is switched off again instead (the board forgot).
    fn startup_stop(&mut self, device: usize) {
        for index in 0..self.axes.len() {
            if self.axes[index].device != device {
                continue;
            }
            if self.axes[index].switched_off && self.off_axis(index).is_ok() {
                continue;
            }
            self.stop_axis(index, true);
        }
    }

    /// The state of the device of axis `index`.
    pub(crate) fn device_state_of(&self, index: usize) -> DeviceState {
        self.axes
            .get(index)
            .and_then(|axis| self.devices.get(axis.device))
            .map_or(DeviceState::Offline, |device| device.state)
    }

    /// Whether the link of `device` has opened at least once.
    pub(crate) fn device_link_opened(&self, device: usize) -> bool {
        self.devices
            .get(device)
            .is_some_and(|device| self.link_opened[device.bus])
    }

    /// Whether the link of `device` is up.
    pub(crate) fn device_link_up(&self, device: usize) -> bool {
        self.devices
            .get(device)
            .is_some_and(|device| self.link_up[device.bus])
    }
}
