//! Samples kept in shared memory: [`Received`] and the newest-sample cache behind
//! [`Client::latest`](crate::Client::latest).

use core::fmt;
use core::ops::Deref;
use std::cell::RefCell;
use std::rc::Rc;

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{PayloadHeader as _, ZeroCopySend};
use iceoryx2::sample::Sample;
use iceoryx2::service::Service;

use crate::ClientError;

/// A payload received from the server, still in shared memory (nothing was copied).
///
/// Cheap to clone (a reference count). While you hold one, the server cannot reuse its
/// memory chunk; the service allows each subscriber only a couple of held samples, so drop
/// it before asking for the next one if you can (holding one while reading the next is fine).
pub struct Received<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    sample: Rc<Sample<S, T, ()>>,
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Clone for Received<S, T> {
    fn clone(&self) -> Self {
        Self {
            sample: Rc::clone(&self.sample),
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Received<S, T> {
    /// The iceoryx2 node id of the process that published it (the server).
    pub fn origin_node(&self) -> u128 {
        self.sample.header().node_id().value()
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Deref for Received<S, T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.sample.payload()
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> fmt::Debug for Received<S, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Received")
            .field(self.sample.payload())
            .finish()
    }
}

/// One subscriber and the newest sample taken from it.
pub(crate) struct LatestCache<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<S, T, ()>,
    newest: RefCell<Option<Rc<Sample<S, T, ()>>>>,
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> fmt::Debug for LatestCache<S, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LatestCache")
            .field("has_newest", &self.newest.borrow().is_some())
            .finish_non_exhaustive()
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> LatestCache<S, T> {
    pub(crate) fn new(subscriber: Subscriber<S, T, ()>) -> Self {
        Self {
            subscriber,
            newest: RefCell::new(None),
        }
    }

    /// The newest sample taken so far, without looking for new ones.
    pub(crate) fn current(&self) -> Option<Received<S, T>> {
        self.newest.borrow().as_ref().map(|sample| Received {
            sample: Rc::clone(sample),
        })
    }

    /// Drops the newest sample kept (one from a server that is gone).
    pub(crate) fn forget(&self) {
        *self.newest.borrow_mut() = None;
    }

    /// Takes every waiting sample and keeps the newest; returns it (or the one kept before).
    pub(crate) fn refresh(&self) -> Result<Option<Received<S, T>>, ClientError> {
        while self.take_next()?.is_some() {}
        Ok(self.current())
    }

    /// Takes the oldest waiting sample (the next in publication order), keeps it as the
    /// newest and returns it; `None` when nothing is waiting.
    pub(crate) fn take_next(&self) -> Result<Option<Received<S, T>>, ClientError> {
        let waiting = self
            .subscriber
            .has_samples()
            .map_err(|error| ClientError::ipc("check for new samples", error))?;
        if !waiting {
            return Ok(None);
        }
        // Give our own hold on the previous sample back first (unless the caller still holds
        // it), so that reading never needs more than one extra borrowed sample.
        {
            let mut newest = self.newest.borrow_mut();
            if newest.as_ref().is_some_and(|rc| Rc::strong_count(rc) == 1) {
                *newest = None;
            }
        }
        let sample = self
            .subscriber
            .receive()
            .map_err(|error| ClientError::ipc("receive a sample", error))?;
        Ok(sample.map(|sample| {
            let sample = Rc::new(sample);
            *self.newest.borrow_mut() = Some(Rc::clone(&sample));
            Received { sample }
        }))
    }
}
