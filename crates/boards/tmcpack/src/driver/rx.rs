//! What the driver does with an answer, a late answer, or the absence of one.
//!
//! **Not answering** (a verdict, [`DeviceFault::NotResponding`]): only when at least
//! [`MAX_TIMEOUTS`] requests in a row went unanswered *and* the first of them was written
//! at least `silence_ms` before (module docs). A pack that is silent for less — its
//! host or its firmware held the answers for 50, 100 or 200 ms and then answered again —
//! keeps its configuration and its goals: its late answers are dropped (module `late`) and
//! the next one it gives ends the silence. The verdict names the evidence: how many
//! requests, since when, and the last one with its write stamp, its due time and how far
//! past it the link was heard.
//!
//! **Reset** ([`DeviceFault::Reset`]): only on a `$43` answer with the reset flag set
//! ("during first read out 1, afterwards 0", manual 8.6) from a pack that had been online;
//! the verdict names that answer.

use core::time::Duration;

use tmcpack::{Command, FRAME_LEN, Reply, ReplyFrame};

use super::hunter::{Found, Want};
use super::startup::Quiesce;
use super::wire::{Expect, Purpose, Wire};
use super::{MAX_TIMEOUTS, Phase, RESET_CHECK_PERIOD, RETRY_PERIOD, TmcpackDriver};
use motion_drivers::{DeviceFault, Goal, Seconds, Verdict};

/// The last request that went unanswered, for the evidence of a verdict.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(crate) struct Unanswered {
    expect: Expect,
    written: Duration,
    due: Duration,
}

/// A query as the evidence names it: `` `$20` motor 2 ``, `` `$30` channel 7 ``, `` `$43` ``.
struct Asked(Expect);

impl core::fmt::Display for Asked {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "`${:02X}`", self.0.command.code())?;
        match (self.0.command, self.0.motor) {
            (Command::ReadInput, Some(channel)) => write!(f, " channel {channel}"),
            (_, Some(motor)) => write!(f, " motor {motor}"),
            (_, None) => Ok(()),
        }
    }
}

impl TmcpackDriver {
    /// The query in flight went unanswered: its window ended and the link was heard past
    /// it (`handle_timeout`).
    pub(super) fn on_timeout(&mut self, now: Duration) {
        let Wire::Awaiting {
            expect,
            sent_at,
            deadline,
            ..
        } = self.wire
        else {
            return;
        };
        // An unanswered query at start-up: the pack may answer at another rate.
        let probing = self.phase == Phase::Identify;
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.timeouts_in_row = self.timeouts_in_row.saturating_add(1);
        if self.timeouts_in_row == 1 {
            self.silent_since = sent_at;
        }
        // Manual 6.1: a word torn on the line is dropped by the pack once its packet timeout
        // ($41, as programmed, of every pack on the bus) has passed; and should the answer
        // have ended just before the window did, the pack drives the line for its
        // switch-over time after it.
        let quiet = self.spacing().max(self.switchover);
        self.wire = Wire::Quiet { until: now + quiet };
        self.remember_late(now, &expect);
        if probing {
            self.probe_next_rate();
        }
        if self.declared_not_answering() {
            // Asked again every retry period.
            self.retry_at = now + RETRY_PERIOD;
        }
        self.unanswered = Some(Unanswered {
            expect,
            written: sent_at,
            due: deadline,
        });
        self.judge_silence(now);
    }

    /// Declares the pack not answering when at least [`MAX_TIMEOUTS`] requests went
    /// unanswered in a row and the first was written `silence_ms` ago or more, with no
    /// query awaited now (also when no query could go: every answer could have been taken
    /// for a late one). Once per silence.
    pub(super) fn judge_silence(&mut self, now: Duration) {
        if matches!(self.wire, Wire::Awaiting { .. }) || self.timeouts_in_row < MAX_TIMEOUTS {
            return;
        }
        let silent = now.saturating_sub(self.silent_since);
        if silent < self.not_answering {
            return;
        }
        if !self.declared_not_answering() {
            let heard = self.stamps.judged(now);
            if let Some(last) = self.unanswered {
                self.status.declare(Verdict::new(
                    DeviceFault::NotResponding,
                    now,
                    format_args!(
                        "{} requests unanswered in a row since {} ({} ms silent); the last, {}, written at {}, due by {}, the link heard until {} ({} ms past due)",
                        self.timeouts_in_row,
                        Seconds(self.silent_since),
                        silent.as_millis(),
                        Asked(last.expect),
                        Seconds(last.written),
                        Seconds(last.due),
                        Seconds(heard),
                        heard.saturating_sub(last.due).as_millis(),
                    ),
                ));
            }
            self.restart(DeviceFault::NotResponding);
            // Beyond the bound its answers are not waited for any more.
            self.late.clear_own();
        }
        // Asked again from now on, every retry period.
        self.timeouts_in_row = 0;
        self.assume_unknown_line();
        self.phase = Phase::Identify;
        self.retry_at = now + RETRY_PERIOD;
    }

