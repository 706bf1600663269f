//! What the zenoh transport receives (feature `zenoh`): payload copies with their origin,
//! and the feed of one key expression. Shared by `remote.rs` (which opens feeds) and
//! `received.rs` (which hands their values out), so that neither imports the other.

use core::fmt;
use core::time::Duration;
use std::cell::RefCell;
use std::collections::VecDeque;

use zenoh::handlers::RingChannelHandler;
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;

use crate::{ClientError, RemoteError};

/// A payload received over the network: a copy, with the node id of the server that wrote
/// it.
pub(crate) struct Owned<T> {
    pub(crate) value: Box<T>,
    pub(crate) origin: u128,
}

impl<T: fmt::Debug> fmt::Debug for Owned<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.value.fmt(f)
    }
}

/// The samples of one key expression: a subscription (if the key is published), and
/// values fetched with a query, delivered first.
pub(crate) struct Feed<T> {
    subscriber: Option<Subscriber<RingChannelHandler<Sample>>>,
    peeked: RefCell<Option<Sample>>,
    fetched: RefCell<VecDeque<Owned<T>>>,
    server: String,
    decode: fn(&Sample, &str) -> Result<Owned<T>, ClientError>,
}

impl<T> fmt::Debug for Feed<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Feed")
            .field("subscribed", &self.subscriber.is_some())
            .finish_non_exhaustive()
    }
}

impl<T> Feed<T> {
    /// A feed of `server`'s samples from `subscriber` (`None`: filled only by
    /// [`push`](Self::push)), decoded with `decode`.
    pub(crate) fn new(
        subscriber: Option<Subscriber<RingChannelHandler<Sample>>>,
        server: String,
        decode: fn(&Sample, &str) -> Result<Owned<T>, ClientError>,
    ) -> Self {
        Self {
            subscriber,
            peeked: RefCell::new(None),
            fetched: RefCell::new(VecDeque::new()),
            server,
            decode,
        }
    }

    /// Hands `value` out before anything subscribed.
    pub(crate) fn push(&self, value: Owned<T>) {
        self.fetched.borrow_mut().push_back(value);
    }

    /// The next sample, in order; `None` when nothing waits.
    pub(crate) fn next(&self) -> Result<Option<Owned<T>>, ClientError> {
        if let Some(value) = self.fetched.borrow_mut().pop_front() {
            return Ok(Some(value));
        }
        let Some(subscriber) = &self.subscriber else {
            return Ok(None);
        };
        let sample = match self.peeked.borrow_mut().take() {
            Some(sample) => sample,
            None => match subscriber.try_recv() {
                Ok(Some(sample)) => sample,
                Ok(None) => return Ok(None),
                Err(error) => return Err(RemoteError::zenoh("receive a sample", error).into()),
            },
        };
        (self.decode)(&sample, &self.server).map(Some)
    }

    /// Waits up to `timeout` for a sample; whether one waits now.
    pub(crate) fn wait(&self, timeout: Duration) -> Result<bool, ClientError> {
        if !self.fetched.borrow().is_empty() || self.peeked.borrow().is_some() {
            return Ok(true);
        }
        let Some(subscriber) = &self.subscriber else {
            std::thread::sleep(timeout);
            return Ok(false);
        };
        match subscriber.recv_timeout(timeout) {
            Ok(Some(sample)) => {
                *self.peeked.borrow_mut() = Some(sample);
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(error) => Err(RemoteError::zenoh("wait for a sample", error).into()),
        }
    }
}
