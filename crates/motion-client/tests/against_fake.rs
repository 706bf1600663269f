//! The client against the fake server of `motion_client::testing` (same services, same
//! types). Every wait has a timeout; every test uses its own instance name.

use core::ops::ControlFlow;
use core::time::Duration;

use iceoryx2::prelude::{ipc, local};
use iceoryx2::service::Service;
use motion_client::ipc::{AxisFlags, AxisMode, CommandKind, CommandRequest, Reason};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientBuilder, ClientError, ConnectError};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(5);

fn start<S: Service>(prefix: &str) -> Result<(FakeServer, Client<S>)> {
    let server = FakeServer::start::<S>(FakeConfig::demo(&unique_name(prefix)))?;
    let client = Client::<S>::connect(server.name())?;
    Ok((server, client))
}

#[test]
fn connect_without_server_fails_clearly() {
    let name = unique_name("nobody");
    let error = ClientBuilder::new(&name)
        .connect_timeout(Duration::from_millis(100))
        .connect::<local::Service>()
        .expect_err("no server runs");
    assert!(matches!(error, ConnectError::NoServer { .. }), "{error:?}");
    let message = error.to_string();
    assert!(
        message.contains(&name) && message.contains("motiond"),
        "{message}"
    );
}

#[test]
fn info_describes_axes_and_handles_find_them() -> Result {
    let (_server, client) = start::<local::Service>("info")?;
    let info = client.info()?;
    let names: Vec<&str> = info.axes().iter().map(|axis| axis.name()).collect();
    assert_eq!(names, ["x", "y", "a"]);
    assert_eq!(info.axes()[2].unit(), "deg");
    assert_eq!(info.command_timeout_ms, 250);
    let y = client.axis("y")?;
    assert_eq!((y.index(), y.name()), (1, "y".to_owned()));
    assert_eq!(y.info().max, 100.0);
    let missing = client.axis("nope").expect_err("no such axis");
    assert!(matches!(missing, ClientError::UnknownAxis(_)));
    assert_eq!(client.axes().len(), 3);
    Ok(())
}

#[test]
fn frames_arrive_in_order_and_latest_is_newest() -> Result {
    let (_server, client) = start::<local::Service>("frames")?;
    let first = client.next_frame(WAIT)?.tick;
    let mut last = first;
    for frame in client.frames(WAIT).take(20) {
        let tick = frame?.tick;
        assert!(tick > last, "ticks go up: {tick} after {last}");
        last = tick;
    }
    std::thread::sleep(Duration::from_millis(20));
    let newest = client.latest()?;
    assert!(newest.tick > last);
    assert_eq!(newest.axes().len(), 3);
    // Holding one frame while reading on is allowed.
    let held = newest.clone();
    let next = client.next_frame(WAIT)?;
    assert!(next.tick > held.tick);
    Ok(())
}

#[test]
fn for_each_frame_is_driven_by_a_waitset() -> Result {
    let (_server, client) = start::<ipc::Service>("waitset")?;
    let mut ticks = Vec::new();
    client.for_each_frame(WAIT, |frame| {
        ticks.push(frame.tick);
        if ticks.len() == 10 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })?;
    assert_eq!(ticks.len(), 10);
    assert!(ticks.windows(2).all(|pair| pair[1] > pair[0]), "{ticks:?}");
    Ok(())
}

#[test]
fn ramp_to_then_wait_until_arrived() -> Result {
    let (_server, client) = start::<local::Service>("move")?;
    let x = client.axis("x")?;
    let accepted = x.ramp_to(5.0, 50.0, 0.0)?;
    let frame = x.wait_until_arrived(WAIT)?;
    assert!(frame.tick >= accepted.tick);
    let state = frame.axes()[0];
    assert_eq!(state.position, 5.0);
    assert!(state.flags().contains(AxisFlags::ARRIVED));
    x.position(-2.0)?;
    x.wait_until_arrived(WAIT)?;
    assert_eq!(x.state()?.position, -2.0);
    Ok(())
}

