//! Lines a board runs itself (`Driver::lead_line`): a synchronized straight line from rest
//! is handed, board by board, to the boards that can run it with their own function — the
//! Trinamic pack's `$26` + `$50` linear interpolation for its motors of the group, the
//! QSB-M's own position move — instead of being followed with segments. Each leg is the
//! line's time law on that axis (its peak velocity and acceleration at the set feed); the
//! engine's path still runs every tick and supervises the board against it.
//!
//! | while a board leads | the engine |
//! |---|---|
//! | the board prepares the line (a pack's `$14` / `$26`, the QSB's rate and acceleration) | holds the path at its start; once every such board of the group is ready it starts them all in the same tick, and the path once every start (`$50`, MOVE STEPS + COMMAND 8) has gone out; a board not ready (or started) within [`ARM_TIMEOUT`] is followed with goals instead |
//! | the line runs at its feed | sends that board nothing |
//! | hold (or cancel) | asks the board to pause (`Driver::pause_line`, the QSB-M's COMMAND 6); a board that cannot follows the hold with goals from then on |
//! | resume at the line's feed | asks the paused board to resume (COMMAND 7), else follows with goals |
//! | a feed change, a replacing path | follows with goals from then on (a board's line has one pace) |
//! | the board is measured more than [`LEAD_DRIFT`] of the axis's `path_tolerance` off the path | follows with goals from then on |

use core::time::Duration;

use motion_drivers::{Driver, LINE_RATE_TOLERANCE, LineLeg};
use motion_ipc::MAX_GROUP_AXES;

use crate::Engine;

/// How long the boards of a line may take to prepare it before the engine follows it with
/// goals instead (a pack's `$14` and `$26` per motor: a few words on its bus).
pub(crate) const ARM_TIMEOUT: Duration = Duration::from_millis(500);

/// A board running a line by itself that is measured farther than this share of the
/// axis's `path_tolerance` from the path is followed with goals from then on: its rates in
/// its own units match the path's only to `LINE_RATE_TOLERANCE`, steps may be lost, and
/// goals feed the error back.
pub(crate) const LEAD_DRIFT: f64 = 0.5;

/// Where a line handed to boards is before its path's time moves.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Arming {
    /// Not waiting: the path runs.
    #[default]
    No,
    /// The boards prepare the line (since then).
    Preparing(Duration),
    /// The boards were started; their starts are on their way (since then).
    Starting(Duration),
}

/// Whether a member's board runs the group's line itself.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Lead {
    /// The engine follows the path with goals.
    #[default]
    No,
    /// The board runs the line.
    Running,
    /// The board paused the line and waits to resume it.
    Paused,
}

impl<D: Driver> Engine<D> {
    /// A line that starts from rest at `feed` (> 0): every board that can runs its
    /// members' legs itself. Members that do not move are not handed over.
    pub(crate) fn lead_line(&mut self, group: usize, feed: f64) {
        let now = self.now;
        let g = &mut self.groups[group];
        let count = g.members.len();
        if feed.is_nan() || feed <= 0.0 || count == 0 || g.path.duration() <= 0.0 {
            return;
        }
        if g.members
            .iter()
            .any(|m| self.axes[m.axis].state.moving || self.axes[m.axis].stale)
        {
            return;
        }
        // Each axis's acceleration where the line starts, and its velocity half-way (the
        // peak of a trapezoid or a triangle), at the feed the path runs at.
        let half = g.path.duration() / 2.0;
        // A board's pace off by r arrives r × the line's duration late: at most half the
        // group's goal_time_tolerance, and never more than LINE_RATE_TOLERANCE.
        let duration = g.path.duration() / feed;
        let rate_tolerance =
            (0.5 * g.config.goal_time_tolerance.as_secs_f64() / duration).min(LINE_RATE_TOLERANCE);
        g.path.sample(
            0.0,
            &mut g.then,
            &mut g.then_velocity,
            &mut g.then_acceleration,
        );
        let mut accel = [0.0f64; MAX_GROUP_AXES];
        for (slot, a) in accel.iter_mut().zip(&g.then_acceleration) {
            *slot = a.abs() * feed * feed;
        }
        g.path.sample(
            half,
            &mut g.then,
            &mut g.then_velocity,
            &mut g.then_acceleration,
        );
        for first in 0..count {
            let g = &self.groups[group];
            let head = &self.axes[g.members[first].axis];
            let board = (head.bus, head.slot);
            // Each board once: at its first member.
            if g.members[..first].iter().any(|m| {
                let axis = &self.axes[m.axis];
                (axis.bus, axis.slot) == board
            }) {
                continue;
            }
            let mut legs = [LineLeg {
                channel: 0,
                counts: 0.0,
                velocity: 0.0,
                accel: 0.0,
                rate_tolerance,
            }; MAX_GROUP_AXES];
            let mut slots = [0usize; MAX_GROUP_AXES];
            let mut n = 0;
            for (slot, member) in g.members.iter().enumerate().skip(first) {
                let axis = &self.axes[member.axis];
                let velocity = g.then_velocity.get(slot).map_or(0.0, |v| v.abs() * feed);
                let a = accel.get(slot).copied().unwrap_or(0.0);
                if (axis.bus, axis.slot) != board || velocity <= 0.0 || a <= 0.0 {
                    continue;
                }
                if let (Some(leg), Some(s)) = (legs.get_mut(n), slots.get_mut(n)) {
                    *leg = LineLeg {
                        channel: axis.channel,
                        counts: axis.to_counts(g.path.end()[slot]),
                        velocity: axis.magnitude_to_counts(velocity),
                        accel: axis.magnitude_to_counts(a),
                        rate_tolerance,
                    };
                    *s = slot;
                    n += 1;
                }
            }
            if n == 0 {
                continue;
            }
            let (bus, driver_slot) = board;
            let taken = self.buses[bus]
                .driver_mut(driver_slot)
                .is_some_and(|driver| driver.lead_line(now, &legs[..n]).unwrap_or(false));
            if !taken {
                continue;
            }
            for &slot in &slots[..n] {
                let member = &mut self.groups[group].members[slot];
                member.led = Lead::Running;
                member.sent_at = Some(now);
                let index = member.axis;
                self.goal_set(index);
            }
            self.groups[group].arming = Arming::Preparing(now);
        }
    }

