//! [`JogGuard`]: a velocity or power goal that lives as long as a value in your program.
//!
//! The server stops velocity and power goals that are not renewed within its deadman
//! (`command_timeout_ms` in [`ServerInfo`](motion_ipc::ServerInfo)). A guard renews its goal
//! every third of that time whenever the program calls into the client (any read, wait or
//! command: [`Client::next_frame`], [`Client::latest`], [`Client::for_each_frame`], waits)
//! or calls [`Client::keep_alive`]. A program that stops calling into the client lets the
//! deadman stop the axis; that is the point. Dropping the guard stops the axis at once.
//!
//! A guard fails safe when the server restarts: it never renews its goal on the new server
//! (which started every axis stopped), reports [`ClientError::ServerRestarted`] from
//! [`JogGuard::check`], [`JogGuard::set`] and [`JogGuard::stop`], and sends nothing when
//! dropped. A renewal that reached a new server before the client could know is stopped at
//! once (see [`Client::command`]).

use core::fmt;
use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{CommandKind, Reason};

use crate::{Accepted, Client, ClientError};

/// Shortest renewal period, whatever the deadman.
const MIN_REFRESH: Duration = Duration::from_millis(5);

#[derive(Debug, Clone, Copy)]
struct JogEntry {
    id: u64,
    axis: u32,
    kind: CommandKind,
    values: [f64; 3],
    last_sent: Instant,
    refused: Option<Reason>,
    /// The server restart count when the goal was started.
    epoch: u64,
}

/// The live guards of one client.
#[derive(Debug, Default)]
pub(crate) struct JogTable {
    next_id: u64,
    entries: Vec<JogEntry>,
    /// Renewing right now (a renewal's own reads must not renew again).
    busy: bool,
}

impl<S: Service> Client<S> {
    /// How often guards renew their goals; `None` when the server has no deadman.
    pub(crate) fn jog_refresh_period(&self) -> Option<Duration> {
        let timeout_ms = self
            .info
            .current()
            .map_or(0, |info| info.command_timeout_ms);
        (timeout_ms > 0)
            .then(|| (Duration::from_millis(u64::from(timeout_ms)) / 3).max(MIN_REFRESH))
    }

    /// `remaining`, shortened so that a sleeping client wakes in time to renew its guards.
    pub(crate) fn jog_wait_cap(&self, remaining: Duration) -> Duration {
        let table = self.jogs.borrow();
        let Some(period) = self.jog_refresh_period() else {
            return remaining;
        };
        let now = Instant::now();
        let epoch = self.session.epoch();
        table
            .entries
            .iter()
            .filter(|entry| entry.refused.is_none() && entry.epoch == epoch)
            .map(|entry| (entry.last_sent + period).saturating_duration_since(now))
            .fold(remaining, Duration::min)
    }

    /// Renews every guard whose renewal is due. Called by every read and wait.
    pub(crate) fn service_jogs(&self) {
        let Some(period) = self.jog_refresh_period() else {
            return;
        };
        {
            let mut table = self.jogs.borrow_mut();
            if table.busy || table.entries.is_empty() {
                return;
            }
            table.busy = true;
        }
        // A restart seen here ends every guard before anything is sent.
        let _ = self.refresh_info();
        let now = Instant::now();
        let due: Vec<JogEntry> = self
            .jogs
            .borrow()
            .entries
            .iter()
            .filter(|entry| entry.refused.is_none() && now >= entry.last_sent + period)
            .copied()
            .collect();
        for entry in due {
            if entry.epoch != self.session.epoch() {
                continue;
            }
            let result = self.command(entry.axis, entry.kind, entry.values);
            self.note_renewal(
                entry.id,
                result.as_ref().err().and_then(ClientError::reason),
            );
        }
        self.jogs.borrow_mut().busy = false;
    }

    fn note_renewal(&self, id: u64, refused: Option<Reason>) {
        let mut table = self.jogs.borrow_mut();
        if let Some(entry) = table.entries.iter_mut().find(|entry| entry.id == id) {
            entry.last_sent = Instant::now();
            entry.refused = refused;
        }
    }

    /// Renews every jog guard that is due, without reading anything. Call it from a loop
    /// that does not otherwise call into the client.
    pub fn keep_alive(&self) {
        self.service_jogs();
    }
}

