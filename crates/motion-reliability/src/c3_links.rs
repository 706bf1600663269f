//! Campaign 3, links. Unplug: the QSB-M's serial link (a pty this process serves) is
//! unplugged and a fresh board plugged in on the same path, again and again, while the
//! axes of the two other links (a SIXpack on a pty, an SPI_motor stepper on an SPI socket)
//! keep moving; their refresh age (frame tick − the axis's last refresh tick) must not
//! suffer, the new board must be handshaken again, and the goal the axis had when its link
//! went must not be resumed. Noise: see [`crate::c3_noise`].

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::bail;
use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use iceoryx2::prelude::ipc;
use motion_client::{Client, ClientBuilder};
use motion_ipc::{AxisFlags, AxisMode, DeviceState, FaultCode};
use motion_testkit::RawClient;
use motion_testkit::pty_board::{PtyBoard, PtyOptions};
use motion_testkit::socket_board::SocketBoard;

use crate::boards::{
    is_qsb_motion, new_qsb, new_stepper, qsb_lines, qsb_section, serve_qsb, server_section,
    spimotor_section, tmcpack_section,
};
use crate::c1_dead_clients::online;
use crate::harness::{Harness, Samples, TickMeter};
use crate::report::Row;

/// Keeps `x` (the SIXpack) and `focus` (the stepper) moving back and forth.
struct Motion<'c> {
    x: motion_client::Axis<'c, ipc::Service>,
    focus: motion_client::Axis<'c, ipc::Service>,
    leg: u32,
    next: Instant,
}

