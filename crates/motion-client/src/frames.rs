//! Reading frames: the newest one, every one in order, or a callback in a `WaitSet`.

use core::ops::ControlFlow;
use core::time::Duration;
use std::time::Instant;

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::{CallbackProgression, SynchronousMultiplexing, WaitSetBuilder};
use iceoryx2::service::Service;
use iceoryx2::waitset::WaitSetRunResult;

use crate::session::Seen;
use crate::{Client, ClientError, Frame};

/// How long [`Client::latest`] waits when no frame has been received yet.
pub const FIRST_FRAME_TIMEOUT: Duration = Duration::from_secs(1);

/// How long frames may stay away before the client checks whether the frame service was
/// recreated under it (and resubscribes).
const SILENCE_CHECK: Duration = Duration::from_millis(250);

impl<S: Service> Client<S> {
    /// The next waiting frame of the current server (frames a server known to be gone left
    /// in the buffer are dropped); notes a restart.
    fn take_frame(&self) -> Result<Option<Frame<S>>, ClientError> {
        let ports = self.frame_ports()?;
        loop {
            let Some(frame) = ports.cache.take_next()? else {
                return Ok(None);
            };
            match self.session.observe_frame(frame.origin_node(), frame.tick) {
                Seen::Current => return Ok(Some(frame)),
                Seen::Retired => ports.cache.forget(),
                Seen::Restarted => {
                    self.on_restart();
                    return Ok(Some(frame));
                }
            }
        }
    }

    /// The newest frame without renewing jog guards (see [`Client::latest`]).
    pub(crate) fn newest_frame(&self) -> Result<Frame<S>, ClientError> {
        while let Some(frame) = self.take_frame()? {
            drop(frame);
        }
        if let Some(frame) = self.frame_ports()?.cache.current() {
            return Ok(frame);
        }
        self.next_frame_inner(FIRST_FRAME_TIMEOUT)
    }

    /// The newest frame, zero-copy. Takes every frame waiting and keeps the newest; if none
    /// was ever received, waits up to [`FIRST_FRAME_TIMEOUT`] for one. The first call
    /// subscribes to the frame service.
    pub fn latest(&self) -> Result<Frame<S>, ClientError> {
        self.service_jogs();
        self.newest_frame()
    }

    /// The next frame in publication order if one is waiting, without blocking.
    pub fn try_next_frame(&self) -> Result<Option<Frame<S>>, ClientError> {
        self.service_jogs();
        self.take_frame()
    }

    /// The next frame in publication order, blocking on the tick event (no busy polling)
    /// for up to `timeout`. A frame already waiting is returned at once. Frames the client
    /// was too slow for are lost (the server never waits for a client): compare `tick`s.
    pub fn next_frame(&self, timeout: Duration) -> Result<Frame<S>, ClientError> {
        self.next_frame_inner(timeout)
    }

    fn next_frame_inner(&self, timeout: Duration) -> Result<Frame<S>, ClientError> {
        let deadline = Instant::now() + timeout;
        let mut silent_since = Instant::now();
        loop {
            self.service_jogs();
            if let Some(frame) = self.take_frame()? {
                return Ok(frame);
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(ClientError::NoFrame(timeout));
            }
            if now.duration_since(silent_since) >= SILENCE_CHECK {
                // Frames stopped: a server that recreated the services publishes elsewhere.
                self.reopen_frames_if_recreated()?;
                self.refresh_info()?;
                silent_since = now;
            }
            let nap = self.jog_wait_cap(deadline - now).min(SILENCE_CHECK);
            self.wait_tick(nap)?;
        }
    }

