//! Safety: faults from drivers, deadman, soft limits, e-stop and its stop categories,
//! stops, reset and shutdown.

use motion_drivers::Driver;
use motion_drivers::{Goal, GoalError};
use motion_ipc::{AxisMode, ClientId, FaultCode, Reason};

use crate::Engine;
use crate::axis::{Fault, fault_code};
use crate::config::EstopCategory;

/// Below this speed (units/s) a stopping axis whose board says it stands still holds.
const STANDSTILL_FRACTION_OF_MAX: f64 = 1e-3;

impl<D: Driver> Engine<D> {
    /// Step 1b: take every channel's state from its driver; refresh ticks, staleness and
    /// driver fault transitions.
    pub(crate) fn update_from_drivers(&mut self) {
        let now = self.now;
        for index in 0..self.axes.len() {
            let axis = &self.axes[index];
            let Some(driver) = self.buses[axis.bus].drivers().get(axis.slot) else {
                continue;
            };
            let mut state = driver.channel(axis.channel);
            if !(state.position.is_finite() && state.velocity.is_finite()) {
                // A driver bug must never put NaN into a frame: keep the last good values.
                state.position = axis.state.position;
                state.velocity = axis.state.velocity;
            }
            let status = driver.status();
            let budget = driver.refresh_budget();
            let tick = self.tick;
            let axis = &mut self.axes[index];
            axis.fresh = state.refreshed_at > axis.refreshed_at;
            if axis.fresh {
                axis.refreshed_at = state.refreshed_at;
                axis.last_refresh_tick = tick;
            }
            axis.stale = axis
                .refreshed_at
                .is_none_or(|at| now.saturating_sub(at) > budget);
            axis.state = state;
            let driver_fault = state.fault.or(status.fault).map(fault_code);
            match (axis.fault, driver_fault) {
                (None, Some(code)) => {
                    axis.fault = Some(Fault {
                        code,
                        by_engine: false,
                        value: 0.0,
                        limit: 0.0,
                        at: now,
                    });
                    self.stop_by_category(index);
                }
                (Some(latched), None)
                    if !latched.by_engine
                        && axis.refreshed_at.is_some_and(|at| at > latched.at) =>
                {
                    // The cause is gone and fresh data arrived: the axis stays stopped
                    // and needs a new command.
                    axis.fault = None;
                }
                (Some(latched), Some(code)) if !latched.by_engine => {
                    axis.fault = Some(Fault { code, ..latched });
                }
                _ => {}
            }
        }
    }

    /// Step 4: deadman expiry, soft limits of open-loop goals, stopping → hold (or off),
    /// homing done.
    pub(crate) fn run_safety(&mut self) {
        let now = self.now;
        for index in 0..self.axes.len() {
            let axis = &self.axes[index];
            if axis.deadman_at.is_some_and(|at| now >= at) {
                self.stop_axis(index, false);
                self.axes[index].deadman_expired = true;
                self.counters.deadman_stops += 1;
                continue;
            }
            let open_loop = matches!(
                axis.mode,
                AxisMode::Velocity | AxisMode::RampVelocity | AxisMode::Power
            );
            if open_loop && !axis.stale {
                let position = axis.position();
                let velocity = axis.velocity();
                let reach = axis.stopping_distance();
                let heading_up = velocity > 0.0 || (velocity == 0.0 && axis.target > 0.0);
                let heading_down = velocity < 0.0 || (velocity == 0.0 && axis.target < 0.0);
                if (heading_up && position + reach >= axis.max)
                    || (heading_down && position - reach <= axis.min)
                {
                    self.stop_axis(index, false);
                    self.counters.limit_stops += 1;
                    continue;
                }
            }
            let axis = &mut self.axes[index];
            let still = !axis.state.moving
                && axis.velocity().abs() <= axis.max_velocity * STANDSTILL_FRACTION_OF_MAX;
            match axis.mode {
                AxisMode::Stopping if still && axis.off_after_stop => {
                    let _ = self.off_axis(index);
                }
                // Not before the board has reported the axis at all: a hold at the
                // position of an axis never heard from (0) would be a following error at
                // its first report (a Trinamic pack that restored its positions from
                // EEPROM, or kept them while the server restarted).
                AxisMode::Stopping if still && axis.refreshed_at.is_some() => {
                    axis.mode = AxisMode::Hold;
                    axis.target = axis.position();
                    axis.arrived = true;
                }
                AxisMode::Homing if still && axis.state.homed => {
                    axis.mode = AxisMode::Hold;
                    axis.target = axis.position();
                    axis.arrived = true;
                    axis.goal_owner = ClientId::NONE;
                }
                _ => {}
            }
        }
    }

    /// Decelerates axis `index` at its max acceleration and holds. An axis the engine
    /// believes off and at rest is left alone unless `force` (start-up and shutdown stops
    /// reach every channel, whatever the engine believed).
    pub(crate) fn stop_axis(&mut self, index: usize, force: bool) {
        let now = self.now;
        let Some(axis) = self.axes.get(index) else {
            return;
        };
        let decel = axis.magnitude_to_counts(axis.max_accel);
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let was_off = axis.mode == AxisMode::Off;
        let stopped = match self.buses[bus].driver_mut(slot) {
            Some(driver) if force || !was_off || axis.state.moving => {
                driver.set_goal(now, channel, Goal::Stop { decel }).is_ok()
            }
            _ => false,
        };
        if stopped {
            self.goal_set(index);
        }
        let axis = &mut self.axes[index];
        axis.mode = if stopped {
            AxisMode::Stopping
        } else if was_off {
            AxisMode::Off
        } else {
            AxisMode::Hold
        };
        axis.target = axis.position();
        axis.arrived = true;
        axis.deadman_at = None;
        axis.goal_owner = ClientId::NONE;
        axis.off_after_stop = false;
        axis.group = None;
        axis.held = None;
        if stopped {
            axis.switched_off = false;
        }
    }

