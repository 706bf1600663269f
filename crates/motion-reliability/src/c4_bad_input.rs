//! Campaign 4, bad input over shared memory: random and adversarial `CommandRequest`s —
//! unknown kinds and targets, NaN and ±∞, out-of-range axis and signal indices, values at
//! and just past every limit, borrowed client ids, commands on an axis another client
//! claimed — sent by two clients at ten times the tick rate, each keeping up to 8 requests
//! in flight. Every request must get exactly one reply with a known reason (the first
//! checks — schema, kind, finite values, identity, target, axis index — have one right
//! answer, compared with an oracle), no byte on the boards' wires may leave the axes'
//! limits, the server must stay alive, and its tick latency is compared with a quiet run.

use core::time::Duration;
use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::bail;
use iceoryx2::prelude::*;
use motion_ipc::{ClientId, CommandKind, CommandReply, CommandRequest, Reason, SCHEMA_VERSION};
use motion_sim::rng::SimRng;
use motion_testkit::RawClient;
use nix::sys::signal::Signal;

use crate::boards::{
    FOCUS_LIMITS, QSB_LIMITS, QsbAndStepper, qsb_lines, qsb_out_of_limits, server_section,
    spimotor_out_of_limits, spimotor_position_outside,
};
use crate::c1_dead_clients::online;
use crate::harness::{Harness, TickMeter};
use crate::report::Row;

const AXES: u32 = 2;
const SIGNALS: u32 = 1;
/// One group of both axes (requests with `target = Group` meet a real one).
const GROUPS: u32 = 1;
const IN_FLIGHT: usize = 8;

type Pending =
    iceoryx2::pending_response::PendingResponse<ipc::Service, CommandRequest, (), CommandReply, ()>;