#[test]
fn a_move_held_stays_and_resumes_to_its_target() -> Result {
    let (_server, client) = start::<local::Service>("hold")?;
    let x = client.axis("x")?;
    let error = x.hold().expect_err("nothing moves");
    assert_eq!(error.reason(), Some(Reason::NotMoving));
    x.ramp_to(90.0, 10.0, 0.0)?;
    std::thread::sleep(Duration::from_millis(100));
    x.hold()?;
    // The reply comes before the frame that shows it: wait for that frame.
    let deadline = std::time::Instant::now() + WAIT;
    let state = loop {
        let state = x.state()?;
        if state.flags().contains(AxisFlags::HELD) || std::time::Instant::now() > deadline {
            break state;
        }
        client.next_frame(WAIT)?;
    };
    assert!(state.flags().contains(AxisFlags::HELD), "{state:?}");
    assert!(state.position < 90.0);
    let error = x
        .ramp_to(0.0, 0.0, 0.0)
        .and_then(|_| x.resume())
        .expect_err("forgotten");
    assert_eq!(error.reason(), Some(Reason::NotMoving));
    x.ramp_to(20.0, 50.0, 0.0)?;
    std::thread::sleep(Duration::from_millis(20));
    x.hold()?;
    x.resume()?;
    x.wait_until_arrived(WAIT)?;
    assert_eq!(x.state()?.position, 20.0);
    Ok(())
}

#[test]
fn out_of_limit_is_refused_with_reason_and_nothing_moves() -> Result {
    let (server, client) = start::<local::Service>("limit")?;
    let x = client.axis("x")?;
    let error = x.ramp_to(1000.0, 0.0, 0.0).expect_err("outside −100..100");
    assert_eq!(error.reason(), Some(Reason::OutOfRange));
    assert!(error.to_string().contains("axis x"), "{error}");
    let error = x.velocity(1000.0).expect_err("above max_velocity");
    assert_eq!(error.reason(), Some(Reason::VelocityLimit));
    let error = client.axis("a")?.home(0.0).expect_err("a cannot home");
    assert_eq!(error.reason(), Some(Reason::Unsupported));
    std::thread::sleep(Duration::from_millis(20));
    let state = x.state()?;
    assert_eq!((state.position, state.mode()), (0.0, Ok(AxisMode::Hold)));
    assert_eq!(server.requests().len(), 3);
    Ok(())
}

#[test]
fn estop_refuses_motion_until_reset_and_aborts_waits() -> Result {
    let (_server, client) = start::<local::Service>("estop")?;
    let x = client.axis("x")?;
    x.ramp_to(50.0, 10.0, 0.0)?;
    client.estop()?;
    let aborted = x.wait_until_arrived(WAIT).expect_err("e-stop");
    assert!(
        matches!(aborted, ClientError::WaitAborted { .. }),
        "{aborted:?}"
    );
    let refused = x.position(1.0).expect_err("latched");
    assert_eq!(refused.reason(), Some(Reason::EstopLatched));
    x.stop()?; // anyone may always stop
    client.reset()?;
    x.position(1.0)?;
    x.wait_until_arrived(WAIT)?;
    Ok(())
}

#[test]
fn a_claim_refuses_the_other_client_until_released() -> Result {
    let (_server, first) = start::<ipc::Service>("claim")?;
    let second = Client::<ipc::Service>::connect(first.server_name())?;
    assert_ne!(first.id(), second.id());
    first.axis("y")?.claim()?;
    let refused = second.axis("y")?.position(3.0).expect_err("claimed");
    assert_eq!(refused.reason(), Some(Reason::ClaimedByOther));
    assert!(
        refused.to_string().contains("claimed by another client"),
        "{refused}"
    );
    let not_mine = second.axis("y")?.release().expect_err("not the holder");
    assert_eq!(not_mine.reason(), Some(Reason::NotClaimed));
    let frame = second.latest()?;
    assert_eq!(frame.axes()[1].claimed_by, first.id());
    first.axis("y")?.release()?;
    second.axis("y")?.position(3.0)?;
    Ok(())
}

#[test]
fn home_then_wait_until_homed() -> Result {
    let (_server, client) = start::<local::Service>("home")?;
    let x = client.axis("x")?;
    x.set_position(2.0)?;
    x.home(0.0)?;
    let frame = x.wait_until_homed(WAIT)?;
    let state = frame.axes()[0];
    assert!(state.flags().contains(AxisFlags::HOMED));
    assert_eq!(state.position, 0.0);
    Ok(())
}

