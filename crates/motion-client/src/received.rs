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

/// A payload received from the server, still in shared memory (nothing was copied) — or,
/// from a remote client (feature `zenoh`), the copy that came over the network.
///
/// Cheap to clone (a reference count). While you hold one, the server cannot reuse its
/// memory chunk; the service allows each subscriber only a couple of held samples, so drop
/// it before asking for the next one if you can (holding one while reading the next is fine).
pub struct Received<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    held: Held<S, T>,
}

/// Where a received payload lives.
enum Held<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    /// In the server's shared memory.
    Shm(Rc<Sample<S, T, ()>>),
    /// A copy received over the network.
    #[cfg(feature = "zenoh")]
    Net(Rc<crate::remote::Owned<T>>),
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Clone for Held<S, T> {
    fn clone(&self) -> Self {
        match self {
            Self::Shm(sample) => Self::Shm(Rc::clone(sample)),
            #[cfg(feature = "zenoh")]
            Self::Net(owned) => Self::Net(Rc::clone(owned)),
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Held<S, T> {
    /// Whether only the cache holds it.
    fn unshared(&self) -> bool {
        match self {
            Self::Shm(sample) => Rc::strong_count(sample) == 1,
            #[cfg(feature = "zenoh")]
            Self::Net(owned) => Rc::strong_count(owned) == 1,
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Clone for Received<S, T> {
    fn clone(&self) -> Self {
        Self {
            held: self.held.clone(),
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Received<S, T> {
    /// The iceoryx2 node id of the process that published it (the server).
    pub fn origin_node(&self) -> u128 {
        match &self.held {
            Held::Shm(sample) => sample.header().node_id().value(),
            #[cfg(feature = "zenoh")]
            Held::Net(owned) => owned.origin,
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> Deref for Received<S, T> {
    type Target = T;
    fn deref(&self) -> &T {
        match &self.held {
            Held::Shm(sample) => sample.payload(),
            #[cfg(feature = "zenoh")]
            Held::Net(owned) => &owned.value,
        }
    }
}

impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> fmt::Debug for Received<S, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Received").field(&**self).finish()
    }
}

/// Where a cache takes its samples from.
enum Source<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    /// A subscriber of the server's service.
    Shm(Subscriber<S, T, ()>),
    /// A feed from a bridge.
    #[cfg(feature = "zenoh")]
    Net(Box<crate::remote::Feed<T>>),
}

/// One subscriber and the newest sample taken from it.
pub(crate) struct LatestCache<S: Service, T: fmt::Debug + ZeroCopySend + 'static> {
    source: Source<S, T>,
    newest: RefCell<Option<Held<S, T>>>,
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
            source: Source::Shm(subscriber),
            newest: RefCell::new(None),
        }
    }

    /// The newest sample taken so far, without looking for new ones.
    pub(crate) fn current(&self) -> Option<Received<S, T>> {
        self.newest
            .borrow()
            .as_ref()
            .map(|held| Received { held: held.clone() })
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
    // Without the `zenoh` feature the source has one variant only.
    #[allow(clippy::infallible_destructuring_match)]
    pub(crate) fn take_next(&self) -> Result<Option<Received<S, T>>, ClientError> {
        let subscriber = match &self.source {
            Source::Shm(subscriber) => subscriber,
            #[cfg(feature = "zenoh")]
            Source::Net(feed) => {
                let Some(owned) = feed.next()? else {
                    return Ok(None);
                };
                let held = Held::Net(Rc::new(owned));
                *self.newest.borrow_mut() = Some(held.clone());
                return Ok(Some(Received { held }));
            }
        };
        let waiting = subscriber
            .has_samples()
            .map_err(|error| ClientError::ipc("check for new samples", error))?;
        if !waiting {
            return Ok(None);
        }
        // Give our own hold on the previous sample back first (unless the caller still holds
        // it), so that reading never needs more than one extra borrowed sample.
        {
            let mut newest = self.newest.borrow_mut();
            if newest.as_ref().is_some_and(Held::unshared) {
                *newest = None;
            }
        }
        let sample = subscriber
            .receive()
            .map_err(|error| ClientError::ipc("receive a sample", error))?;
        Ok(sample.map(|sample| {
            let held = Held::Shm(Rc::new(sample));
            *self.newest.borrow_mut() = Some(held.clone());
            Received { held }
        }))
    }
}

#[cfg(feature = "zenoh")]
impl<S: Service, T: fmt::Debug + ZeroCopySend + 'static> LatestCache<S, T> {
    /// A cache fed from a bridge.
    pub(crate) fn remote(feed: crate::remote::Feed<T>) -> Self {
        Self {
            source: Source::Net(Box::new(feed)),
            newest: RefCell::new(None),
        }
    }

    /// The bridge's feed, if this cache has one.
    pub(crate) fn feed(&self) -> Option<&crate::remote::Feed<T>> {
        match &self.source {
            Source::Net(feed) => Some(feed),
            Source::Shm(_) => None,
        }
    }
}
