//! A pack whose answers are held on the host side (issue 39 item 4: "a reply delayed on
//! the host — the server or the board's process starved for up to 200 ms — is never a
//! reset"): on the fake clock, the simulated link holds every answer the pack gives for
//! 50, 100 and 200 ms while a position move runs. The pack is on RS-232 (manual 6.1: "The
//! RS 232 interface can be used accordingly"), whose receive wire is the host's alone: an
//! answer held there keeps nobody from sending (on the half-duplex pair of the sim link a
//! held answer would take the line at its late instant, and a request written before it,
//! legitimately, would queue behind it — a collision the starved pack causes, not the
//! host). The driver counts the unanswered queries,
//! drops their late answers, and neither declares the pack not answering nor reset: the
//! move keeps its goal and arrives, and the pack never sees a request while an answer of
//! its own was still due (manual 7.1).

use super::*;

#[test]
fn answers_held_for_50_100_200_ms_are_no_verdict_and_the_move_arrives() {
    for hold in [50u64, 100, 200] {
        let hold = Duration::from_millis(hold);
        let (mut rig, board, faults) = rs232();
        wait_online(&mut rig, 2);
        accepted(&mut rig, 0, CommandKind::Position, [40.0, 0.0, 0.0]);
        rig.run(200);
        assert!(motor(&board, 0).action == Action::Ramp, "under way");
        let status = |rig: &Rig| rig.engine.driver(0).expect("device 0").status();
        let before = status(&rig);
        faults.set_reply_delay(hold);
        let until = rig.now + hold;
        while rig.now < until {
            rig.tick();
            assert!(status(&rig).online, "{hold:?}: online throughout");
        }
        faults.set_reply_delay(Duration::ZERO);
        move_and_check(
            &mut rig,
            &board,
            0,
            0,
            40.0,
            MAX_VELOCITY_MM,
            Duration::from_secs(5),
        );
        let after = status(&rig);
        assert!(
            after.timeouts > before.timeouts,
            "{hold:?}: the held answers were missed"
        );
        assert_eq!(after.verdicts, 0, "{hold:?}: {:?}", after.verdict);
        assert_eq!(after.resets, 0, "{hold:?}");
        assert_eq!(after.fault, None, "{hold:?}");
        assert!(after.online);
        assert_eq!(rig.axis(0).fault, FaultCode::None as u16, "{hold:?}");
        let stats = board.lock().unwrap().stats();
        assert_eq!(stats.interlaced, 0, "{hold:?}: manual 7.1");
        assert_eq!(stats.replaced_replies, 0, "{hold:?}");
    }
}

/// One SIXpack at address 1 on RS-232 (full duplex), axes x and y on motors 0 and 1.
fn rs232() -> (Rig, Pack, SimFaults) {
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    let link = SimLink::stream_with("rs232", BAUD, Duplex::Full, wire);
    let faults = link.faults();
    let config = engine_config(
        vec![device("pack", 1)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let driver = driver(1, Variant::SixPack, &[0, 1], 0);
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}