/// A request sent: itself, the oracle's reason, its pending reply, when it left.
type InFlight = (CommandRequest, Option<Reason>, Pending, Instant);

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let total: u64 = if h.quick { 20_000 } else { 1_000_000 };
    let quiet_time = Duration::from_secs(if h.quick { 2 } else { 20 });
    let mut row = Row::new("4 bad input");
    row.runs = format!("{total} random and adversarial requests at 10 per tick, 2 clients");
    let name = h.name("input");
    let epoch = Instant::now();
    let boards = QsbAndStepper::serve(h, &name, epoch)?;
    let signal = "\n[[signal]]\nname = \"lamp\"\ndevice = \"feeder_qsb\"\npin = \"io3\"\nkind = \"digital-out\"\nsafe = false\n\n[[group]]\nname = \"pair\"\naxes = [\"feeder\", \"focus\"]\n";
    let config = h.write(
        &format!("{name}.toml"),
        &format!(
            "{}{}{signal}",
            server_section(&name, "liveness_check_ms = 100"),
            boards.sections()
        ),
    )?;
    let mut server = h.server(&config)?;
    let mut owner = RawClient::try_connect(&name, Duration::from_secs(10))?;
    if !matches!(
        owner.try_wait_frame(Duration::from_secs(15), |f| online(f, 0) && online(f, 1)),
        Some((_, true))
    ) {
        bail!("the boards are not online");
    }
    let attackers = [
        RawClient::try_connect(&name, Duration::from_secs(10))?,
        RawClient::try_connect(&name, Duration::from_secs(10))?,
    ];
    let meter = TickMeter::start(&name)?;
    std::thread::sleep(quiet_time);
    let quiet = meter.take();
    let mut rng = SimRng::new(h.seed ^ 0xBAD1);
    let mut in_flight: [Vec<InFlight>; 2] = [Vec::new(), Vec::new()];
    let (mut sent, mut replies, mut lost, mut unknown, mut mismatched, mut send_errors) =
        (0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
    let mut reasons: BTreeMap<String, u64> = BTreeMap::new();
    let mut examples: Vec<String> = Vec::new();
    let mut sequence = 0u64;
    let started = Instant::now();
    let mut next_claim = Instant::now();
    let mut claimed = false;
    let mut quota = 0f64;
    let mut extreme = 0u32;
    let mut positions_outside: Vec<String> = Vec::new();
    let mut last = Instant::now();
    while sent < total || in_flight.iter().any(|f| !f.is_empty()) {
        // The owner claims the stepper for a second, then leaves it for a second.
        if Instant::now() >= next_claim {
            let kind = if claimed {
                CommandKind::Release
            } else {
                CommandKind::Claim
            };
            let _ = owner.try_command(1, kind, [0.0; 3]);
            claimed = !claimed;
            next_claim = Instant::now() + Duration::from_secs(1);
        }
        // 10 requests per millisecond in all.
        let now = Instant::now();
        quota = (quota + (now - last).as_secs_f64() * 10_000.0).min(40.0);
        last = now;
        for (index, attacker) in attackers.iter().enumerate() {
            while sent < total && quota >= 1.0 && in_flight[index].len() < IN_FLIGHT {
                sequence += 1;
                let own = attacker.id();
                let request = adversarial(&mut rng, own, sequence);
                let expected = oracle(&request, own);
                match attacker.commands.send_copy(request) {
                    Ok(pending) => {
                        in_flight[index].push((request, expected, pending, Instant::now()))
                    }
                    Err(_) => send_errors += 1,
                }
                sent += 1;
                quota -= 1.0;
            }
            in_flight[index].retain(|(request, expected, pending, at)| match pending.receive() {
                Ok(Some(reply)) => {
                    replies += 1;
                    let reply: CommandReply = *reply;
                    match Reason::try_from(reply.reason) {
                        Ok(reason) => {
                            *reasons.entry(format!("{reason:?}")).or_default() += 1;
                            let wrong = reply.sequence != request.sequence
                                || expected.is_some_and(|e| e != reason && reason != Reason::Busy);
                            if wrong {
                                mismatched += 1;
                                if examples.len() < 5 {
                                    examples.push(format!(
                                        "{request:?} → {reason:?}, expected {expected:?}"
                                    ));
                                }
                            }
                        }
                        Err(_) => unknown += 1,
                    }
                    false
                }
                _ if at.elapsed() > Duration::from_secs(2) => {
                    lost += 1;
                    false
                }
                _ => true,
            });
        }
        // Where the stepper really is (velocity runs are stopped at the limits by the
        // engine, not by the bytes on the wire).
        if let Ok(board) = boards.stepper.lock() {
            let position = board.current_position();
            extreme = extreme.max(position.unsigned_abs());
            if let Some(outside) = spimotor_position_outside(position)
                && positions_outside.len() < 5
            {
                positions_outside.push(outside);
            }
        }
        std::thread::sleep(Duration::from_micros(200));
        if !server.is_running() {
            break;
        }
    }
    let attack_time = started.elapsed();
    let loaded = meter.take();
    drop(meter);
    let alive = server.is_running();
    // Still answering after the attack?
    let answers = owner.try_command(0, CommandKind::Stop, [0.0; 3]).is_ok();
    std::thread::sleep(Duration::from_millis(300));
    let mut violations: Vec<String> = qsb_lines(&boards.qsb_board.take_received())
        .iter()
        .filter_map(|l| qsb_out_of_limits(&l.line))
        .collect();
    violations.extend(
        boards
            .stepper_board
            .take_transactions()
            .iter()
            .filter_map(|(_, mosi)| spimotor_out_of_limits(mosi)),
    );
    let rate = sent as f64 / attack_time.as_secs_f64();
    row.figure(
        "sent",
        format!("{sent} in {:.1} s ({rate:.0}/s)", attack_time.as_secs_f64()),
    );
    row.figure(
        "replies by reason",
        reasons
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    let quiet_p99 = quiet.latency.quantile(0.99);
    let loaded_p99 = loaded.latency.quantile(0.99);
    row.figure(
        "tick latency p99 (deadline → frame sent)",
        format!(
            "quiet {:.0} µs / under attack {:.0} µs",
            quiet_p99 / 1e3,
            loaded_p99 / 1e3
        ),
    );
    row.target("tick latency p99", loaded_p99, quiet_p99, 1.1);
    row.check(
        "server alive",
        alive && answers,
        format!("running {alive}, answers {answers}"),
    );
    row.check(
        "every request answered once, with a reason",
        lost == 0 && unknown == 0 && send_errors == 0 && replies == sent,
        format!("{replies} replies to {sent} requests, {lost} lost, {unknown} unknown reasons, {send_errors} not sent"),
    );
    row.check(
        "the reason the checks prescribe",
        mismatched == 0,
        format!("{mismatched} replies with another reason than the oracle's"),
    );
    row.check(
        "0 bytes outside an axis's limits",
        violations.is_empty(),
        format!(
            "{} out-of-limit writes: {:?}",
            violations.len(),
            violations.iter().take(5).collect::<Vec<_>>()
        ),
    );
    row.figure(
        "stepper's farthest position",
        format!("{extreme} steps (limits ±{})", FOCUS_LIMITS.1),
    );
    row.check(
        "the stepper stays within its limits",
        positions_outside.is_empty(),
        format!("{:?}", positions_outside),
    );
    row.note(
        "velocity runs on the SPI_motor are targets 2^30 steps away (the driver's run distance): \
         not counted as out-of-limit bytes; the stepper's true position is checked instead",
    );
    for example in examples {
        row.note(example);
    }
    let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
    if code != Some(0) {
        row.note(format!("SIGTERM after the attack: exit {code:?}"));
    }
    Ok(row)
}

/// A value from the edges of what an axis takes.
fn value(rng: &mut SimRng, axis: u32) -> f64 {
    let (min, max, velocity, accel) = if axis == 0 { QSB_LIMITS } else { FOCUS_LIMITS };
    let pool = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.0,
        -0.0,
        min,
        max,
        min - 1e-9,
        max + 1e-9,
        velocity,
        -velocity,
        velocity * 1.0001,
        -velocity * 1.0001,
        accel,
        accel * 1.0001,
        -accel,
        f64::MAX,
        f64::MIN,
        f64::MIN_POSITIVE,
        5e-324,
        1e308,
        1.0,
        -1.0,
        1.0001,
    ];
    if rng.next_f64() < 0.3 {
        rng.range_f64(2.0 * min, 2.0 * max)
    } else {
        pool[(rng.next_u64() % pool.len() as u64) as usize]
    }
}

