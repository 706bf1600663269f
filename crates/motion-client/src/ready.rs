//! Readiness: a device takes goals once it is online (answering, configured, its start-up
//! stop acknowledged). Until then the server refuses goals with `DeviceStarting` or
//! `DeviceOffline`.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::DeviceState;

use crate::{Client, ClientError, DeviceStatus, Frame};

impl<S: Service> Client<S> {
    /// Every device and its state in the newest frame (opens the frame subscription).
    pub fn devices(&self) -> Result<Vec<DeviceStatus>, ClientError> {
        let frame = self.latest()?;
        Ok(self.statuses(&frame, None))
    }

    fn statuses(&self, frame: &Frame<S>, only: Option<&[usize]>) -> Vec<DeviceStatus> {
        let count = self.info.current().map_or(0, |info| info.devices().len());
        (0..count)
            .filter(|index| only.is_none_or(|only| only.contains(index)))
            .map(|index| DeviceStatus {
                index,
                name: self.device_name(index),
                state: frame.device_state(index),
            })
            .collect()
    }

    /// Waits until every device is online. Fails with [`ClientError::NotReady`] naming the
    /// devices still starting or offline (and their state) when `timeout` passes, and at
    /// once when a device is faulted (a reset is needed; waiting does not help).
    pub fn wait_ready(&self, timeout: Duration) -> Result<(), ClientError> {
        let count = self.info.current().map_or(0, |info| info.devices().len());
        let all: Vec<usize> = (0..count).collect();
        self.wait_devices_ready(&all, timeout)
    }

    /// [`Client::wait_ready`] for the devices `devices` (indices, config order).
    pub fn wait_devices_ready(
        &self,
        devices: &[usize],
        timeout: Duration,
    ) -> Result<(), ClientError> {
        if devices.is_empty() {
            return Ok(());
        }
        let deadline = Instant::now() + timeout;
        let mut frame = self.latest()?;
        loop {
            let pending: Vec<DeviceStatus> = self
                .statuses(&frame, Some(devices))
                .into_iter()
                .filter(|device| device.state != DeviceState::Online)
                .collect();
            if pending.is_empty() {
                return Ok(());
            }
            let faulted = pending
                .iter()
                .any(|device| device.state == DeviceState::Faulted);
            let now = Instant::now();
            if faulted || now >= deadline {
                return Err(ClientError::NotReady {
                    devices: pending,
                    waited: timeout,
                });
            }
            drop(frame);
            frame = match self.next_frame(deadline - now) {
                Ok(next) => next,
                Err(ClientError::NoFrame(_)) => {
                    return Err(ClientError::NotReady {
                        devices: pending,
                        waited: timeout,
                    });
                }
                Err(error) => return Err(error),
            };
        }
    }
}