    /// The next frame by busy polling (no sleeping), for latency measurements on a
    /// dedicated core. Spins for up to `timeout`. Jog guards are not renewed while spinning
    /// (call [`Client::keep_alive`] between frames if you hold one).
    pub fn next_frame_spinning(&self, timeout: Duration) -> Result<Frame<S>, ClientError> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(frame) = self.take_frame()? {
                return Ok(frame);
            }
            if Instant::now() >= deadline {
                return Err(ClientError::NoFrame(timeout));
            }
            core::hint::spin_loop();
        }
    }

    /// Every frame in order, each waited for up to `timeout`. The iterator yields
    /// `Err(NoFrame)` (and then ends) when the server stays silent, and ends without an
    /// error after SIGINT/SIGTERM.
    pub fn frames(&self, timeout: Duration) -> Frames<'_, S> {
        Frames {
            client: self,
            timeout,
            done: false,
        }
    }

    /// Calls `on_frame` for every frame, sleeping in an iceoryx2 `WaitSet` on the tick event
    /// in between. Returns `Ok(())` when `on_frame` breaks or on SIGINT/SIGTERM, and
    /// `Err(NoFrame)` when no tick came for `timeout`.
    pub fn for_each_frame(
        &self,
        timeout: Duration,
        mut on_frame: impl FnMut(&Frame<S>) -> ControlFlow<()>,
    ) -> Result<(), ClientError>
    where
        Listener<S>: SynchronousMultiplexing,
    {
        let ports = self.frame_ports()?;
        let Some(tick) = ports.tick.as_ref() else {
            // Over a bridge there is no event to wait on: wait for the frames themselves.
            return self.for_each_frame_polled(timeout, on_frame);
        };
        let waitset = WaitSetBuilder::new()
            .create::<S>()
            .map_err(|error| ClientError::ipc("create a wait set", error))?;
        let guard = waitset
            .attach_deadline(&**tick, timeout)
            .map_err(|error| ClientError::ipc("attach the tick event to a wait set", error))?;
        let refresh = self.jog_refresh_period();
        let _interval = match refresh {
            Some(period) => Some(
                waitset
                    .attach_interval(period)
                    .map_err(|error| ClientError::ipc("attach the jog refresh interval", error))?,
            ),
            None => None,
        };
        let mut outcome = Ok(());
        let mut stop = false;
        // Frames that arrived before the first wake-up.
        while let Some(frame) = self.try_next_frame()? {
            if on_frame(&frame).is_break() {
                return Ok(());
            }
        }
        while !stop {
            let mut deadline_missed = false;
            let run = waitset
                .wait_and_process_once(|id| {
                    if id.has_missed_deadline(&guard) {
                        deadline_missed = true;
                        return CallbackProgression::Stop;
                    }
                    if id.has_event_from(&guard) {
                        // Consume the notifications; the frames themselves are read below.
                        if let Err(error) = tick.try_wait(|_| {}) {
                            outcome = Err(ClientError::ipc("take tick notifications", error));
                            return CallbackProgression::Stop;
                        }
                    }
                    CallbackProgression::Continue
                })
                .map_err(|error| ClientError::ipc("wait in the wait set", error))?;
            if outcome.is_err() {
                break;
            }
            if matches!(
                run,
                WaitSetRunResult::Interrupt | WaitSetRunResult::TerminationRequest
            ) {
                break;
            }
            if deadline_missed {
                outcome = Err(ClientError::NoFrame(timeout));
                break;
            }
            while let Some(frame) = self.try_next_frame()? {
                if on_frame(&frame).is_break() {
                    stop = true;
                    break;
                }
            }
        }
        outcome
    }
}

impl<S: Service> Client<S> {
    /// [`Client::for_each_frame`] without a wait set: each frame waited for in turn.
    fn for_each_frame_polled(
        &self,
        timeout: Duration,
        mut on_frame: impl FnMut(&Frame<S>) -> ControlFlow<()>,
    ) -> Result<(), ClientError> {
        loop {
            match self.next_frame(timeout) {
                Ok(frame) => {
                    if on_frame(&frame).is_break() {
                        return Ok(());
                    }
                }
                Err(ClientError::Interrupted) => return Ok(()),
                Err(error) => return Err(error),
            }
        }
    }
}

/// Iterator over every frame; see [`Client::frames`].
#[derive(Debug)]
pub struct Frames<'c, S: Service> {
    client: &'c Client<S>,
    timeout: Duration,
    done: bool,
}

impl<S: Service> Iterator for Frames<'_, S> {
    type Item = Result<Frame<S>, ClientError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.client.next_frame(self.timeout) {
            Ok(frame) => Some(Ok(frame)),
            Err(ClientError::Interrupted) => {
                self.done = true;
                None
            }
            Err(error) => {
                self.done = true;
                Some(Err(error))
            }
        }
    }
}