    /// De-energises axis `index` (its motor coasts).
    pub(crate) fn off_axis(&mut self, index: usize) -> Result<(), GoalError> {
        let now = self.now;
        let axis = &self.axes[index];
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let driver = self.buses[bus].driver_mut(slot).ok_or(GoalError::Offline)?;
        driver.set_goal(now, channel, Goal::Off)?;
        self.goal_set(index);
        let axis = &mut self.axes[index];
        axis.mode = AxisMode::Off;
        axis.target = axis.position();
        axis.deadman_at = None;
        axis.goal_owner = ClientId::NONE;
        axis.off_after_stop = false;
        axis.switched_off = true;
        axis.group = None;
        Ok(())
    }

    /// Stops axis `index` the way its e-stop category says: hold (category 2), stop then
    /// off (category 1), off at once (category 0). A board that cannot de-energise holds.
    pub(crate) fn stop_by_category(&mut self, index: usize) {
        let Some(axis) = self.axes.get(index) else {
            return;
        };
        match axis.estop {
            EstopCategory::Hold => self.stop_axis(index, false),
            EstopCategory::StopOff => {
                self.stop_axis(index, false);
                let axis = &mut self.axes[index];
                if axis.mode == AxisMode::Stopping {
                    axis.off_after_stop = true;
                } else if self.off_axis(index).is_err() {
                    self.stop_axis(index, false);
                }
            }
            EstopCategory::Off => {
                if self.off_axis(index).is_err() {
                    self.stop_axis(index, false);
                }
            }
        }
    }

    /// Latches an engine fault on axis `index` and stops it by its category.
    pub(crate) fn fault_axis(&mut self, index: usize, code: FaultCode, value: f64, limit: f64) {
        let now = self.now;
        let Some(axis) = self.axes.get_mut(index) else {
            return;
        };
        axis.fault = Some(Fault {
            code,
            by_engine: true,
            value,
            limit,
            at: now,
        });
        self.counters.faults += 1;
        self.stop_by_category(index);
    }

    /// E-stop: latch, stop every axis by its category, outputs to their safe states.
    pub(crate) fn estop_all(&mut self) {
        self.estop = true;
        for index in 0..self.axes.len() {
            self.stop_by_category(index);
            self.axes[index].estopped = true;
        }
        self.outputs_to_safe_state();
    }

    /// Stops every axis and latches `fault` on each (e.g. too many overruns); a reset
    /// clears it.
    pub fn stop_all_with_fault(&mut self, fault: FaultCode) {
        for index in 0..self.axes.len() {
            self.fault_axis(index, fault, 0.0, 0.0);
        }
    }

    /// Clears the e-stop latch, deadman expiries and the latched faults whose cause is
    /// gone; the targets of axes without a running goal become their current positions
    /// (nothing resumes). Claims are not touched: a claim ends only by release, by its
    /// holder's death or departure, or by lease expiry — never by someone's reset. An axis
    /// with a running goal (nothing was latched on it) keeps its goal and its owner.
    pub(crate) fn reset(&mut self) -> Reason {
        if self.shutting_down {
            return Reason::ShuttingDown;
        }
        self.estop = false;
        for axis in &mut self.axes {
            axis.estopped = false;
            axis.deadman_expired = false;
            let position = axis.position();
            let cause_gone = match axis.fault {
                None => true,
                Some(fault) if !fault.by_engine => axis.state.fault.is_none(),
                Some(fault) => match fault.code {
                    FaultCode::Overspeed => axis.velocity().abs() <= fault.limit,
                    FaultCode::LimitExceeded => {
                        let tolerance = axis.following_error;
                        position >= axis.min - tolerance && position <= axis.max + tolerance
                    }
                    _ => true,
                },
            };
            if cause_gone {
                axis.fault = None;
            }
            axis.overspeed_samples = 0;
            if axis.has_active_goal() {
                continue;
            }
            axis.target = position;
            axis.arrived = true;
            if axis.mode != AxisMode::Off && axis.mode != AxisMode::Stopping {
                axis.mode = AxisMode::Hold;
            }
        }
        for signal in &mut self.signals {
            signal.safe_applied = false;
        }
        Reason::Accepted
    }

    /// Stops every configured axis whatever mode the engine believed (an axis it believed
    /// off is switched off again), outputs to their safe states, and refuses new motion
    /// commands (for SIGINT/SIGTERM). Wait for [`all_at_rest`](Self::all_at_rest) with
    /// further steps.
    pub fn begin_shutdown(&mut self) {
        self.shutting_down = true;
        for index in 0..self.axes.len() {
            if self.axes[index].mode == AxisMode::Off && self.off_axis(index).is_ok() {
                continue;
            }
            self.stop_axis(index, true);
        }
        self.outputs_to_safe_state();
    }
}