impl Motion<'_> {
    fn tick(&mut self) {
        if Instant::now() < self.next {
            return;
        }
        self.leg += 1;
        let sign = if self.leg.is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        let _ = self.x.ramp_to(sign * 5.0, 10.0, 0.0);
        let _ = self.focus.ramp_to(sign * 500.0, 500.0, 0.0);
        self.next = Instant::now() + Duration::from_millis(1200);
    }

    fn run_for(&mut self, time: Duration) {
        let end = Instant::now() + time;
        while Instant::now() < end {
            self.tick();
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// Runs the unplug part.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let count = if h.quick { 3 } else { 100 };
    let quiet_time = Duration::from_secs(if h.quick { 3 } else { 30 });
    let mut row = Row::new("3a links: unplug/replug");
    row.runs = format!(
        "{count} × unplug/replug of the QSB's serial link, the SIXpack and the stepper moving"
    );
    let name = h.name("plug");
    let epoch = Instant::now();
    let tty = h.path(&format!("{name}-qsb.tty"));
    let pack_tty = h.path(&format!("{name}-pack.tty"));
    let socket = h.path(&format!("{name}.sock"));
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let stepper = new_stepper();
    let mut qsb = new_qsb();
    let mut qsb_board = serve_qsb(&tty, &qsb, epoch, PtyOptions::default())?;
    let _pack_board = PtyBoard::try_start(
        &pack_tty,
        Arc::clone(&pack),
        epoch,
        19_200,
        PtyOptions::default(),
    )?;
    let _stepper_board = SocketBoard::try_start(&socket, Arc::clone(&stepper), epoch)?;
    let config = h.write(
        &format!("{name}.toml"),
        &format!(
            "{}{}{}{}",
            server_section(&name, ""),
            qsb_section(&tty),
            tmcpack_section(&pack_tty),
            spimotor_section(&socket)
        ),
    )?;
    let mut server = h.server(&config)?;
    let raw = RawClient::try_connect(&name, Duration::from_secs(10))?;
    match raw.try_wait_frame(Duration::from_secs(20), |f| (0..3).all(|a| online(f, a))) {
        Some((_, true)) => {}
        other => bail!(
            "not every board online: {:?}",
            other.map(|(f, _)| f.axes()[..3].to_vec())
        ),
    }
    let client: Client<ipc::Service> = ClientBuilder::new(&name)
        .connect_timeout(Duration::from_secs(10))
        .connect()?;
    let feeder = client.axis("feeder")?;
    let mut motion = Motion {
        x: client.axis("x")?,
        focus: client.axis("focus")?,
        leg: 0,
        next: Instant::now(),
    };
    let meter = TickMeter::start(&name)?;
    motion.run_for(Duration::from_millis(500));
    let _ = meter.take();
    motion.run_for(quiet_time);
    let quiet = meter.take();
    let (mut not_down, mut not_back, mut no_handshake, mut resumed) = (0u32, 0u32, 0u32, 0u32);
    let mut down = Samples::default();
    let mut back = Samples::default();
    let mut problems = Vec::new();
    for i in 0..count {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        let _ = feeder.ramp_to(sign * 300.0, 20.0, 0.0);
        motion.run_for(Duration::from_millis(60));
        let unplugged = Instant::now();
        qsb_board.unplug();
        let gone = wait(&mut motion, &raw, Duration::from_secs(5), |f| {
            let a = f.axes()[0];
            a.fault() == Ok(FaultCode::LinkDown) || a.device_state() != Ok(DeviceState::Online)
        });
        if gone {
            down.push(unplugged.elapsed().as_secs_f64() * 1e3);
        } else {
            not_down += 1;
        }
        // A fresh board on the same path, as after a power cycle of the adapter.
        qsb = new_qsb();
        let replugged = Instant::now();
        qsb_board = serve_qsb(&tty, &qsb, epoch, PtyOptions::default())?;
        let up = wait(&mut motion, &raw, Duration::from_secs(10), |f| {
            online(f, 0) && !f.axes()[0].flags().contains(AxisFlags::FAULT)
        });
        if up {
            back.push(replugged.elapsed().as_secs_f64() * 1e3);
        } else {
            not_back += 1;
            if problems.len() < 5 {
                problems.push(format!(
                    "replug #{i}: not back: {:?}",
                    raw.frame().axes()[0]
                ));
            }
        }
        motion.run_for(Duration::from_millis(300));
        let lines = qsb_lines(
            &qsb_board
                .received
                .lock()
                .map(|l| l.clone())
                .unwrap_or_default(),
        );
        let probed = lines.iter().any(|l| l.line.ty == qsb::CommandType::Read);
        no_handshake += u32::from(!probed);
        let axis = raw.frame().axes()[0];
        let moving = qsb
            .lock()
            .map(|b| b.motor_velocity() != 0.0)
            .unwrap_or(true);
        let stale_goal = moving
            || lines.iter().any(|l| is_qsb_motion(&l.line))
            || matches!(axis.mode(), Ok(AxisMode::RampPosition | AxisMode::Position));
        if stale_goal {
            resumed += 1;
            if problems.len() < 5 {
                problems.push(format!("replug #{i}: the old goal went on: {axis:?}"));
            }
        }
    }
    let loaded = meter.take();
    row.figure(
        "unplug → LinkDown/offline in the frame",
        down.p50_p99_max(1.0, "ms"),
    );
    row.figure("replug → online", back.p50_p99_max(1.0, "ms"));
    for (axis, label) in [(1usize, "SIXpack x"), (2, "stepper focus")] {
        let q = quiet
            .refresh_age
            .get(axis)
            .map_or(f64::NAN, |s| s.quantile(0.999));
        let l = loaded
            .refresh_age
            .get(axis)
            .map_or(f64::NAN, |s| s.quantile(0.999));
        row.figure(
            &format!("{label} refresh age p99.9"),
            format!("quiet {q:.0} / unplugging {l:.0} ticks"),
        );
        row.target(&format!("{label} refresh age p99.9"), l, q, 1.1);
    }
    row.check(
        "every unplug seen, every replug back",
        not_down == 0 && not_back == 0,
        format!("{not_down} unplugs not seen in 5 s, {not_back} replugs not online in 10 s"),
    );
    row.check(
        "the new board handshaken",
        no_handshake == 0,
        format!("{no_handshake} of {count} fresh boards got no request"),
    );
    row.check(
        "no stale goal resumed",
        resumed == 0,
        format!("{resumed} of {count} fresh boards were set moving by the old goal"),
    );
    h.check_alive_and_stop(&mut row, &mut server);
    for problem in problems {
        row.note(problem);
    }
    Ok(row)
}

/// Waits for `done` on the newest frame, keeping the other axes moving.
fn wait(
    motion: &mut Motion<'_>,
    raw: &RawClient,
    timeout: Duration,
    mut done: impl FnMut(&motion_ipc::MotionFrame) -> bool,
) -> bool {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        motion.tick();
        if raw
            .try_frame(Duration::from_millis(100))
            .is_some_and(|f| done(&f))
        {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}
