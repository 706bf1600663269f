//! The suite: the eight phases against the server and its baselines, the command-to-wire
//! phase and the axes sweep, gathered into one [`Report`].

use motion_ipc::{ServerStats, ServiceNames};

use crate::args::{BenchArgs, CommandProbe, PeerMode};
use crate::delivery::{self, Waiting};
use crate::dist::{self, Summary, format_ns};
use crate::report::{Report, Row, Unit, write_dist};
use crate::{
    BenchError, groups, io_phase, ipc, link_rate, peer, plots, python, roundtrip, rt, stream,
    sweep, wakeup, wire,
};

/// The numbered progress lines: `[n/total] what (duration)` on stderr.
struct Progress {
    done: usize,
    total: usize,
}

impl Progress {
    fn next(&mut self, what: &str, cli: &BenchArgs) {
        self.done += 1;
        eprintln!("[{}/{}] {what} ({:?})", self.done, self.total, cli.duration);
    }
}

fn rt_flags(flags: u32) -> String {
    let mut words = Vec::new();
    for (bit, word) in [
        (ServerStats::RT_FIFO, "SCHED_FIFO"),
        (ServerStats::RT_LOCKED, "memory locked"),
        (ServerStats::RT_PINNED, "pinned"),
        (ServerStats::RT_DMA_LATENCY, "cpu_dma_latency 0"),
    ] {
        if flags & bit != 0 {
            words.push(word);
        }
    }
    if words.is_empty() {
        "SCHED_OTHER, nothing locked or pinned".to_owned()
    } else {
        words.join(", ")
    }
}