    /// A `$43` answer at `now` says the pack booted: the answer to the query written at
    /// `asked`, or — `late` — to the one that went unanswered at `asked` (module `late`).
    fn on_reset_flag(&mut self, now: Duration, asked: Duration, late: bool) {
        self.status.resets = self.status.resets.saturating_add(1);
        let last = self.last_answer_at.unwrap_or_default();
        let (which, query) = if late {
            ("late ", "that had gone unanswered at")
        } else {
            ("", "written at")
        };
        self.status.declare(Verdict::new(
            DeviceFault::Reset,
            now,
            format_args!(
                "the {which}`$43` answer at {} to the query {query} {} has the reset flag set (manual 8.6 \"during first read out 1\"): the pack booted after its answer at {}",
                Seconds(now),
                Seconds(asked),
                Seconds(last),
            ),
        ));
        self.restart(DeviceFault::Reset);
        self.assume_unknown_line();
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
        // The pack answers in order: whatever it was asked before came or never will.
        self.late.clear_own();
        let previous = self.last_answer_at.replace(now);
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
                    self.last_answer_at = previous;
                    self.on_reset_flag(now, sent_at, false);
                    self.last_answer_at = Some(now);
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
            // The pack answers: that is all a probe asks.
            (_, Purpose::Probe) => {}
            _ => {
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            }
        }
    }

    /// Bytes from the line: the answer to the query in flight, found among them; words
    /// that begin like a late answer taken out (module `late`).
    pub(super) fn receive(&mut self, now: Duration, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        if self.can.is_some() {
            self.receive_can(now, bytes);
            return;
        }
        let skipped = self.hunter.skipped;
        let unsolicited = !matches!(self.wire, Wire::Awaiting { .. });
        let mut rest = bytes;
        while !rest.is_empty() {
            let (expect, sent_at) = match self.wire {
                Wire::Awaiting {
                    expect, sent_at, ..
                } => (Some(expect), sent_at),
                _ => (None, Duration::ZERO),
            };
            let want = Want {
                reply_address: self.reply_address,
                expect,
                late: &self.late,
                now,
            };
            let (found, used) = self.hunter.push(&want, rest);
            rest = rest.get(used..).unwrap_or_default();
            match (found, expect) {
                (Some(Found::Late(word)), _) => self.on_late_word(now, word),
                (Some(Found::Answer(reply)), Some(expect)) => {
                    // The pack keeps driving the line for the switch-over time after its
                    // answer.
                    self.wire = Wire::Quiet {
                        until: now + self.switchover,
                    };
                    self.on_reply(now, expect, sent_at, reply);
                }
                _ => {}
            }
        }
        if self.hunter.skipped != skipped {
            // Noise, an echo, or a word nobody asked for.
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        }
        if unsolicited {
            self.hold_line_after_bytes(now, bytes.len());
        }
    }

    /// `received` bytes came while no answer was awaited (a late answer, noise): someone
    /// drives the line. Nothing goes out before the word they belong to can have ended and
    /// the pack's switch-over hold after it has passed (manual 6.1: "The PACK continues to drive the
    /// line for a pre-set time after transmitting a message"), so that a request never
    /// meets a late answer on the pair.
    fn hold_line_after_bytes(&mut self, now: Duration, received: usize) {
        // The rest of the word the hunter holds a part of; else the rest of a word the
        // bytes just received may have begun.
        let rest = match self.hunter.pending() {
            0 => (FRAME_LEN - received % FRAME_LEN) % FRAME_LEN,
            held => FRAME_LEN.saturating_sub(held),
        };
        let byte = self.word_time / FRAME_LEN as u32;
        let free = now + byte * rest as u32 + self.switchover;
        self.wire = match self.wire {
            Wire::Idle => Wire::Quiet { until: free },
            Wire::Quiet { until } => Wire::Quiet {
                until: until.max(free),
            },
            Wire::Sending { until, number } => Wire::Sending {
                until: until.max(free),
                number,
            },
            // The query in flight: its own answer (or its window) decides.
            awaiting @ Wire::Awaiting { .. } => awaiting,
        };
    }

    /// A word that begins like a late answer came at `now`: counted and dropped. The
    /// driver's own ends the late answers asked before it (the pack answers in order); a
    /// `$43` of its own with the reset flag set still proves a reboot (module `late`).
    pub(super) fn on_late_word(&mut self, now: Duration, word: tmcpack::Word) {
        self.late_replies = self.late_replies.saturating_add(1);
        let head = word.get(..3).unwrap_or_default();
        let others = self.late.matches_other(head, now);
        let Some(own) = self.late.answered_own(head) else {
            return;
        };
        if others {
            return;
        }
        if let Ok(frame) = ReplyFrame::decode(&word)
            && let Reply::UnitInfo {
                firmware,
                reset: true,
                serial,
                ..
            } = frame.reply
        {
            self.on_unit_info(firmware, true, serial);
            if self.ever_online && !self.declared_not_answering() {
                // It was kept from its timeout on for `not_answering`.
                let unanswered = own.until().saturating_sub(self.not_answering);
                self.on_reset_flag(now, unanswered, true);
                self.phase = Phase::Survey;
            }
        }
    }
}