    /// Before the path's time moves on: a line handed to boards starts once every one of
    /// them has it prepared — every board in the same tick — and the path with it once
    /// every board's start has gone out; if a board is not ready (or its start not out)
    /// within [`ARM_TIMEOUT`], the engine follows the line with goals instead. Returns
    /// whether the path may advance this tick.
    pub(crate) fn line_started(&mut self, group: usize) -> bool {
        let now = self.now;
        let (since, preparing) = match self.groups[group].arming {
            Arming::No => return true,
            Arming::Preparing(since) => (since, true),
            Arming::Starting(since) => (since, false),
        };
        let mut led = false;
        let mut waiting = false;
        for member in &self.groups[group].members {
            if member.led == Lead::No {
                continue;
            }
            led = true;
            let axis = &self.axes[member.axis];
            let driver = self.buses[axis.bus].drivers().get(axis.slot);
            waiting |= driver.is_none_or(|driver| {
                if preparing {
                    !driver.line_ready()
                } else {
                    driver.line_starting()
                }
            });
        }
        let timed_out = now.saturating_sub(since) >= ARM_TIMEOUT;
        if led && waiting && !timed_out {
            return false;
        }
        self.groups[group].arming = Arming::No;
        if !led {
            return true;
        }
        if waiting {
            self.follow_led(group);
            return true;
        }
        if !preparing {
            return true;
        }
        let count = self.groups[group].members.len();
        let mut starting = false;
        for first in 0..count {
            let g = &self.groups[group];
            if g.members[first].led == Lead::No {
                continue;
            }
            let head = &self.axes[g.members[first].axis];
            let board = (head.bus, head.slot);
            let seen = g.members[..first].iter().any(|m| {
                let axis = &self.axes[m.axis];
                m.led != Lead::No && (axis.bus, axis.slot) == board
            });
            if !seen && let Some(driver) = self.buses[board.0].driver_mut(board.1) {
                driver.start_line(now);
                starting |= driver.line_starting();
            }
        }
        if starting {
            self.groups[group].arming = Arming::Starting(now);
        }
        !starting
    }

    /// Hold: every board that runs the line pauses it if it can; the others are followed
    /// with goals from now on.
    pub(crate) fn pause_led(&mut self, group: usize) {
        self.each_led(group, |driver, now, channel, lead| match lead {
            Lead::Running if driver.pause_line(now, channel).unwrap_or(false) => Lead::Paused,
            Lead::Paused => Lead::Paused,
            _ => Lead::No,
        });
    }

    /// Resume (at the feed the line was handed over at): every paused board resumes it if
    /// it can; the others are followed with goals.
    pub(crate) fn resume_led(&mut self, group: usize) {
        self.each_led(group, |driver, now, channel, lead| match lead {
            Lead::Paused if driver.resume_line(now, channel).unwrap_or(false) => Lead::Running,
            Lead::Running => Lead::Running,
            _ => Lead::No,
        });
    }

    /// The engine follows every member with goals from now on.
    pub(crate) fn follow_led(&mut self, group: usize) {
        self.each_led(group, |_, _, _, _| Lead::No);
    }

    /// The engine follows the members on `axis`'s board with goals from now on (the others
    /// go on leading: their lines are theirs).
    pub(crate) fn follow_led_board(&mut self, group: usize, axis: usize) {
        let board = (self.axes[axis].bus, self.axes[axis].slot);
        for slot in 0..self.groups[group].members.len() {
            let member = self.groups[group].members[slot];
            let on = &self.axes[member.axis];
            if member.led != Lead::No && (on.bus, on.slot) == board {
                let m = &mut self.groups[group].members[slot];
                m.led = Lead::No;
                m.restart(self.now);
            }
        }
    }

    /// `step` decides each led member's next state; a member no longer led is followed
    /// with goals from this tick, as if its motion had just started.
    fn each_led(
        &mut self,
        group: usize,
        mut step: impl FnMut(&mut D, Duration, usize, Lead) -> Lead,
    ) {
        let now = self.now;
        for slot in 0..self.groups[group].members.len() {
            let member = self.groups[group].members[slot];
            if member.led == Lead::No {
                continue;
            }
            let axis = &self.axes[member.axis];
            let (bus, driver_slot, channel) = (axis.bus, axis.slot, axis.channel);
            let next = match self.buses[bus].driver_mut(driver_slot) {
                Some(driver) => step(driver, now, channel, member.led),
                None => Lead::No,
            };
            let m = &mut self.groups[group].members[slot];
            m.led = next;
            if next == Lead::No {
                m.restart(now);
            }
        }
    }
}