/// A running jog (velocity or power goal) that stops its axis when dropped.
/// Made by [`Axis::jog`](crate::Axis::jog) and [`Axis::power_guarded`](crate::Axis::power_guarded).
#[must_use = "dropping the guard stops the axis at once"]
pub struct JogGuard<'c, S: Service> {
    client: &'c Client<S>,
    id: u64,
    axis: u32,
    active: bool,
}

impl<S: Service> fmt::Debug for JogGuard<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("JogGuard")
            .field("axis", &self.axis)
            .field("active", &self.active)
            .finish_non_exhaustive()
    }
}

impl<'c, S: Service> JogGuard<'c, S> {
    pub(crate) fn start(
        client: &'c Client<S>,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<Self, ClientError> {
        client.command(axis, kind, values)?;
        let epoch = client.session.epoch();
        let mut table = client.jogs.borrow_mut();
        table.next_id += 1;
        let id = table.next_id;
        table.entries.push(JogEntry {
            id,
            axis,
            kind,
            values,
            last_sent: Instant::now(),
            refused: None,
            epoch,
        });
        Ok(Self {
            client,
            id,
            axis,
            active: true,
        })
    }

    /// The axis index.
    pub fn axis(&self) -> u32 {
        self.axis
    }

    /// The restart that ended this guard's goal, if the server restarted since it started.
    fn lost_to(&self) -> Option<ClientError> {
        let epoch = self.entry()?.epoch;
        if epoch == self.client.session.epoch() {
            return None;
        }
        self.client
            .session
            .last_restart()
            .map(ClientError::ServerRestarted)
    }

    fn entry(&self) -> Option<JogEntry> {
        self.client
            .jogs
            .borrow()
            .entries
            .iter()
            .find(|entry| entry.id == self.id)
            .copied()
    }

    /// `Ok` while the goal runs: [`ClientError::ServerRestarted`] once the server
    /// restarted (the goal died with it and is never renewed on the new server),
    /// [`ClientError::Refused`] once the server refused a renewal.
    pub fn check(&self) -> Result<(), ClientError> {
        let _ = self.client.refresh_info();
        if let Some(error) = self.lost_to() {
            return Err(error);
        }
        match self.refused() {
            Some(reason) => Err(ClientError::Refused {
                kind: "renewal",
                target: self
                    .client
                    .target_label(motion_ipc::Target::Axis, self.axis),
                reason,
                tick: 0,
                detail: None,
            }),
            None => Ok(()),
        }
    }

    /// Changes the jog's velocity (or power) and sends it now.
    pub fn set(&self, value: f64) -> Result<Accepted, ClientError> {
        let _ = self.client.refresh_info();
        if let Some(error) = self.lost_to() {
            return Err(error);
        }
        let entry = {
            let mut table = self.client.jogs.borrow_mut();
            let entry = table.entries.iter_mut().find(|entry| entry.id == self.id);
            entry.map(|entry| {
                entry.values[0] = value;
                *entry
            })
        };
        // The entry lives as long as the guard: only `finish` (stop or drop, both taking
        // the guard) removes it.
        let entry = entry.expect("a jog guard's entry lives as long as the guard");
        let result = self.client.command(entry.axis, entry.kind, entry.values);
        self.client
            .note_renewal(self.id, result.as_ref().err().and_then(ClientError::reason));
        result
    }

    /// The reason the server gave when it last refused a renewal (e-stop, claim, limit);
    /// once refused, the guard stops renewing and the axis is stopped by the server.
    pub fn refused(&self) -> Option<Reason> {
        self.entry().and_then(|entry| entry.refused)
    }

    /// Stops the axis and returns the server's answer to the stop. After a server restart
    /// nothing is sent (the new server never ran this goal) and the restart is returned.
    pub fn stop(mut self) -> Result<Accepted, ClientError> {
        self.finish()
    }

    fn finish(&mut self) -> Result<Accepted, ClientError> {
        self.active = false;
        let _ = self.client.refresh_info();
        if let Some(error) = self.lost_to() {
            self.client
                .jogs
                .borrow_mut()
                .entries
                .retain(|entry| entry.id != self.id);
            return Err(error);
        }
        self.client
            .jogs
            .borrow_mut()
            .entries
            .retain(|entry| entry.id != self.id);
        self.client.command(self.axis, CommandKind::Stop, [0.0; 3])
    }
}

impl<S: Service> Drop for JogGuard<'_, S> {
    fn drop(&mut self) {
        if self.active {
            // Nothing to report to from here; the deadman is the fallback if this is lost.
            // After a restart, finish sends nothing.
            let _ = self.finish();
        }
    }
}
