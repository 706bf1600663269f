//! What the driver does with an answer, or with its absence.

use core::time::Duration;

use tmcpack::{DEFAULT_PACKET_TIMEOUT, Reply};

use super::startup::Quiesce;
use super::wire::{Expect, Purpose, Wire};
use super::{MAX_TIMEOUTS, Phase, RESET_CHECK_PERIOD, RETRY_PERIOD, TmcpackDriver};
use motion_drivers::{DeviceFault, Goal};

impl TmcpackDriver {
    pub(super) fn on_timeout(&mut self, now: Duration) {
        // An unanswered `$43` of the start-up: the pack may answer at another rate.
        let probing = matches!(
            self.wire,
            Wire::Awaiting {
                expect: Expect {
                    purpose: Purpose::Startup,
                    ..
                },
                ..
            }
        );
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.timeouts_in_row = self.timeouts_in_row.saturating_add(1);
        // Silence long enough for the pack to abort any partial word (6.1, $41), whatever
        // timeout it has (it may have rebooted to its factory one).
        let abort = self.spacing().max(DEFAULT_PACKET_TIMEOUT);
        self.wire = Wire::Quiet {
            until: now + abort + self.switchover,
        };
        if probing {
            self.probe_next_rate();
        }
        if self.timeouts_in_row < MAX_TIMEOUTS {
            return;
        }
        self.timeouts_in_row = 0;
        self.restart(DeviceFault::NotResponding);
        self.assume_factory_line();
        self.phase = Phase::Identify;
        self.retry_at = now + RETRY_PERIOD;
    }

    pub(super) fn on_reply(
        &mut self,
        now: Duration,
        expect: Expect,
        sent_at: Duration,
        reply: Reply,
    ) {
        self.status.replies = self.status.replies.saturating_add(1);
        self.timeouts_in_row = 0;
        match (reply, expect.purpose) {
            (
                Reply::UnitInfo {
                    firmware,
                    reset,
                    serial,
                    ..
                },
                purpose,
            ) => {
                self.on_unit_info(firmware, reset, serial);
                let rebooted = reset && self.ever_online;
                if rebooted {
                    self.status.resets = self.status.resets.saturating_add(1);
                    self.restart(DeviceFault::Reset);
                    self.assume_factory_line();
                }
                match purpose {
                    Purpose::Startup => self.identified(),
                    _ if rebooted => self.phase = Phase::Survey,
                    _ => self.reset_check_at = now + RESET_CHECK_PERIOD,
                }
            }
            (Reply::Actions { actions }, Purpose::Survey) => {
                for channel in self.channels.iter_mut().flatten() {
                    channel.surveyed(actions.get(usize::from(channel.motor)).copied());
                }
                self.quiesce = Quiesce::new(now, actions, &self.channels);
                self.phase = if self.quiesce.is_some() {
                    Phase::Quiesce
                } else {
                    Phase::Configure(0)
                };
            }
            (
                Reply::Velocity {
                    motor, velocity, ..
                },
                Purpose::Quiesce,
            ) => {
                if let Some(quiesce) = self.quiesce.as_mut() {
                    quiesce.on_velocity(motor, velocity);
                }
            }
            (reply @ Reply::Input { .. }, Purpose::Io) => self.io.on_input(now, reply),
            (Reply::PowerDown { status }, Purpose::PowerDown) => self.on_power_down(now, status),
            (
                Reply::Position {
                    motor,
                    position,
                    action,
                    stopped,
                },
                Purpose::Poll,
            ) => {
                let seq = self.seq;
                let Some(Some(channel)) = self.channels.get_mut(usize::from(motor)) else {
                    return;
                };
                if channel.on_poll(now, seq, sent_at, position, action, stopped) {
                    let decel = channel.cfg.max_accel;
                    // A motor found moving after a (re)start is not ours to keep running;
                    // a failed search is stopped.
                    let _ = channel.plan(Goal::Stop { decel });
                }
            }
            _ => {
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            }
        }
    }

    /// Bytes from the line: the answer to the query in flight, found among them.
    pub(super) fn receive(&mut self, now: Duration, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        if self.can.is_some() {
            self.receive_can(now, bytes);
            return;
        }
        let Wire::Awaiting {
            expect, sent_at, ..
        } = self.wire
        else {
            // A late answer, an echo or noise: nobody asked.
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            return;
        };
        let Some(reply) = self.hunter.push(self.reply_address, expect, bytes) else {
            return;
        };
        if self.hunter.skipped > 0 {
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        }
        // The pack keeps driving the line for the switch-over time after its answer.
        self.wire = Wire::Quiet {
            until: now + self.switchover,
        };
        self.on_reply(now, expect, sent_at, reply);
    }
}
