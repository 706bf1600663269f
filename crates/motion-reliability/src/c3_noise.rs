//! Campaign 3b, noise: bit errors on the line from a QSB-M (on a pty this process serves)
//! to motiond, at rates from 1e-6 to 1e-2 of the bits. The axis is held still, so the board
//! streams the same encoder count over and over; every count a frame shows that the board
//! never sent is a false accept. Resyncs are the link's error counter (bad lines dropped).
//! The QSB protocol has no checksum (ASCII hex lines): a flipped bit that turns a hex digit
//! into another hex digit makes a valid line with a wrong value, which no decoder can tell.
//! The driver's line-noise guard (motion-drivers `qsb::guard`) holds any line that
//! contradicts the ones before until the next confirms it, so up to ber 1e-4 (one corrupted
//! line in hundreds) nothing false may show and nothing may fault.

use core::time::Duration;
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Instant;

use anyhow::bail;
use iceoryx2::prelude::*;
use motion_ipc::{CommandKind, CommandRequest, FaultCode};
use motion_testkit::RawClient;
use motion_testkit::pty_board::{LineNoise, PtyOptions};

use crate::boards::{new_qsb, qsb_section, serve_qsb, server_section};
use crate::c1_dead_clients::online;
use crate::harness::{Harness, server_stats};
use crate::report::Row;

const RATES: [f64; 6] = [0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2];

/// Up to this bit-error rate the line-noise guard of the QSB driver (docs/RELIABILITY.md)
/// must show no count the board did not send and fault nothing.
const GUARDED_BER: f64 = 1e-4;

/// Runs the noise part.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let seconds = if h.quick { 1 } else { 30 };
    let mut row = Row::new("3b links: line noise");
    row.runs = format!("{seconds} s at each bit-error rate 0, 1e-6 … 1e-2 (QSB → motiond)");
    let name = h.name("noise");
    let epoch = Instant::now();
    let board = new_qsb();
    let noise = LineNoise::new(h.seed ^ 0x0B17);
    let tty = h.path(&format!("{name}.tty"));
    let served = serve_qsb(
        &tty,
        &board,
        epoch,
        PtyOptions {
            noise: Some(Arc::clone(&noise)),
            log_sent: true,
            ..PtyOptions::default()
        },
    )?;
    let config = h.write(
        &format!("{name}.toml"),
        &format!("{}{}", server_section(&name, ""), qsb_section(&tty)),
    )?;
    let mut server = h.server(&config)?;
    let raw = RawClient::try_connect(&name, Duration::from_secs(10))?;
    if !matches!(
        raw.try_wait_frame(Duration::from_secs(10), |f| online(f, 0)),
        Some((_, true))
    ) {
        bail!("the QSB axis is not online");
    }
    let stats_node = NodeBuilder::new()
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut total_false = 0u64;
    let mut clean_false = 0u64;
    let mut quiet_faults = 0u64;
    let mut guarded: Vec<String> = Vec::new();
    for ber in RATES {
        // A clean start for each rate: faults of the previous one reset.
        noise.set_ber(0.0);
        std::thread::sleep(Duration::from_millis(100));
        let reset = CommandRequest::new(raw.id(), 0, CommandRequest::ALL_AXES, CommandKind::Reset);
        let _ = raw.request(reset, Duration::from_secs(2));
        std::thread::sleep(Duration::from_millis(300));
        let before = server_stats(&stats_node, &name, Duration::from_secs(3))?;
        let _ = served.take_sent();
        while let Ok(Some(_)) = raw.frames.receive() {}
        let flipped_before = noise.flipped();
        noise.set_ber(ber);
        let mut seen: BTreeSet<i64> = BTreeSet::new();
        let mut frames = 0u64;
        let mut faults: BTreeSet<String> = BTreeSet::new();
        let end = Instant::now() + Duration::from_secs(seconds);
        while Instant::now() < end {
            while let Ok(Some(frame)) = raw.frames.receive() {
                frames += 1;
                let axis = frame.axes()[0];
                if axis.last_refresh_tick + 2 >= frame.tick {
                    seen.insert(axis.raw_counts);
                }
                if let Ok(code) = axis.fault()
                    && code != FaultCode::None
                {
                    faults.insert(format!("{code:?}"));
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        noise.set_ber(0.0);
        let flipped = noise.flipped() - flipped_before;
        std::thread::sleep(Duration::from_millis(1200));
        let after = server_stats(&stats_node, &name, Duration::from_secs(3))?;
        let sent = sent_counts(&served.take_sent());
        let false_accepts: Vec<i64> = seen.iter().copied().filter(|c| !sent.contains(c)).collect();
        let link = |s: &motion_ipc::ServerStats| {
            s.links().first().map_or((0, 0), |l| (l.errors, l.frames))
        };
        let (errors, decoded) = (
            link(&after).0 - link(&before).0,
            link(&after).1 - link(&before).1,
        );
        row.figure(
            &format!("ber {ber:e}"),
            format!(
                "{flipped} bits flipped, {errors} resyncs, {decoded} replies, {} false accepts, faults {}",
                false_accepts.len(),
                if faults.is_empty() { "none".to_owned() } else { faults.iter().cloned().collect::<Vec<_>>().join("+") }
            ),
        );
        if ber <= GUARDED_BER && (!false_accepts.is_empty() || !faults.is_empty()) {
            guarded.push(format!(
                "ber {ber:e}: {} false accepts, faults {faults:?}",
                false_accepts.len()
            ));
        }
        if ber == 0.0 {
            clean_false = false_accepts.len() as u64;
            quiet_faults = faults.len() as u64;
        } else {
            total_false += false_accepts.len() as u64;
        }
        if !false_accepts.is_empty() {
            row.note(format!(
                "ber {ber:e}: counts shown that the board never sent (it sent {:?}): {:?}",
                sent.iter().take(4).collect::<Vec<_>>(),
                false_accepts.iter().take(6).collect::<Vec<_>>()
            ));
        }
        let _ = frames;
    }
    row.check(
        "a clean line: 0 false accepts, 0 faults",
        clean_false == 0 && quiet_faults == 0,
        format!("{clean_false} false accepts, {quiet_faults} faults at ber 0"),
    );
    row.figure(
        "false accepts with noise (all rates)",
        total_false.to_string(),
    );
    row.check(
        "up to ber 1e-4: 0 false accepts, 0 faults",
        guarded.is_empty(),
        if guarded.is_empty() {
            "none".to_owned()
        } else {
            guarded.join("; ")
        },
    );
    row.note(
        "above ber 1e-4 false accepts and faults are reported, not judged: the QSB's line \
         format has no checksum, and two corrupted lines in a row pass the driver's guard",
    );
    h.check_alive_and_stop(&mut row, &mut server);
    Ok(row)
}

/// Every encoder count (register 0x0E) in the board's clean output.
fn sent_counts(bytes: &[(Duration, u8)]) -> BTreeSet<i64> {
    let mut decoder = qsb::ResponseDecoder::new();
    bytes
        .iter()
        .filter_map(|(_, b)| decoder.push(*b))
        .filter(|r| r.register == 0x0E)
        .map(|r| i64::from(r.data as i32))
        .collect()
}