#[test]
fn jog_guard_renews_the_deadman_and_stops_when_dropped() -> Result {
    let (server, client) = start::<local::Service>("jog")?;
    let x = client.axis("x")?;
    {
        let jog = x.jog(10.0, 0.0)?;
        // Twice the 250 ms deadman, reading frames all along.
        let until = std::time::Instant::now() + Duration::from_millis(600);
        while std::time::Instant::now() < until {
            client.next_frame(WAIT)?;
        }
        assert_eq!(jog.refused(), None);
        let state = x.state()?;
        assert_eq!(state.mode(), Ok(AxisMode::RampVelocity));
        assert!(!state.flags().contains(AxisFlags::DEADMAN_EXPIRED));
        assert!(state.position > 5.0, "moved: {}", state.position);
    }
    let requests = server.requests();
    let renewals = requests
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::RampVelocity))
        .count();
    assert!(renewals >= 3, "renewed {renewals} times");
    let last = requests.last().ok_or("no requests")?;
    assert_eq!((last.kind(), last.axis), (Ok(CommandKind::Stop), 0));
    client.next_frame(WAIT)?;
    assert_eq!(x.state()?.velocity, 0.0);
    Ok(())
}

#[test]
fn an_unrenewed_velocity_is_stopped_by_the_deadman() -> Result {
    let (_server, client) = start::<local::Service>("deadman")?;
    let y = client.axis("y")?;
    y.velocity(5.0)?;
    std::thread::sleep(Duration::from_millis(400));
    let state = y.state()?;
    assert!(
        state.flags().contains(AxisFlags::DEADMAN_EXPIRED),
        "{state:?}"
    );
    Ok(())
}

#[test]
fn raw_send_returns_the_reply_as_is() -> Result {
    let (_server, client) = start::<local::Service>("raw")?;
    let reply = client.send(99, CommandKind::Position, [0.0; 3])?;
    assert_eq!(reply.result(), Err(Reason::UnknownAxis));
    let reply = client.send(CommandRequest::ALL_AXES, CommandKind::Stop, [0.0; 3])?;
    assert_eq!(reply.result(), Ok(()));
    let error = client
        .command(0, CommandKind::Position, [f64::NAN, 0.0, 0.0])
        .expect_err("NaN");
    assert_eq!(error.reason(), Some(Reason::NotFinite));
    Ok(())
}

#[test]
fn a_stopped_server_is_reported_not_waited_for_forever() -> Result {
    let (server, client) = start::<ipc::Service>("gone")?;
    let x = client.axis("x")?;
    x.stop()?;
    client.latest()?; // subscribes to frames
    server.shutdown()?;
    let error = x.position(1.0).expect_err("no server");
    assert!(
        matches!(
            error,
            ClientError::NoServer { .. } | ClientError::NoReply { .. }
        ),
        "{error:?}"
    );
    client.latest()?; // the last frame received stays readable
    let silent = client.next_frame(Duration::from_millis(100));
    assert!(matches!(silent, Err(ClientError::NoFrame(_))), "{silent:?}");
    Ok(())
}

#[test]
fn a_refused_renewal_is_reported_by_the_guard() -> Result {
    let (server, client) = start::<local::Service>("renewal")?;
    let y = client.axis("y")?;
    let jog = y.jog(-5.0, 0.0)?;
    client.estop()?;
    // Read frames past one renewal period (a third of the 250 ms deadman).
    let until = std::time::Instant::now() + Duration::from_millis(200);
    while std::time::Instant::now() < until {
        client.next_frame(WAIT)?;
    }
    assert_eq!(jog.refused(), Some(Reason::EstopLatched));
    let renewals_before = server.requests().len();
    let until = std::time::Instant::now() + Duration::from_millis(200);
    while std::time::Instant::now() < until {
        client.next_frame(WAIT)?;
    }
    assert_eq!(
        server.requests().len(),
        renewals_before,
        "no renewals once refused"
    );
    jog.stop()?; // a stop is always taken
    Ok(())
}

#[test]
fn for_each_frame_reports_a_silent_server() -> Result {
    let (server, client) = start::<ipc::Service>("silent")?;
    client.latest()?; // subscribes to frames
    server.shutdown()?;
    let mut seen = 0;
    let result = client.for_each_frame(Duration::from_millis(200), |_| {
        seen += 1;
        ControlFlow::Continue(())
    });
    assert!(matches!(result, Err(ClientError::NoFrame(_))), "{result:?}");
    assert!(seen <= 4, "only the frames buffered before the stop");
    Ok(())
}
