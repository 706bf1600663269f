//! What the board is asked to do for one channel, one step of a goal at a time (the
//! packets each step sends are planned in `plan.rs`).

use core::time::Duration;

/// One step of a goal on the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Step {
    /// Nothing commanded since start-up or a board reset.
    Idle,
    /// Control mode Off.
    Off,
    /// Power mode at ±8191.
    Power(i16),
    /// Position PID towards a target (configured velocity / acceleration limits).
    Position(i32),
    /// Position ramp (velocity and acceleration shl 12).
    Ramp {
        position: i32,
        velocity: u32,
        accel: u32,
    },
    /// Velocity PID, ramped (velocity plain, acceleration shl 12).
    Velocity { velocity: i32, accel: u32 },
    /// A stop as the engine asked for it (deceleration shl 12). It is planned when it is
    /// sent, from the velocity measured then: at standstill it is a [`Step::Hold`], else a
    /// [`Step::StopLift`].
    Stop { accel: u32 },
    /// Stop, first transaction: control mode Off then Velocity PID (the loop starts
    /// afresh), acceleration limit lifted (28 ← 0) and velocity target = the measured
    /// `velocity` with no ramp (36, acceleration 0), so the board's velocity setpoint is
    /// where the motor really runs, not where an earlier goal asked it to run.
    StopLift { accel: u32, velocity: i32 },
    /// Stop, second transaction, at least one board loop period after the first was
    /// answered: ramp that setpoint to 0 at the stop's deceleration (36), which takes
    /// `ramp`; then [`Step::Hold`].
    StopRamp { accel: u32, ramp: Duration },
    /// Position PID holding where the channel is when the step is sent; restores the
    /// acceleration limit.
    Hold,
    /// Counter ← value; holds there unless the motor is off.
    SetCounter(i32),
    /// Home with an edge input already active: move off the switch first.
    HomeBackoff { velocity: i32, accel: u32 },
    /// Home: run towards the switch with the input armed.
    HomeSearch { velocity: i32, accel: u32 },
}

impl Step {
    /// A stop is in progress (planned, lifting or ramping).
    pub(super) const fn stopping(self) -> bool {
        matches!(
            self,
            Self::Stop { .. } | Self::StopLift { .. } | Self::StopRamp { .. }
        )
    }

    /// The step needs the channel's measured data to be sent (velocity or position).
    pub(super) const fn needs_data(self) -> bool {
        matches!(self, Self::Stop { .. } | Self::StopLift { .. } | Self::Hold)
    }

    /// The step keeps the acceleration limit lifted (it is restored by every other step).
    pub(super) const fn keeps_limit_lifted(self) -> bool {
        matches!(self, Self::StopLift { .. } | Self::StopRamp { .. })
    }
}
