//! Command round trip: `CommandRequest` sent → its `CommandReply` received, the client
//! busy-polling for the reply; and "command → applied" in ticks: `reply.tick_applied` minus
//! the newest frame's tick when the request left.

use core::time::Duration;
use std::collections::BTreeMap;

use motion_ipc::{ClientId, CommandKind, CommandRequest, Reason, ServiceNames};

use crate::args::CommandProbe;
use crate::delivery::duration_ns;
use crate::dist::Dist;
use crate::ipc;
use crate::rt::{XorShift, now_ns, sleep_until_ns};

/// A reply later than this is counted as lost.
const REPLY_TIMEOUT_NS: u64 = 1_000_000_000;

/// What one round-trip phase saw.
#[derive(Debug)]
pub struct RoundTripRun {
    /// Send → reply received, ns.
    pub rtt: Dist,
    /// `tick_applied` − newest frame tick at send (absent without a frame service).
    pub ticks: Option<Dist>,
    /// Replies by reason name.
    pub reasons: BTreeMap<String, u64>,
    /// Requests without a reply within 1 s, or that could not be sent.
    pub lost: u64,
}

/// Sends one request at a time to `names`'s command service for `duration`. Before each,
/// it waits a pseudo-random part of `pace_ns`, so that requests land at every phase of the
/// server's tick instead of always just after (or just before) it.
pub fn measure(
    names: &ServiceNames,
    probe: CommandProbe,
    axis_count: u32,
    with_frames: bool,
    pace_ns: u64,
    duration: Duration,
) -> Result<RoundTripRun, String> {
    let names = names.clone();
    std::thread::scope(|scope| {
        scope
            .spawn(move || {
                let _ = crate::rt::set_up_thread(None, None);
                let node = ipc::node("commands")?;
                let client = ipc::open_commands(&node, &names)?;
                let frames = if with_frames {
                    Some(ipc::open_frames(&node, &names, ipc::OPEN_TIMEOUT)?)
                } else {
                    None
                };
                let id = ClientId::from_u128(node.id().value());
                let mut run = RoundTripRun {
                    rtt: Dist::new(),
                    ticks: frames.as_ref().map(|_| Dist::new()),
                    reasons: BTreeMap::new(),
                    lost: 0,
                };
                let mut random = XorShift::new(u64::from(std::process::id()) ^ now_ns());
                let mut newest_tick = None;
                let end = now_ns() + duration_ns(duration);
                let mut sequence = 0u64;
                while now_ns() < end {
                    sleep_until_ns(now_ns() + random.below(pace_ns));
                    if let Some(frames) = &frames
                        && let Some(frame) = ipc::latest(frames)?
                    {
                        newest_tick = Some(frame.tick);
                    }
                    sequence += 1;
                    let request = request(probe, id, sequence, axis_count);
                    let sent = now_ns();
                    let Ok(pending) = client.send_copy(request) else {
                        run.lost += 1;
                        continue;
                    };
                    let reply = loop {
                        match pending.receive() {
                            Ok(Some(response)) => break Some(*response.payload()),
                            Ok(None) if now_ns() - sent > REPLY_TIMEOUT_NS => break None,
                            Ok(None) => std::hint::spin_loop(),
                            Err(e) => return Err(format!("receive a reply: {e:?}")),
                        }
                    };
                    let received = now_ns();
                    let Some(reply) = reply.filter(|r| r.sequence == sequence) else {
                        run.lost += 1;
                        continue;
                    };
                    run.rtt.record(received - sent);
                    let reason = Reason::try_from(reply.reason)
                        .map_or_else(|_| format!("reason {}", reply.reason), |r| format!("{r:?}"));
                    *run.reasons.entry(reason).or_default() += 1;
                    if let (Some(ticks), Some(at_send)) = (run.ticks.as_mut(), newest_tick) {
                        ticks.record(reply.tick_applied.saturating_sub(at_send));
                    }
                }
                Ok(run)
            })
            .join()
            .map_err(|_| "the command client thread panicked".to_owned())?
    })
}

fn request(probe: CommandProbe, id: ClientId, sequence: u64, axis_count: u32) -> CommandRequest {
    match probe {
        CommandProbe::UnknownAxis => {
            CommandRequest::new(id, sequence, axis_count, CommandKind::Stop)
        }
        CommandProbe::ClaimRelease => {
            let kind = if sequence % 2 == 1 {
                CommandKind::Claim
            } else {
                CommandKind::Release
            };
            CommandRequest::new(id, sequence, 0, kind)
        }
    }
}
