//! The `estop` event off the tick's hot path (issue 31: asking the listener every tick was
//! a system call, about 3 µs of every idle tick). A thread of its own sleeps in poll(2) on
//! a duplicate of the listener's descriptor and raises a flag when a notification is there;
//! the tick looks at the flag (one atomic load) and takes the notification from the
//! listener only then, in the same tick a direct look would have. The thread then waits for
//! the tick to say it has taken it before it looks again, so a pending notification never
//! makes it spin.
//!
//! Only the tick reads the listener; the thread only polls its descriptor.
#![allow(unsafe_code)] // the listener's descriptor is borrowed once to duplicate it; see SAFETY

use std::os::fd::{AsFd, BorrowedFd, OwnedFd};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::FileDescriptorBased;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
use nix::sys::eventfd::{EfdFlags, EventFd};

use crate::Ipc;

/// The flag the tick looks at, and the thread that raises it.
#[derive(Debug)]
pub struct EstopWatch {
    pending: Arc<AtomicBool>,
    /// Written by the tick once it took what the flag announced.
    taken: Arc<EventFd>,
    /// Written on drop: the thread ends.
    stop: Arc<EventFd>,
    thread: Option<JoinHandle<()>>,
}

impl EstopWatch {
    /// Starts watching `listener`'s descriptor (thread `estop-watch`).
    pub fn start(listener: &Listener<Ipc>) -> std::io::Result<Self> {
        // SAFETY: the descriptor belongs to `listener`, which is alive for this call; it is
        // only borrowed to duplicate it, and the duplicate is owned by the thread.
        let borrowed =
            unsafe { BorrowedFd::borrow_raw(listener.file_descriptor().native_handle()) };
        let watched: OwnedFd = borrowed.try_clone_to_owned()?;
        let flags = EfdFlags::EFD_NONBLOCK | EfdFlags::EFD_CLOEXEC;
        let taken = Arc::new(EventFd::from_flags(flags)?);
        let stop = Arc::new(EventFd::from_flags(flags)?);
        let pending = Arc::new(AtomicBool::new(false));
        let thread = {
            let (pending, taken, stop) =
                (Arc::clone(&pending), Arc::clone(&taken), Arc::clone(&stop));
            std::thread::Builder::new()
                .name("estop-watch".into())
                .spawn(move || watch(&watched, &pending, &taken, &stop))?
        };
        Ok(Self {
            pending,
            taken,
            stop,
            thread: Some(thread),
        })
    }

    /// Whether a notification may be waiting on the listener (one atomic load). When it
    /// says so, [`EstopWatch::clear`], take the listener's notifications, [`EstopWatch::resume`].
    pub fn pending(&self) -> bool {
        self.pending.load(Ordering::Acquire)
    }

    /// Clears the flag; call it before taking the listener's notifications (then take
    /// them, then [`EstopWatch::resume`]), so that one that comes after the take raises the
    /// flag anew.
    pub fn clear(&self) {
        self.pending.store(false, Ordering::Release);
    }

    /// The tick took the listener's notifications: the thread may look again.
    pub fn resume(&self) {
        // Fails only when the counter would overflow: it is then readable anyway.
        let _ = self.taken.write(1);
    }
}

impl Drop for EstopWatch {
    fn drop(&mut self) {
        let _ = self.stop.write(1);
        if let Some(thread) = self.thread.take()
            && thread.join().is_err()
        {
            tracing::error!("the e-stop watch thread panicked");
        }
    }
}

/// Whether `fd`'s poll entry says it is readable (or hung up: either way, look).
fn readable(fd: &PollFd<'_>) -> bool {
    fd.revents().is_some_and(|r| !r.is_empty())
}

fn watch(watched: &OwnedFd, pending: &AtomicBool, taken: &EventFd, stop: &EventFd) {
    loop {
        let mut fds = [
            PollFd::new(watched.as_fd(), PollFlags::POLLIN),
            PollFd::new(stop.as_fd(), PollFlags::POLLIN),
        ];
        if poll(&mut fds, PollTimeout::NONE).is_err() {
            // EINTR: look again.
            continue;
        }
        if readable(&fds[1]) {
            return;
        }
        if !readable(&fds[0]) {
            continue;
        }
        pending.store(true, Ordering::Release);
        // Until the tick took it, the descriptor stays readable: wait for the tick.
        loop {
            let mut fds = [
                PollFd::new(taken.as_fd(), PollFlags::POLLIN),
                PollFd::new(stop.as_fd(), PollFlags::POLLIN),
            ];
            if poll(&mut fds, PollTimeout::NONE).is_err() {
                continue;
            }
            if readable(&fds[1]) {
                return;
            }
            if readable(&fds[0]) {
                let _ = taken.read();
                break;
            }
        }
    }
}
