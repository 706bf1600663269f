//! [`JogGuard`]: a velocity or power goal that lives as long as a value in your program.
//!
//! The server stops velocity and power goals that are not renewed within its deadman
//! (`command_timeout_ms` in [`ServerInfo`](motion_ipc::ServerInfo)). A guard renews its goal
//! every third of that time whenever the program calls into the client (any read, wait or
//! command: [`Client::next_frame`], [`Client::latest`], [`Client::for_each_frame`], waits)
//! or calls [`Client::keep_alive`]. A program that stops calling into the client lets the
//! deadman stop the axis; that is the point. Dropping the guard stops the axis at once.

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
}

/// The live guards of one client.
#[derive(Debug, Default)]
pub(crate) struct JogTable {
    next_id: u64,
    entries: Vec<JogEntry>,
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
        table
            .entries
            .iter()
            .filter(|entry| entry.refused.is_none())
            .map(|entry| (entry.last_sent + period).saturating_duration_since(now))
            .fold(remaining, Duration::min)
    }

    /// Renews every guard whose renewal is due. Called by every read and wait.
    pub(crate) fn service_jogs(&self) {
        let Some(period) = self.jog_refresh_period() else {
            return;
        };
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
            let result = self.command(entry.axis, entry.kind, entry.values);
            self.note_renewal(
                entry.id,
                result.as_ref().err().and_then(ClientError::reason),
            );
        }
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

    /// Changes the jog's velocity (or power) and sends it now.
    pub fn set(&self, value: f64) -> Result<Accepted, ClientError> {
        let entry = {
            let mut table = self.client.jogs.borrow_mut();
            let entry = table.entries.iter_mut().find(|entry| entry.id == self.id);
            entry.map(|entry| {
                entry.values[0] = value;
                *entry
            })
        };
        let Some(entry) = entry else {
            return Err(ClientError::ipc(
                "change a jog",
                "the guard is no longer active",
            ));
        };
        let result = self.client.command(entry.axis, entry.kind, entry.values);
        self.client
            .note_renewal(self.id, result.as_ref().err().and_then(ClientError::reason));
        result
    }

    /// The reason the server gave when it last refused a renewal (e-stop, claim, limit);
    /// once refused, the guard stops renewing and the axis is stopped by the server.
    pub fn refused(&self) -> Option<Reason> {
        self.client
            .jogs
            .borrow()
            .entries
            .iter()
            .find(|entry| entry.id == self.id)
            .and_then(|entry| entry.refused)
    }

    /// Stops the axis and returns the server's answer to the stop.
    pub fn stop(mut self) -> Result<Accepted, ClientError> {
        self.finish()
    }

    fn finish(&mut self) -> Result<Accepted, ClientError> {
        self.active = false;
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
            let _ = self.finish();
        }
    }
}
