//! Safety: faults from drivers, deadman, soft limits, e-stop, stops.

use motion_drivers::Goal;
use motion_ipc::{AxisMode, ClientId, FaultCode, Reason};

use crate::Engine;
use crate::axis::fault_code;

/// Below this speed (units/s) a stopping axis whose board says it stands still holds.
const STANDSTILL_FRACTION_OF_MAX: f64 = 1e-3;

impl Engine {
    /// Step 1: take every channel's state from its driver; refresh ticks, staleness and
    /// fault transitions.
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
            if state.refreshed_at > axis.refreshed_at {
                axis.refreshed_at = state.refreshed_at;
                axis.last_refresh_tick = tick;
            }
            axis.stale = axis
                .refreshed_at
                .is_none_or(|at| now.saturating_sub(at) > budget);
            axis.state = state;
            let driver_fault = state.fault.or(status.fault).map(fault_code);
            match (axis.fault, driver_fault) {
                (None, Some(fault)) => {
                    axis.fault = Some(fault);
                    axis.fault_at = now;
                    self.stop_axis(index, None);
                }
                (Some(latched), None)
                    if latched != FaultCode::Overrun
                        && axis.refreshed_at.is_some_and(|at| at > axis.fault_at) =>
                {
                    // The cause is gone and fresh data arrived: the axis stays stopped
                    // and needs a new command.
                    axis.fault = None;
                }
                (Some(_), Some(fault)) => axis.fault = Some(fault),
                _ => {}
            }
        }
    }

    /// Step 3: deadman expiry, soft limits, stopping → hold, homing done.
    pub(crate) fn run_safety(&mut self) {
        let now = self.now;
        for index in 0..self.axes.len() {
            let axis = &self.axes[index];
            if axis.deadman_at.is_some_and(|at| now >= at) {
                self.stop_axis(index, None);
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
                    self.stop_axis(index, None);
                    self.counters.limit_stops += 1;
                    continue;
                }
            }
            let axis = &mut self.axes[index];
            let still = !axis.state.moving
                && axis.velocity().abs() <= axis.max_velocity * STANDSTILL_FRACTION_OF_MAX;
            match axis.mode {
                AxisMode::Stopping if still => {
                    axis.mode = AxisMode::Hold;
                    axis.target = axis.position();
                }
                AxisMode::Homing if still && axis.state.homed => {
                    axis.mode = AxisMode::Hold;
                    axis.target = axis.position();
                    axis.goal_owner = ClientId::NONE;
                }
                _ => {}
            }
        }
    }

    /// Decelerates axis `index` at its max acceleration and holds; `fault` latches an
    /// engine fault (cleared only by reset).
    pub(crate) fn stop_axis(&mut self, index: usize, fault: Option<FaultCode>) {
        let now = self.now;
        let Some(axis) = self.axes.get(index) else {
            return;
        };
        let decel = axis.magnitude_to_counts(axis.max_accel);
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let was_off = axis.mode == AxisMode::Off;
        let stopped = match self.buses[bus].driver_mut(slot) {
            Some(driver) if !was_off || axis.state.moving => {
                driver.set_goal(now, channel, Goal::Stop { decel }).is_ok()
            }
            _ => false,
        };
        let axis = &mut self.axes[index];
        axis.mode = if stopped {
            AxisMode::Stopping
        } else if was_off {
            AxisMode::Off
        } else {
            AxisMode::Hold
        };
        axis.target = axis.position();
        axis.deadman_at = None;
        axis.goal_owner = ClientId::NONE;
        if let Some(fault) = fault {
            axis.fault = Some(fault);
            axis.fault_at = now;
        }
    }

    /// E-stop: latch, and stop every axis.
    pub(crate) fn estop_all(&mut self) {
        self.estop = true;
        for index in 0..self.axes.len() {
            self.stop_axis(index, None);
            self.axes[index].estopped = true;
        }
    }

    /// Stops every axis and latches `fault` on each (e.g. too many overruns); a reset
    /// clears it.
    pub fn stop_all_with_fault(&mut self, fault: FaultCode) {
        for index in 0..self.axes.len() {
            self.stop_axis(index, Some(fault));
        }
    }

    /// Clears the e-stop latch and engine-latched faults; targets become the current
    /// positions (nothing resumes).
    pub(crate) fn reset(&mut self) -> Reason {
        if self.shutting_down {
            return Reason::ShuttingDown;
        }
        self.estop = false;
        for axis in &mut self.axes {
            axis.estopped = false;
            axis.deadman_expired = false;
            let driver_fault = axis.state.fault.is_some();
            if !driver_fault {
                axis.fault = None;
            }
            axis.target = axis.position();
            if axis.mode != AxisMode::Off && axis.mode != AxisMode::Stopping {
                axis.mode = AxisMode::Hold;
            }
        }
        Reason::Accepted
    }
}