/// Runs the suite against the live motiond instance `server` (`[server] name`), progress on
/// stderr. [`BenchError::NoServer`] when no such server ticks.
pub fn run(server: &str, cli: &BenchArgs) -> Result<Report, BenchError> {
    // --plot draws from the distribution files: without --out they go beside the pictures.
    let out = cli.out.as_deref().or(cli.plot.as_deref());
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let names = ServiceNames::new(server);
    let node = ipc::node("main")?;
    let frames = ipc::open_frames(&node, &names, ipc::OPEN_TIMEOUT).map_err(|e| {
        BenchError::NoServer(format!(
            "{e}: is motiond running with [server] name = \"{server}\"? Start it (`cargo run --release` \
             runs config/sim.toml, instance `demo`; a deployed server runs as the `motion` user: \
             `sudo -u motion motionctl bench`) or pass --server NAME."
        ))
    })?;
    let (period_ns, axis_count) = ipc::frame_timing(&frames, core::time::Duration::from_secs(3))
        .map_err(BenchError::NoServer)?;
    drop(frames);
    let hz = u32::try_from(1_000_000_000 / period_ns.max(1)).unwrap_or(u32::MAX);
    let stats = ipc::open_stats(&node, &names, ipc::OPEN_TIMEOUT)?;
    let stats_start = ipc::wait_stats(&stats, 0, core::time::Duration::from_millis(2500))?;
    let mut probe = cli.command;
    let mut report = Report::default();
    if probe == CommandProbe::ClaimRelease && axis_count == 0 {
        probe = CommandProbe::UnknownAxis;
        report.notes.push(
            "--command claim-release needs an axis; the server has none, so the round trip \
             used the unknown-axis probe"
                .to_owned(),
        );
    }
    // The Python client phase: an explicit --python must work (said now, not after the
    // run); without one, a missing or unusable target/py-venv skips the phase with a note.
    let python = match python::find_python(cli.python.as_deref()) {
        Ok(path) => Some(path),
        Err(error) if cli.python.is_some() => return Err(BenchError::Failed(error.to_string())),
        Err(error) => {
            report.notes.push(format!(
                "Python client rows: skipped: {error}. To enable: {}",
                python::HOW_TO_ENABLE
            ));
            None
        }
    };
    let mut progress = Progress {
        done: 0,
        total: 8 + usize::from(python.is_some()),
    };
    let dma = rt::DmaLatency::hold();
    report.context = vec![
        (
            "server".to_owned(),
            format!("motiond/{server}/… ({axis_count} axes, tick {hz} Hz)"),
        ),
        (
            "server real-time".to_owned(),
            stats_start.map_or("unknown (no stats yet)".to_owned(), |s| {
                rt_flags(s.rt_flags)
            }),
        ),
        (
            "bench cpu_dma_latency".to_owned(),
            match &dma {
                Ok(_) => "held at 0 for the whole run".to_owned(),
                Err(e) => format!("not held ({e})"),
            },
        ),
        (
            "phase duration".to_owned(),
            format!("{:?} each, one after the other", cli.duration),
        ),
        (
            "cores".to_owned(),
            std::thread::available_parallelism().map_or("?".to_owned(), |n| n.to_string()),
        ),
    ];
    eprintln!(
        "latency bench: motiond/{server} at {hz} Hz, {axis_count} axes; {} phases of {:?}{}{}",
        progress.total,
        cli.duration,
        if python.is_some() {
            " (the Python client's: 2 × that)"
        } else {
            ""
        },
        match (cli.command_to_wire, cli.axes_sweep) {
            (true, true) => ", the command-to-wire phase and the axes sweep",
            (true, false) => " and the command-to-wire phase",
            (false, true) => " and the axes sweep",
            (false, false) => "",
        }
    );

    progress.next("wake-up baseline: clock_nanosleep loop", cli);
    let sleeper = wakeup::measure(period_ns, cli.duration, cli.rt_priority, cli.cpu)?;
    // Wake-up: read before the bench's own busy-polling phases load the machine.
    let stats_quiet = ipc::wait_stats(
        &stats,
        stats_start.map_or(0, |s| s.tick),
        core::time::Duration::from_millis(2500),
    )?;
    progress.next("motiond frames, WaitSet client", cli);
    let ours_ws = delivery::measure(&names, Waiting::WaitSet, cli.duration, cli.rt_priority)?;
    progress.next("motiond frames, busy-polling client", cli);
    let ours_busy = delivery::measure(&names, Waiting::BusyPoll, cli.duration, cli.rt_priority)?;
    progress.next("motiond command round trip", cli);
    let ours_rtt = roundtrip::measure(&names, probe, axis_count, true, period_ns, cli.duration)?;
    let python_run = python.as_deref().and_then(|interpreter| {
        progress.next(
            &format!(
                "Python client: {} -m motiond.bench (frames, then command round trip)",
                interpreter.display()
            ),
            cli,
        );
        python::measure(interpreter, server, cli.duration)
            .map_err(|error| {
                eprintln!("  Python client phase failed: {error}");
                report.notes.push(format!(
                    "Python client rows: not measured this run: {error}"
                ));
            })
            .ok()
            .map(|run| (interpreter.display().to_string(), run))
    });
    // Work: read after the client phases, as the peer's own work covers its client phases.
    let stats_loaded = ipc::wait_stats(
        &stats,
        stats_quiet.map_or(0, |s| s.tick),
        core::time::Duration::from_millis(2500),
    )?;

    let peer = peer::Peer::start(PeerMode::Ticking, hz, cli.rt_priority, cli.cpu)?;
    progress.next("baseline peer frames, WaitSet client", cli);
    let base_ws = delivery::measure(&peer.names, Waiting::WaitSet, cli.duration, cli.rt_priority)?;
    progress.next("baseline peer frames, busy-polling client", cli);
    let base_busy = delivery::measure(
        &peer.names,
        Waiting::BusyPoll,
        cli.duration,
        cli.rt_priority,
    )?;
    progress.next("baseline peer request-response (answered per tick)", cli);
    let base_rtt = roundtrip::measure(&peer.names, probe, 0, true, period_ns, cli.duration)?;
    let peer_figures = peer.stop()?;
    let busy_peer = peer::Peer::start(PeerMode::BusyRr, hz, None, None)?;
    progress.next("baseline request-response, busy-polling server", cli);
    let floor_rtt = roundtrip::measure(&busy_peer.names, probe, 0, false, period_ns, cli.duration)?;
    busy_peer.stop()?;

    let scratch = || -> Result<std::path::PathBuf, String> {
        let dir = match out {
            Some(dir) => dir.to_path_buf(),
            None => std::env::temp_dir().join(format!("motiond-bench-{}", std::process::id())),
        };
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(dir)
    };
    let server_rt = sweep::ServerRt {
        priority: cli.rt_priority,
        cpu: cli.cpu,
    };
    // At the I/O threads' priority (one below the tick's): a board that outranked them
    // would preempt the I/O thread between its write(2) and its stamp.
    crate::rt::set_board_priority(cli.rt_priority.map(|p| p.saturating_sub(1).max(1)));
    let wire_run = if cli.command_to_wire {
        eprintln!(
            "[wire] command to wire: own motiond with four simulated boards ({:?} each), then each board's transport baseline ({:?} each)",
            cli.duration,
            (cli.duration / 3).max(core::time::Duration::from_secs(1))
        );
        match sweep::find_motiond(cli.motiond.as_deref())
            .and_then(|motiond| wire::run(&motiond, hz, server_rt, cli.duration, &scratch()?))
        {
            Ok(run) => Some(run),
            Err(e) => {
                report.notes.push(format!(
                    "command → first byte on the wire (µs): not measured this run: {e}"
                ));
                None
            }
        }
    } else {
        report.notes.push(
            "command → first byte on the wire (µs): skipped (--command-to-wire=false)".to_owned(),
        );
        None
    };

    let io_run = if cli.io_phase {
        eprintln!(
            "[io] own motiond with four idle external links: CPU ({:?}{}), reply → read ({:?}), \
             then the baselines",
            cli.duration,
            if cli.io_before.is_some() {
                ", and again with --io-before"
            } else {
                ""
            },
            (cli.duration / 2).max(core::time::Duration::from_secs(1))
        );
        match sweep::find_motiond(cli.motiond.as_deref()).and_then(|motiond| {
            io_phase::run(
                &motiond,
                cli.io_before.as_deref(),
                hz,
                server_rt,
                cli.duration,
                &scratch()?,
            )
        }) {
            Ok(run) => Some(run),
            Err(e) => {
                report.notes.push(format!(
                    "I/O phase (CPU, reply → read): not measured this run: {e}"
                ));
                None
            }
        }
    } else {
        report
            .notes
            .push("I/O phase (CPU, reply → read): skipped (--io-phase=false)".to_owned());
        None
    };

    let groups_run = if cli.groups {
        eprintln!(
            "[groups] own motiond on config/sim.toml: a trajectory on gantry and base, three \
             gantry lines and their single-axis baseline, a velocity stream to base and its \
             plain peer pair"
        );
        match sweep::find_motiond(cli.motiond.as_deref()).and_then(|motiond| {
            groups::run(
                &motiond,
                hz,
                server_rt,
                cli.rt_priority,
                cli.duration,
                &scratch()?,
                python.as_deref().map(|path| (path, cli.busy_loops)),
            )
        }) {
            Ok(run) => Some(run),
            Err(e) => {
                report.notes.push(format!(
                    "coordinated motion (tracking, arrival skew, streaming): not measured this \
                     run, an error: {e}"
                ));
                None
            }
        }
    } else {
        report.notes.push(
            "coordinated motion (tracking, arrival skew, streaming): skipped (--groups=false)"
                .to_owned(),
        );
        None
    };

    let link_rate_run = if cli.link_rate {
        eprintln!(
            "[link-rate] own motiond with two simulated SIXpacks, at {} and {} baud ({:?})",
            link_rate::FACTORY_BAUD,
            link_rate::FAST_BAUD,
            cli.duration
        );
        match sweep::find_motiond(cli.motiond.as_deref())
            .and_then(|motiond| link_rate::run(&motiond, hz, server_rt, cli.duration, &scratch()?))
        {
            Ok(run) => Some(run),
            Err(e) => {
                report.notes.push(format!(
                    "SIXpack refresh at two baud rates: not measured this run: {e}"
                ));
                None
            }
        }
    } else {
        report
            .notes
            .push("SIXpack refresh at two baud rates: skipped (--link-rate=false)".to_owned());
        None
    };

    if cli.axes_sweep {
        eprintln!(
            "[sweep] motiond at 4, 16, 64, 128 simulated axes ({:?} each)",
            cli.duration
        );
        match sweep::find_motiond(cli.motiond.as_deref()) {
            Ok(motiond) => {
                let dir = scratch()?;
                report.sweep = sweep::run(&motiond, hz, cli.duration, &dir);
                report.sweep_baseline = Some(peer_figures.work);
            }
            Err(e) => report.notes.push(format!("axes sweep not run: {e}")),
        }
    }

    let window = |read: Option<ServerStats>, when: &str| match (stats_start, read) {
        (_, None) => "no ServerStats received".to_owned(),
        (start, Some(end)) => format!(
            "ServerStats since motiond started, read at tick {} {when}{}; {} overruns",
            end.tick,
            start.map_or(String::new(), |s| format!(
                "; tick {} when the bench began",
                s.tick
            )),
            end.overruns
        ),
    };
    let quiet = stats_quiet.unwrap_or(ServerStats::EMPTY);
    let loaded = stats_loaded.unwrap_or(ServerStats::EMPTY);
    let ticks_of = |run: &roundtrip::RoundTripRun| run.ticks.as_ref().map(dist::Dist::summary);
    let reasons = |run: &roundtrip::RoundTripRun| {
        let list: Vec<String> = run
            .reasons
            .iter()
            .map(|(k, v)| format!("{k} ×{v}"))
            .collect();
        format!("replies: {}; lost {}", list.join(", "), run.lost)
    };
    let probe_text = match probe {
        CommandProbe::UnknownAxis => format!(
            "probe: Stop on axis {axis_count} (one past the last), answered UnknownAxis — \
             validated like any command, moves nothing, works without devices"
        ),
        CommandProbe::ClaimRelease => {
            "probe: Claim/Release pairs on axis 0 — no motion, the claim is held for one round trip"
                .to_owned()
        }
    };
    report.rows = vec![
        Row {
            figure: "tick wake-up latency (actual wake − deadline)".to_owned(),
            unit: Unit::Ns,
            ours: quiet.wakeup.into(),
            baseline: Some(sleeper.latency.summary()),
            baseline_label: format!(
                "bare clock_nanosleep(TIMER_ABSTIME) loop at {hz} Hz in this bench: {}; {} overruns",
                sleeper.thread, sleeper.overruns
            ),
            note: format!(
                "server: {}; the baseline ran for {:?} while motiond kept ticking",
                window(stats_quiet, "right after the wake-up baseline phase"),
                cli.duration
            ),
        },
        Row {
            figure: "tick deadline → frame publish (wake-up + work up to the send), frames seen in this run".to_owned(),
            unit: Unit::Ns,
            ours: ours_ws.deadline_to_publish.summary(),
            baseline: Some(base_ws.deadline_to_publish.summary()),
            baseline_label: "plain iceoryx2 peer ticking at the same rate, publishing the same 8232-byte payload".to_owned(),
            note: "from MotionFrame.time_ns (deadline) and publish_ns, during the WaitSet phase".to_owned(),
        },
        Row {
            figure: "frame delivery, client blocked in a WaitSet on the tick event".to_owned(),
            unit: Unit::Ns,
            ours: ours_ws.latency.summary(),
            baseline: Some(base_ws.latency.summary()),
            baseline_label: "plain iceoryx2 publish-subscribe + event of an 8232-byte payload between two plain processes".to_owned(),
            note: format!(
                "publish_ns → sample in hand (CLOCK_MONOTONIC); client {}; lost ticks: ours {}, baseline {}",
                ours_ws.thread, ours_ws.lost, base_ws.lost
            ),
        },
        Row {
            figure: "frame delivery, client busy-polling".to_owned(),
            unit: Unit::Ns,
            ours: ours_busy.latency.summary(),
            baseline: Some(base_busy.latency.summary()),
            baseline_label: "plain iceoryx2 publish-subscribe of an 8232-byte payload, busy-polling subscriber".to_owned(),
            note: format!("lost ticks: ours {}, baseline {}", ours_busy.lost, base_busy.lost),
        },
        Row {
            figure: "command round trip (request sent → reply received, client busy-polls)".to_owned(),
            unit: Unit::Ns,
            ours: ours_rtt.rtt.summary(),
            baseline: Some(base_rtt.rtt.summary()),
            baseline_label: format!(
                "plain iceoryx2 request-response, peer answering at the start of each {hz} Hz tick as motiond does"
            ),
            note: format!(
                "{probe_text}; requests sent at random tick phases, so both wait on average half a tick; ours: {}; baseline: {}",
                reasons(&ours_rtt),
                reasons(&base_rtt)
            ),
        },
        Row {
            figure: "command round trip vs the transport floor".to_owned(),
            unit: Unit::Ns,
            ours: ours_rtt.rtt.summary(),
            baseline: Some(floor_rtt.rtt.summary()),
            baseline_label: "plain iceoryx2 request-response, busy-polling server and client".to_owned(),
            note: format!(
                "the ratio is mostly motiond's by-design wait for its next tick; baseline: {}",
                reasons(&floor_rtt)
            ),
        },
        Row {
            figure: "command → applied, in ticks (reply.tick_applied − newest frame tick at send)".to_owned(),
            unit: Unit::Ticks,
            ours: ticks_of(&ours_rtt).unwrap_or_default(),
            baseline: ticks_of(&base_rtt),
            baseline_label: "the ticking plain peer, same computation".to_owned(),
            note: "the unknown-axis (or claim/release) probe of row 5, against the running server".to_owned(),
        },
        Row {
            figure: "tick work time (wake → end of the tick's work)".to_owned(),
            unit: Unit::Ns,
            ours: loaded.work.into(),
            baseline: Some(peer_figures.work),
            baseline_label: "the plain peer's own tick: answer requests, loan, write 8232 bytes, send, notify".to_owned(),
            note: format!(
                "server: {}; {axis_count} axes; the baseline is the peer's work during its own client phases",
                window(stats_loaded, "after the client phases (frames, commands)")
            ),
        },
    ];
    if let Some(run) = &wire_run {
        report.rows.extend(wire::rows(run, ticks_of(&base_rtt)));
    }
    if let Some(run) = &io_run {
        let rows = io_phase::rows(run, hz, wire_run.as_ref(), out, &mut report.notes);
        report.rows.extend(rows);
    }
    if let Some(run) = &groups_run {
        report.rows.extend(groups::rows(run));
        report.notes.extend(groups::notes(run));
        match &run.stream {
            Ok(streamed) => report.rows.extend(stream::rows(streamed)),
            Err(e) => report.notes.push(format!(
                "streaming setpoints: not measured this run, an error: {e}"
            )),
        }
    }
    if let Some(run) = &link_rate_run {
        report.rows.extend(link_rate::rows(run));
        for (slug, title, dist) in link_rate::files(run) {
            if let Some(error) = write_dist(out, &slug, &title, dist) {
                report.notes.push(format!("could not write {error}"));
            }
        }
    }
    if let Some((interpreter, run)) = &python_run {
        report.rows.extend(python::rows(
            run,
            ours_ws.latency.summary(),
            ours_rtt.rtt.summary(),
            probe,
        ));
        report.context.push((
            "python client".to_owned(),
            format!("{interpreter}: {}, iceoryx2 {}", run.python, run.iceoryx2),
        ));
        for (slug, title, dist) in [
            (
                "frame-python-motiond",
                "frame delivery, Python client (client.frames())",
                &run.frames,
            ),
            (
                "command-rtt-python-motiond",
                "command round trip, Python client (Client.command)",
                &run.rtt,
            ),
        ] {
            if let Some(error) = write_dist(out, slug, title, dist) {
                report.notes.push(format!("could not write {error}"));
            }
        }
    }
    report.notes.push(format!(
        "the server's wake-up and work figures (rows 1, 8) are motiond's own since it started \
         (ServerStats has percentiles, not histograms), while the baselines cover this run only; \
         row 2 is this run's window from the frames (wake-up p50 {} in the baseline peer's own histogram)",
        format_ns(peer_figures.wakeup.p50)
    ));
    let files: [(&str, &str, &dist::Dist); 10] = [
        (
            "wakeup-baseline-sleeper",
            "wake-up, bare clock_nanosleep loop",
            &sleeper.latency,
        ),
        (
            "deadline-to-publish-motiond",
            "deadline → publish, motiond",
            &ours_ws.deadline_to_publish,
        ),
        (
            "deadline-to-publish-baseline",
            "deadline → publish, plain peer",
            &base_ws.deadline_to_publish,
        ),
        (
            "frame-waitset-motiond",
            "frame delivery, WaitSet, motiond",
            &ours_ws.latency,
        ),
        (
            "frame-waitset-baseline",
            "frame delivery, WaitSet, plain peer",
            &base_ws.latency,
        ),
        (
            "frame-busy-motiond",
            "frame delivery, busy-poll, motiond",
            &ours_busy.latency,
        ),
        (
            "frame-busy-baseline",
            "frame delivery, busy-poll, plain peer",
            &base_busy.latency,
        ),
        (
            "command-rtt-motiond",
            "command round trip, motiond",
            &ours_rtt.rtt,
        ),
        (
            "command-rtt-baseline-ticking",
            "request-response, ticking plain peer",
            &base_rtt.rtt,
        ),
        (
            "command-rtt-baseline-busy",
            "request-response, busy-polling plain peer",
            &floor_rtt.rtt,
        ),
    ];
    for (slug, title, dist) in files {
        if let Some(error) = write_dist(out, slug, title, dist) {
            report.notes.push(format!("could not write {error}"));
        }
    }
    if let Some(run) = &wire_run {
        for (slug, title, dist) in wire::files(run) {
            if let Some(error) = write_dist(out, &slug, &title, dist) {
                report.notes.push(format!("could not write {error}"));
            }
        }
    }
    if let Some(run) = &groups_run {
        let mut files = groups::files(run);
        if let Ok(streamed) = &run.stream {
            files.extend(stream::files(streamed));
        }
        for (slug, title, dist) in files {
            if let Some(error) = write_dist(out, &slug, &title, dist) {
                report.notes.push(format!("could not write {error}"));
            }
        }
    }
    for (slug, run) in [
        ("command-ticks-motiond", &ours_rtt),
        ("command-ticks-baseline", &base_rtt),
    ] {
        if let Some(ticks) = &run.ticks
            && let Some(error) = write_dist(out, slug, "command → applied, ticks", ticks)
        {
            report.notes.push(format!("could not write {error}"));
        }
    }
    if let Some(dir) = out {
        report
            .context
            .push(("distributions".to_owned(), dir.display().to_string()));
    }
    report.context.push((
        "baseline summaries".to_owned(),
        summary_line(&peer_figures.wakeup),
    ));
    if let (Some(plot_dir), Some(dist_dir)) = (cli.plot.as_deref(), out) {
        match plots::write(dist_dir, plot_dir, &report, &plots::caption_lines()) {
            Ok(names) => eprintln!(
                "[plot] {} pictures and index.html in {}",
                names.len(),
                plot_dir.display()
            ),
            Err(error) => report.notes.push(format!("plots not written: {error}")),
        }
    }
    Ok(report)
}

fn summary_line(s: &Summary) -> String {
    format!(
        "p50 {} p99 {} max {} (the plain peer's own tick, during its client phases)",
        format_ns(s.p50),
        format_ns(s.p99),
        format_ns(s.max)
    )
}
