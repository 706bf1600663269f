//! The robot with issue 29's per-tick features at work.

use super::*;

/// `config/sim.toml` with the QSB-M's probe input and camera trigger of issue 29 (a
/// `capture` signal on DIG I/O 3, a `trigger` signal pulsing io0 when the feeder passes
/// 2 mm).
fn robot_with_capture_and_trigger() -> Robot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
    let text = std::fs::read_to_string(&path).expect("config/sim.toml");
    let device = "name = \"feeder_qsb\"\n";
    assert!(text.contains(device));
    // io0 becomes the trigger output and io3 the probe (io1 and io2 step the drive): the
    // jam sensor on io0 and the drive's enable on io3 go.
    let jam = text
        .find("[[signal]]\nname = \"feeder_jam\"")
        .expect("the jam sensor");
    let next = jam + text[jam + 1..].find("\n[[").expect("a table after it") + 2;
    let text = format!("{}{}", &text[..jam], &text[next..]);
    let text: String = text
        .lines()
        .filter(|line| !line.starts_with("enable_output") && !line.starts_with("enable_active"))
        // Without the enable line the drive cannot be switched off: the feeder holds.
        .map(|line| match line.starts_with("estop = \"stop-off\"") {
            true => "estop = \"hold\"\n".to_owned(),
            false => format!("{line}\n"),
        })
        .collect();
    let text = text.replacen(
        device,
        "name = \"feeder_qsb\"\ncapture_input = 3\ntrigger_on = [\"match\"]\ncompare_position = 2.0\n",
        1,
    );
    let text = format!(
        "{text}\n[[signal]]\nname = \"probe\"\ndevice = \"feeder_qsb\"\npin = \"capture\"\nkind = \"capture\"\n\n\
         [[signal]]\nname = \"camera\"\ndevice = \"feeder_qsb\"\npin = \"trigger\"\nkind = \"trigger\"\n"
    );
    let config = ServerConfig::parse(&path, &text).expect("sim.toml with a probe and a trigger");
    Robot::with(config)
}

/// Issue 29's per-tick work allocates nothing either: an axis's own hold and resume (the
/// QSB-M's COMMAND 6 / 7, the server's on the SIXpack), PI targets changed on the fly
/// (`camera_pan`, `position_mode = "pi"`), the power-down state polled once a second
/// (`pack_aux`, `power_down = "restore"`), the trigger's compare position changed at run
/// time and its pulses as events, the capture register read.
#[test]
fn holds_pi_targets_power_down_polls_and_trigger_events_allocate_nothing() {
    let mut robot = robot_with_capture_and_trigger();
    run(&mut robot, 0, 4000, |_| {});
    let online = robot
        .frame
        .axes()
        .iter()
        .all(|a| !a.flags().contains(AxisFlags::STALE));
    assert!(online, "every board answers: {:?}", robot.frame.axes());
    let camera = robot
        .engine
        .config()
        .signals
        .iter()
        .position(|s| s.name == "camera")
        .expect("the trigger") as u32;
    let (x, feeder, pan) = (
        robot.axis("x"),
        robot.axis("feeder"),
        robot.axis("camera_pan"),
    );
    let client = ClientId::from_u128(43);
    let mut sequence = 0;
    let mut request = |robot: &mut Robot, axis: u32, kind: CommandKind, values: [f64; 3]| {
        sequence += 1;
        robot
            .port
            .requests
            .push_back(CommandRequest::new(client, sequence, axis, kind).with_values(values));
    };
    let pulses_before = robot.frame.signals()[camera as usize].sequence;
    let replies_before = robot.port.replies.len();
    let before = allocations();
    let mut held = (false, false);
    for tick in 0..8000u64 {
        match tick {
            10 => {
                request(
                    &mut robot,
                    feeder,
                    CommandKind::RampPosition,
                    [8.0, 4.0, 0.0],
                );
                request(&mut robot, x, CommandKind::RampPosition, [6.0, 2.0, 0.0]);
                request(&mut robot, pan, CommandKind::Position, [40.0, 0.0, 0.0]);
            }
            600 => {
                request(&mut robot, feeder, CommandKind::Hold, [0.0; 3]);
                request(&mut robot, x, CommandKind::Hold, [0.0; 3]);
                request(&mut robot, pan, CommandKind::Position, [-30.0, 0.0, 0.0]);
            }
            1500 => {
                request(&mut robot, feeder, CommandKind::Resume, [0.0; 3]);
                request(&mut robot, x, CommandKind::Resume, [0.0; 3]);
                request(&mut robot, pan, CommandKind::Position, [10.0, 0.0, 0.0]);
            }
            4000 => {
                let compare =
                    CommandRequest::for_signal(client, 9000, camera, CommandKind::SetOutput)
                        .with_values([5.0, 0.0, 0.0]);
                robot.port.requests.push_back(compare);
                request(
                    &mut robot,
                    feeder,
                    CommandKind::RampPosition,
                    [0.0, 4.0, 0.0],
                );
            }
            _ => {}
        }
        robot.tick();
        if tick == 1400 {
            let flags = |axis: u32| robot.frame.axes[axis as usize].flags();
            held = (
                flags(feeder).contains(AxisFlags::HELD),
                flags(x).contains(AxisFlags::HELD),
            );
        }
    }
    let allocations = allocations() - before;
    assert_eq!(
        allocations, 0,
        "the engine allocated {allocations} times in 8000 steps"
    );
    // The script did what it says: every request taken, both moves held and resumed to
    // their targets, the trigger pulsed on the way.
    let replies = &robot.port.replies[replies_before..];
    assert_eq!(replies.len(), 11, "{replies:?}");
    let refused: Vec<_> = replies.iter().filter(|r| r.result().is_err()).collect();
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(held, (true, true), "held at tick 1400");
    // The PI controller holds within a count of its target (0.11 deg on camera_pan).
    for (axis, target, within) in [(feeder, 0.0, 0.05), (x, 6.0, 0.05), (pan, 10.0, 0.2)] {
        let state = robot.frame.axes[axis as usize];
        assert!(
            (state.position - target).abs() < within,
            "axis {axis} at {} not {target}",
            state.position
        );
    }
    let camera_state = robot.frame.signals()[camera as usize];
    assert!(camera_state.sequence > pulses_before, "{camera_state:?}");
    assert_eq!(camera_state.value, 5.0, "the new compare position");
}
