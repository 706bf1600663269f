//! What the engine asks of one channel of a board: [`Goal`].
//!
//! Goals are in the board's own counts (microsteps, quadrature transitions), already
//! converted from axis units by the engine with the axis's `counts_per_unit`, and already
//! checked against the axis limits. A driver converts counts into its board's scales (the
//! Trinamic velocity formula, QuadQuad2Drv shl-12 fields) and rejects what its board cannot
//! do with [`GoalError::Unsupported`], never silently.

use core::fmt;

/// One channel's goal. All quantities in counts, counts/s, counts/s².
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub enum Goal {
    /// Stop driving: motor off / de-energised, free to turn.
    Off,
    /// Decelerate at `decel` (> 0) to standstill, then actively hold where it stopped.
    Stop {
        /// Deceleration, counts/s².
        decel: f64,
    },
    /// Open-loop power, `fraction` of full scale in −1.0..=1.0.
    Power {
        /// Fraction of full scale.
        fraction: f64,
    },
    /// Hand `counts` straight to the board's position controller (PID, PI or its own
    /// default profile).
    Position {
        /// Target, counts.
        counts: f64,
    },
    /// Run at `velocity`, reaching it with acceleration `accel` (> 0) where the board
    /// ramps.
    Velocity {
        /// Velocity, counts/s.
        velocity: f64,
        /// Acceleration, counts/s².
        accel: f64,
    },
    /// Go to `counts` along a profile limited to `velocity` (> 0) and `accel` (> 0).
    RampPosition {
        /// Target, counts.
        counts: f64,
        /// Velocity limit, counts/s.
        velocity: f64,
        /// Acceleration limit, counts/s².
        accel: f64,
    },
    /// Reference search at `velocity` (> 0, direction per the board's configuration).
    Home {
        /// Search velocity, counts/s.
        velocity: f64,
    },
    /// Declare the current position to be `counts` (no motion).
    SetPosition {
        /// The new current position, counts.
        counts: f64,
    },
}

impl Goal {
    /// The kind of this goal.
    pub const fn kind(&self) -> GoalKind {
        match self {
            Self::Off => GoalKind::Off,
            Self::Stop { .. } => GoalKind::Stop,
            Self::Power { .. } => GoalKind::Power,
            Self::Position { .. } => GoalKind::Position,
            Self::Velocity { .. } => GoalKind::Velocity,
            Self::RampPosition { .. } => GoalKind::RampPosition,
            Self::Home { .. } => GoalKind::Home,
            Self::SetPosition { .. } => GoalKind::SetPosition,
        }
    }
}

/// The kinds of [`Goal`].
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum GoalKind {
    /// [`Goal::Off`].
    Off = 0,
    /// [`Goal::Stop`].
    Stop = 1,
    /// [`Goal::Power`].
    Power = 2,
    /// [`Goal::Position`].
    Position = 3,
    /// [`Goal::Velocity`].
    Velocity = 4,
    /// [`Goal::RampPosition`].
    RampPosition = 5,
    /// [`Goal::Home`].
    Home = 6,
    /// [`Goal::SetPosition`].
    SetPosition = 7,
}

impl GoalKind {
    /// Every kind.
    pub const ALL: [Self; 8] = [
        Self::Off,
        Self::Stop,
        Self::Power,
        Self::Position,
        Self::Velocity,
        Self::RampPosition,
        Self::Home,
        Self::SetPosition,
    ];
}

/// The smallest nonzero velocity and acceleration a board can represent on one channel, in
/// device counts: a goal slower than that would be rounded to nothing or up to the board's
/// step (running faster or accelerating harder than asked), so the engine refuses it. `0.0`:
/// no such floor (a continuous profile, or no velocity goal at all).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RateFloor {
    /// Of a velocity goal and of a reference search, counts/s.
    pub velocity: f64,
    /// Of a position profile's velocity (`RampPosition`), counts/s: finer on a board whose
    /// profile takes another unit (the QuadQuad2Drv's shl 12), coarser on one whose
    /// profile starts higher (the QSB's MD STEP RATE).
    pub profile_velocity: f64,
    /// Counts/s².
    pub accel: f64,
}

impl RateFloor {
    /// No floor.
    pub const NONE: Self = Self {
        velocity: 0.0,
        profile_velocity: 0.0,
        accel: 0.0,
    };
}

/// A set of [`GoalKind`]s: what a channel supports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct GoalKinds(u16);

impl GoalKinds {
    /// The empty set.
    pub const NONE: Self = Self(0);

    /// The set of `kinds`.
    pub const fn of(kinds: &[GoalKind]) -> Self {
        let mut bits = 0u16;
        let mut index = 0;
        while index < kinds.len() {
            bits |= 1 << kinds[index] as u8;
            index += 1;
        }
        Self(bits)
    }

    /// Whether `kind` is in the set.
    pub const fn contains(self, kind: GoalKind) -> bool {
        self.0 & (1 << kind as u8) != 0
    }
}

/// Why a driver refused a goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GoalError {
    /// The board cannot do this kind of goal on this channel.
    Unsupported(GoalKind),
    /// No such channel on the board.
    NoSuchChannel(usize),
    /// A value the board cannot represent (beyond its register range after conversion).
    OutOfBoardRange(GoalKind),
    /// The board is offline (not answering, or its link is down).
    Offline,
    /// The board is still starting (probing, configuring, its start-up stop not yet
    /// acknowledged).
    Starting,
    /// No such I/O pin on the board, or not one the driver was configured to drive.
    NoSuchPin(crate::Pin),
}

impl fmt::Display for GoalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unsupported(kind) => write!(f, "the board cannot do a {kind:?} goal"),
            Self::NoSuchChannel(channel) => write!(f, "the board has no channel {channel}"),
            Self::OutOfBoardRange(kind) => {
                write!(
                    f,
                    "a {kind:?} value is outside what the board can represent"
                )
            }
            Self::Offline => f.write_str("the board is offline"),
            Self::Starting => f.write_str("the board is starting"),
            Self::NoSuchPin(pin) => write!(f, "the board has no output pin #{}", pin.0),
        }
    }
}

impl std::error::Error for GoalError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn goal_kinds_set_contains_exactly_its_members() {
        let set = GoalKinds::of(&[GoalKind::Off, GoalKind::Home]);
        for kind in GoalKind::ALL {
            assert_eq!(
                set.contains(kind),
                matches!(kind, GoalKind::Off | GoalKind::Home)
            );
        }
        assert!(!GoalKinds::NONE.contains(GoalKind::Off));
        assert_eq!(Goal::Home { velocity: 1.0 }.kind(), GoalKind::Home);
    }
}