/// One request, mostly nonsense, sometimes valid.
fn adversarial(rng: &mut SimRng, own: ClientId, sequence: u64) -> CommandRequest {
    let pick = |rng: &mut SimRng| rng.next_f64();
    let kind = if pick(rng) < 0.8 {
        CommandKind::ALL[(rng.next_u64() % CommandKind::ALL.len() as u64) as usize] as u32
    } else {
        [0, 15, 16, 255, u32::MAX, rng.next_u64() as u32][(rng.next_u64() % 6) as usize]
    };
    let axis = match rng.next_u64() % 10 {
        0..=5 => (rng.next_u64() % u64::from(AXES)) as u32,
        6 => CommandRequest::ALL_AXES,
        7 | 8 => AXES + (rng.next_u64() % 3) as u32,
        _ => rng.next_u64() as u32,
    };
    let client = match rng.next_u64() % 10 {
        0..=7 => ClientId::NONE,
        8 => own,
        _ => ClientId {
            lo: rng.next_u64(),
            hi: rng.next_u64(),
        },
    };
    let target = match rng.next_u64() % 20 {
        0..=16 => 0,
        17 | 18 => 1,
        _ => 2 + (rng.next_u64() % 1000) as u32,
    };
    let values = [value(rng, axis), value(rng, axis), value(rng, axis)];
    CommandRequest {
        schema_version: if pick(rng) < 0.97 {
            SCHEMA_VERSION
        } else {
            rng.next_u64() as u32
        },
        kind,
        client,
        sequence,
        axis,
        target,
        values,
    }
}

