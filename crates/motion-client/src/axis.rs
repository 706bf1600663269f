//! [`Axis`]: one axis of the server, by handle; typed commands and waits.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, CommandKind, FaultCode, FrameFlags, Target,
};

use crate::{Accepted, ClaimGuard, Client, ClientError, Frame, JogGuard};

/// One axis of the server, found by name with [`Client::axis`]. Cheap to copy.
///
/// Velocities and accelerations of `0.0` mean "the axis's configured maximum".
#[derive(Debug)]
pub struct Axis<'c, S: Service> {
    client: &'c Client<S>,
    index: u32,
}

impl<S: Service> Clone for Axis<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: Service> Copy for Axis<'_, S> {}

impl<'c, S: Service> Axis<'c, S> {
    pub(crate) fn new(client: &'c Client<S>, index: usize) -> Self {
        Self {
            client,
            index: u32::try_from(index).unwrap_or(u32::MAX),
        }
    }

    /// The axis index (config order), as used in frames and requests.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The axis's static description (name, unit, limits, capabilities).
    pub fn info(&self) -> AxisInfo {
        self.client.axis_info(self.index as usize)
    }

    /// The axis name.
    pub fn name(&self) -> String {
        self.info().name().to_owned()
    }

    /// The axis's state in the newest frame (an 80-byte copy).
    pub fn state(&self) -> Result<AxisState, ClientError> {
        let frame = self.client.latest()?;
        Ok(state_in(&frame, self.index))
    }

    fn command(&self, kind: CommandKind, values: [f64; 3]) -> Result<Accepted, ClientError> {
        self.client.command(self.index, kind, values)
    }

