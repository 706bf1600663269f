//! The `estop` event with its listener off the tick's hot path (`motiond::estop_watch`): a
//! thread `estop-watch` sleeps on the listener's descriptor and the tick asks the listener
//! only when it says so. Every notification latches the e-stop, again after each reset,
//! and a burst of them is one latch, never a stuck or spinning watch.

mod support;

use core::time::Duration;

use iceoryx2::prelude::*;
use motion_ipc::{CommandKind, CommandRequest, FrameFlags, MotionFrame, ServiceNames};
use nix::sys::signal::Signal;
use support::*;

fn latched(frame: &MotionFrame) -> bool {
    frame.flags().contains(FrameFlags::ESTOP_LATCHED)
}

/// Jiffies of CPU (user + system) the thread `comm` of `pid` has used.
fn thread_jiffies(pid: u32, comm: &str) -> Option<u64> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).ok()?;
    for task in tasks.flatten() {
        if std::fs::read_to_string(task.path().join("comm")).is_ok_and(|n| n.trim() == comm) {
            let stat = std::fs::read_to_string(task.path().join("stat")).ok()?;
            // Fields after the command's closing parenthesis: state is field 3, utime 14.
            let rest = &stat[stat.rfind(')')? + 2..];
            let fields: Vec<&str> = rest.split(' ').collect();
            let utime: u64 = fields.get(11)?.parse().ok()?;
            let stime: u64 = fields.get(12)?.parse().ok()?;
            return Some(utime + stime);
        }
    }
    None
}

#[test]
fn every_estop_notification_latches_again_after_each_reset() {
    let name = unique_name("estopev");
    let mut server = Server::start(&stepper_config(&name, ""));
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (_, up) = client.wait_frame(Duration::from_secs(10), |f| {
        f.device_state(0) == motion_ipc::DeviceState::Online
    });
    assert!(up);
    assert!(
        thread_names(server.pid())
            .iter()
            .any(|t| t == "estop-watch"),
        "the listener's watch runs"
    );
    let node = NodeBuilder::new().create::<ipc::Service>().expect("a node");
    let service = ServiceName::new(&ServiceNames::new(&name).estop()).expect("a name");
    let notifier = node
        .service_builder(&service)
        .event()
        .open()
        .expect("the estop event")
        .notifier_builder()
        .create()
        .expect("a notifier");
    for round in 0..3 {
        // A burst: one latch.
        for _ in 0..=round {
            assert_eq!(notifier.notify().expect("notify"), 1, "one listener");
        }
        let (frame, seen) = client.wait_frame(Duration::from_secs(5), latched);
        assert!(seen, "round {round}: not latched: {:?}", frame.flags());
        let reply = client.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3]);
        assert!(reply.result().is_ok(), "round {round}: {reply:?}");
        let (frame, cleared) = client.wait_frame(Duration::from_secs(5), |f| !latched(f));
        assert!(
            cleared,
            "round {round}: reset did not clear: {:?}",
            frame.flags()
        );
        // Nothing more arrives: the burst was taken whole, the watch sleeps again.
        std::thread::sleep(Duration::from_millis(100));
        assert!(
            !latched(&client.frame()),
            "round {round}: latched again by itself"
        );
    }
    // Asleep, not spinning: the watch used (nearly) no CPU in a second of quiet.
    let before = thread_jiffies(server.pid(), "estop-watch").expect("its stat");
    std::thread::sleep(Duration::from_secs(1));
    let after = thread_jiffies(server.pid(), "estop-watch").expect("its stat");
    assert!(
        after - before <= 2,
        "the watch ran {} jiffies in a quiet second",
        after - before
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
