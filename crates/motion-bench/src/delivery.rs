//! Frame delivery latency: `MotionFrame::publish_ns` (stamped by the publisher just before
//! the send) → the moment this client holds the sample, both on CLOCK_MONOTONIC.

use core::time::Duration;

use iceoryx2::prelude::*;
use motion_ipc::ServiceNames;

use crate::dist::Dist;
use crate::ipc::{self, Ipc};
use crate::rt::{self, now_ns};

/// How the client waits for the next frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Waiting {
    /// Sleeps in an iceoryx2 `WaitSet` on the tick event, then takes the frame.
    WaitSet,
    /// Spins on `Subscriber::receive` (one core at 100 %).
    BusyPoll,
}

/// What one delivery phase saw.
#[derive(Debug)]
pub struct DeliveryRun {
    /// publish_ns → received, ns.
    pub latency: Dist,
    /// time_ns (the tick's deadline) → publish_ns: the publisher's wake-up plus its work
    /// up to the send, for every frame seen.
    pub deadline_to_publish: Dist,
    /// Frames received.
    pub frames: u64,
    /// Ticks missing between received frames.
    pub lost: u64,
    /// The client thread's set-up.
    pub thread: String,
}

/// Receives the frames of `names` for `duration`, waiting as `waiting` says. The WaitSet
/// client gets SCHED_FIFO `rt_priority` when given; a busy-polling thread never does.
pub fn measure(
    names: &ServiceNames,
    waiting: Waiting,
    duration: Duration,
    rt_priority: Option<u8>,
) -> Result<DeliveryRun, String> {
    let names = names.clone();
    std::thread::scope(|scope| {
        scope
            .spawn(move || {
                let priority = match waiting {
                    Waiting::WaitSet => rt_priority,
                    Waiting::BusyPoll => None,
                };
                let thread = rt::set_up_thread(priority, None).describe();
                let node = ipc::node("frames")?;
                let frames = ipc::open_frames(&node, &names, ipc::OPEN_TIMEOUT)?;
                let mut run = DeliveryRun {
                    latency: Dist::new(),
                    deadline_to_publish: Dist::new(),
                    frames: 0,
                    lost: 0,
                    thread,
                };
                // The history sample and anything queued are old: not measured.
                ipc::latest(&frames)?;
                let end = now_ns() + duration_ns(duration);
                match waiting {
                    Waiting::WaitSet => {
                        let tick = ipc::open_tick(&node, &names)?;
                        by_waitset(&frames, &tick, end, &mut run)?;
                    }
                    Waiting::BusyPoll => busy_poll(&frames, end, &mut run)?,
                }
                Ok(run)
            })
            .join()
            .map_err(|_| "the frame client thread panicked".to_owned())?
    })
}

struct Tracker {
    last_tick: Option<u64>,
}

impl Tracker {
    fn take(&mut self, frame: &motion_ipc::MotionFrame, received_ns: u64, run: &mut DeliveryRun) {
        run.latency
            .record(received_ns.saturating_sub(frame.publish_ns));
        run.deadline_to_publish
            .record(frame.publish_ns.saturating_sub(frame.time_ns));
        run.frames += 1;
        if let Some(last) = self.last_tick
            && frame.tick > last
        {
            run.lost += frame.tick - last - 1;
        }
        self.last_tick = Some(frame.tick);
    }
}

fn drain(frames: &ipc::Frames, tracker: &mut Tracker, run: &mut DeliveryRun) -> Result<(), String> {
    loop {
        match frames.receive() {
            Ok(Some(sample)) => {
                let received = now_ns();
                tracker.take(sample.payload(), received, run);
            }
            Ok(None) => return Ok(()),
            Err(e) => return Err(format!("receive a frame: {e:?}")),
        }
    }
}

fn by_waitset(
    frames: &ipc::Frames,
    tick: &iceoryx2::port::listener::Listener<Ipc>,
    end: u64,
    run: &mut DeliveryRun,
) -> Result<(), String> {
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(|e| format!("wait set: {e:?}"))?;
    let guard = waitset
        .attach_notification(tick)
        .map_err(|e| format!("attach the tick event: {e:?}"))?;
    let mut tracker = Tracker { last_tick: None };
    // Notifications that piled up before the start.
    let _ = tick.try_wait(|_| {});
    while now_ns() < end {
        let mut failed = None;
        waitset
            .wait_and_process_once_with_timeout(
                |id| {
                    if id.has_event_from(&guard)
                        && let Err(e) = tick.try_wait(|_| {})
                    {
                        failed = Some(format!("take tick notifications: {e:?}"));
                    }
                    CallbackProgression::Continue
                },
                Duration::from_millis(500),
            )
            .map_err(|e| format!("wait in the wait set: {e:?}"))?;
        if let Some(error) = failed {
            return Err(error);
        }
        drain(frames, &mut tracker, run)?;
    }
    Ok(())
}

fn busy_poll(frames: &ipc::Frames, end: u64, run: &mut DeliveryRun) -> Result<(), String> {
    let mut tracker = Tracker { last_tick: None };
    let mut spins = 0u32;
    loop {
        match frames.receive() {
            Ok(Some(sample)) => {
                let received = now_ns();
                tracker.take(sample.payload(), received, run);
                if received >= end {
                    return Ok(());
                }
            }
            Ok(None) => {
                spins = spins.wrapping_add(1);
                if spins.is_multiple_of(1024) && now_ns() >= end {
                    return Ok(());
                }
                std::hint::spin_loop();
            }
            Err(e) => return Err(format!("receive a frame: {e:?}")),
        }
    }
}

/// A duration in ns, saturating.
pub fn duration_ns(duration: Duration) -> u64 {
    u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX)
}