/// The reason of the checks that have exactly one answer (the engine's order: schema,
/// kind, finite values, identity, target, axis index); `None` where the answer depends on
/// the server's state (claims, e-stop, limits, …).
fn oracle(request: &CommandRequest, sender: ClientId) -> Option<Reason> {
    if request.schema_version != SCHEMA_VERSION {
        return Some(Reason::SchemaMismatch);
    }
    let Ok(kind) = request.kind() else {
        return Some(Reason::UnknownKind);
    };
    if request.values.iter().any(|v| !v.is_finite()) {
        return Some(Reason::NotFinite);
    }
    if !request.client.is_none() && request.client != sender {
        return Some(Reason::IdentityMismatch);
    }
    let Ok(target) = request.target() else {
        return Some(Reason::UnknownTarget);
    };
    if target == motion_ipc::Target::Signal {
        return (request.axis >= SIGNALS && matches!(kind, CommandKind::SetOutput))
            .then_some(Reason::UnknownSignal);
    }
    if target == motion_ipc::Target::Group {
        return match kind {
            CommandKind::EStop => Some(Reason::Accepted),
            CommandKind::Reset => None,
            _ if request.axis >= GROUPS => Some(Reason::UnknownGroup),
            _ => None,
        };
    }
    if target == motion_ipc::Target::Device {
        // Only `Commission` addresses a device; its own rules depend on claims and motion.
        return (kind != CommandKind::Commission).then_some(Reason::UnknownTarget);
    }
    match kind {
        CommandKind::EStop => Some(Reason::Accepted),
        CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => Some(Reason::Accepted),
        CommandKind::SetOutput
        | CommandKind::Commission
        | CommandKind::Run
        | CommandKind::Feed
        | CommandKind::Cancel
        | CommandKind::Stream => Some(Reason::UnknownTarget),
        CommandKind::Reset | CommandKind::Off if request.axis == CommandRequest::ALL_AXES => None,
        _ if request.axis >= AXES && kind != CommandKind::Reset => Some(Reason::UnknownAxis),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_oracle_follows_the_engines_order() {
        let me = ClientId::from_u128(7);
        let mut r = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Velocity).with_values([
            f64::NAN,
            0.0,
            0.0,
        ]);
        assert_eq!(oracle(&r, me), Some(Reason::NotFinite));
        r.kind = 99;
        assert_eq!(oracle(&r, me), Some(Reason::UnknownKind));
        r.schema_version = 0;
        assert_eq!(oracle(&r, me), Some(Reason::SchemaMismatch));
        let r = CommandRequest::new(ClientId::from_u128(8), 1, 0, CommandKind::Stop);
        assert_eq!(oracle(&r, me), Some(Reason::IdentityMismatch));
        let r = CommandRequest::new(me, 1, 5, CommandKind::Stop);
        assert_eq!(oracle(&r, me), Some(Reason::UnknownAxis));
        let r = CommandRequest::new(me, 1, 0, CommandKind::Stop);
        assert_eq!(oracle(&r, me), None, "depends on the state");
        let r = CommandRequest::new(me, 1, 0, CommandKind::EStop);
        assert_eq!(oracle(&r, me), Some(Reason::Accepted));
        let r = CommandRequest::new(me, 1, 0, CommandKind::Feed);
        assert_eq!(
            oracle(&r, me),
            Some(Reason::UnknownTarget),
            "a group kind to an axis"
        );
        let r = CommandRequest::new(me, 1, 0, CommandKind::Hold);
        assert_eq!(oracle(&r, me), None, "an axis's move: depends on the state");
        let mut r = CommandRequest::new(me, 1, 1, CommandKind::Run);
        r.target = motion_ipc::Target::Group as u32;
        assert_eq!(oracle(&r, me), Some(Reason::UnknownGroup));
        r.axis = 0;
        assert_eq!(oracle(&r, me), None, "depends on the paths and the state");
    }
}
