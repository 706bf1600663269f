//! [`ClaimGuard`]: an exclusive claim on an axis or a signal that lives as long as a value
//! in your program.

use core::fmt;

use iceoryx2::service::Service;
use motion_ipc::{CommandKind, Target};

use crate::{Accepted, Client, ClientError};

/// A claim taken by [`Axis::claim_guard`](crate::Axis::claim_guard) or
/// [`Signal::claim_guard`](crate::Signal::claim_guard); released when dropped.
///
/// Fails safe when the server restarts: the claim died with the old server, so the guard
/// reports [`ClientError::ServerRestarted`] from [`ClaimGuard::check`], [`ClaimGuard::renew`]
/// and [`ClaimGuard::release`] and sends nothing to the new server (not even a release).
#[must_use = "dropping the guard releases the claim at once"]
pub struct ClaimGuard<'c, S: Service> {
    client: &'c Client<S>,
    target: Target,
    index: u32,
    epoch: u64,
    active: bool,
}

impl<S: Service> fmt::Debug for ClaimGuard<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ClaimGuard")
            .field("target", &self.target)
            .field("index", &self.index)
            .field("active", &self.active)
            .finish_non_exhaustive()
    }
}

impl<'c, S: Service> ClaimGuard<'c, S> {
    pub(crate) fn take(
        client: &'c Client<S>,
        target: Target,
        index: u32,
    ) -> Result<Self, ClientError> {
        client.command_to(target, index, CommandKind::Claim, [0.0; 3])?;
        Ok(Self {
            client,
            target,
            index,
            epoch: client.session.epoch(),
            active: true,
        })
    }

    /// What is claimed: "axis x", "signal lamp".
    pub fn label(&self) -> String {
        self.client.target_label(self.target, self.index)
    }

    /// `Ok` while the claim can still be held; [`ClientError::ServerRestarted`] once the
    /// server restarted (the claim died with it).
    pub fn check(&self) -> Result<(), ClientError> {
        let _ = self.client.refresh_info();
        if self.client.session.epoch() == self.epoch {
            return Ok(());
        }
        match self.client.session.last_restart() {
            Some(restart) => Err(ClientError::ServerRestarted(restart)),
            None => Ok(()),
        }
    }

    /// Claims again, which renews a claim lease (`[server] claim_lease_ms`); refused when
    /// the claim was lost to another client meanwhile.
    pub fn renew(&self) -> Result<Accepted, ClientError> {
        self.check()?;
        self.client
            .command_to(self.target, self.index, CommandKind::Claim, [0.0; 3])
    }

    /// Gives the claim back and returns the server's answer.
    pub fn release(mut self) -> Result<Accepted, ClientError> {
        self.finish()
    }

    fn finish(&mut self) -> Result<Accepted, ClientError> {
        self.active = false;
        self.check()?;
        self.client
            .command_to(self.target, self.index, CommandKind::Release, [0.0; 3])
    }
}

impl<S: Service> Drop for ClaimGuard<'_, S> {
    fn drop(&mut self) {
        if self.active {
            // Claims of a client that is gone are voided by the server anyway.
            let _ = self.finish();
        }
    }
}