    /// Position target handed to the board's own controller (`Position`), without the
    /// server's ramp; `motionctl move` (a limited ramp) is [`ramp_to`](Self::ramp_to).
    pub fn position(&self, position: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Position, [position, 0.0, 0.0])
    }

    /// The old name of [`position`](Self::position).
    #[deprecated(
        since = "0.1.0",
        note = "renamed `position` (a board-controlled target); `motionctl move` is `ramp_to`"
    )]
    pub fn move_to(&self, position: f64) -> Result<Accepted, ClientError> {
        self.position(position)
    }

    /// Position along a velocity- and acceleration-limited profile (`RampPosition`).
    pub fn ramp_to(
        &self,
        position: f64,
        velocity: f64,
        accel: f64,
    ) -> Result<Accepted, ClientError> {
        self.command(CommandKind::RampPosition, [position, velocity, accel])
    }

    /// Velocity in units/s (`Velocity`; the server's deadman applies: see [`Axis::jog`]).
    pub fn velocity(&self, velocity: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Velocity, [velocity, 0.0, 0.0])
    }

    /// Velocity reached with acceleration `accel` (`RampVelocity`; deadman applies).
    pub fn ramp_velocity(&self, velocity: f64, accel: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::RampVelocity, [velocity, accel, 0.0])
    }

    /// Open-loop power, −1.0..=1.0 of full scale (`Power`; deadman applies).
    pub fn power(&self, power: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Power, [power, 0.0, 0.0])
    }

    /// Decelerate to a stop and hold.
    pub fn stop(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Stop, [0.0; 3])
    }

    /// Reference search at `velocity` units/s (0.0: the server's default search speed).
    pub fn home(&self, velocity: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Home, [velocity, 0.0, 0.0])
    }

    /// Brings the axis's position move (`position`, `ramp_to`) to rest and keeps it
    /// (`Hold` with the axis as target): the QSB-M pauses its own move (COMMAND 6), any
    /// other board stops at the move's acceleration. The frame flags the axis `HELD` until
    /// [`resume`](Self::resume), a stop or another goal. Refused with `NotMoving` when the
    /// axis has no position move on its way (a jog is stopped, not held).
    pub fn hold(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Hold, [0.0; 3])
    }

    /// Continues the move [`hold`](Self::hold) brought to rest, to its target with its
    /// velocity and acceleration. Refused with `NotMoving` when nothing is held.
    pub fn resume(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Resume, [0.0; 3])
    }

    /// Declares the current position to be `position` (no motion).
    pub fn set_position(&self, position: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::SetPosition, [position, 0.0, 0.0])
    }

    /// Takes an exclusive claim: other clients' commands on this axis are then refused.
    pub fn claim(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Claim, [0.0; 3])
    }

    /// Gives a claim back.
    pub fn release(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Release, [0.0; 3])
    }

    /// Takes a claim held by a guard: released when the guard is dropped, never released
    /// (nor renewed) on a server that restarted meanwhile.
    pub fn claim_guard(&self) -> Result<ClaimGuard<'c, S>, ClientError> {
        ClaimGuard::take(self.client, Target::Axis, self.index)
    }

    /// De-energises the motor (`Off`): it coasts, without holding torque. A board that
    /// cannot de-energise refuses with `Unsupported`.
    pub fn off(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Off, [0.0; 3])
    }

    /// Waits until the axis's device is online (answering, configured, its start-up stop
    /// acknowledged), so that goals are taken. Fails at once when the device is faulted.
    pub fn wait_ready(&self, timeout: Duration) -> Result<(), ClientError> {
        let device = usize::from(self.info().device_index);
        self.client.wait_devices_ready(&[device], timeout)
    }

    /// The fault sentence of the axis ([`FaultCode::explain`]) when it is faulted in the
    /// newest frame.
    pub fn fault_text(&self) -> Option<String> {
        self.client.fault_text(self.index)
    }

    /// Starts a jog at `velocity` units/s reached with `accel` units/s² (`RampVelocity`),
    /// and returns a guard that keeps it going and stops the axis when dropped.
    pub fn jog(&self, velocity: f64, accel: f64) -> Result<JogGuard<'c, S>, ClientError> {
        JogGuard::start(
            self.client,
            self.index,
            CommandKind::RampVelocity,
            [velocity, accel, 0.0],
        )
    }

    /// Open-loop power under a guard, like [`Axis::jog`].
    pub fn power_guarded(&self, power: f64) -> Result<JogGuard<'c, S>, ClientError> {
        JogGuard::start(
            self.client,
            self.index,
            CommandKind::Power,
            [power, 0.0, 0.0],
        )
    }

    /// Waits until the last position goal is reached (the server's `ARRIVED` flag, from a
    /// frame at or after the goal's tick). Fails early when the axis can no longer get there.
    pub fn wait_until_arrived(&self, timeout: Duration) -> Result<Frame<S>, ClientError> {
        self.wait_for("arrive", timeout, |state, frame| {
            let flags = state.flags();
            if flags.contains(AxisFlags::ARRIVED) && !flags.contains(AxisFlags::MOVING) {
                return Ok(true);
            }
            if let Some(why) = blocked(state, frame) {
                return Err(why);
            }
            match state.mode() {
                Ok(AxisMode::Position | AxisMode::RampPosition) => Ok(false),
                Ok(mode) => Err(format!("its goal was replaced (mode is now {mode:?})")),
                Err(error) => Err(error.to_string()),
            }
        })
    }

    /// Waits until the reference search started by [`Axis::home`] has finished with the
    /// axis homed.
    pub fn wait_until_homed(&self, timeout: Duration) -> Result<Frame<S>, ClientError> {
        self.wait_for("finish homing", timeout, |state, frame| {
            let homing = state.mode() == Ok(AxisMode::Homing);
            if state.flags().contains(AxisFlags::HOMED) && !homing {
                return Ok(true);
            }
            if let Some(why) = blocked(state, frame) {
                return Err(why);
            }
            if homing {
                Ok(false)
            } else {
                Err("the reference search ended without a reference".to_owned())
            }
        })
    }

    fn wait_for(
        &self,
        what: &'static str,
        timeout: Duration,
        mut done: impl FnMut(&AxisState, &Frame<S>) -> Result<bool, String>,
    ) -> Result<Frame<S>, ClientError> {
        let deadline = Instant::now() + timeout;
        let (since, epoch) = self
            .client
            .goal_ticks
            .borrow()
            .get(self.index as usize)
            .copied()
            .unwrap_or((0, self.client.session.epoch()));
        let timed_out = || ClientError::WaitTimeout {
            axis: self.name(),
            what,
            waited: timeout,
        };
        let mut frame = self.client.latest()?;
        loop {
            if self.client.session.epoch() != epoch {
                // The goal died with the old server.
                if let Some(restart) = self.client.session.last_restart() {
                    return Err(ClientError::ServerRestarted(restart));
                }
            }
            if frame.tick >= since {
                let state = state_in(&frame, self.index);
                if let Some(error) = self.faulted(&state) {
                    return Err(error);
                }
                match done(&state, &frame) {
                    Ok(true) => return Ok(frame),
                    Ok(false) => {}
                    Err(why) => {
                        return Err(ClientError::WaitAborted {
                            axis: self.name(),
                            what,
                            why,
                        });
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(timed_out());
            }
            drop(frame);
            frame = match self.client.next_frame(deadline - now) {
                Ok(next) => next,
                Err(ClientError::NoFrame(_)) => return Err(timed_out()),
                Err(error) => return Err(error),
            };
        }
    }

    /// [`ClientError::AxisFaulted`] with the fault sentence when `state` is faulted.
    fn faulted(&self, state: &AxisState) -> Option<ClientError> {
        if !state.flags().contains(AxisFlags::FAULT) {
            return None;
        }
        let info = self.info();
        let (fault, text) = match state.fault() {
            Ok(code) => (
                code,
                code.explain(
                    info.name(),
                    state.fault_value,
                    state.fault_limit,
                    info.unit(),
                ),
            ),
            Err(error) => (
                FaultCode::None,
                format!("axis `{}` is faulted ({error})", info.name()),
            ),
        };
        Some(ClientError::AxisFaulted {
            axis: info.name().to_owned(),
            fault,
            text,
        })
    }
}

fn state_in(frame: &Frame<impl Service>, index: u32) -> AxisState {
    frame
        .axes()
        .get(index as usize)
        .copied()
        .unwrap_or(AxisState::UNKNOWN)
}

/// Why an unfaulted axis cannot reach any goal right now, if it cannot.
fn blocked(state: &AxisState, frame: &Frame<impl Service>) -> Option<String> {
    let flags = state.flags();
    if flags.contains(AxisFlags::ESTOPPED) || frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
        return Some("the e-stop is latched".to_owned());
    }
    if frame.flags().contains(FrameFlags::SHUTTING_DOWN) {
        return Some("the server is shutting down".to_owned());
    }
    None
}
