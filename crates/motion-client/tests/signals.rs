//! Signals against the fake server: reading inputs, setting outputs, claims, waits, and the
//! e-stop's safe states.

use core::time::Duration;

use iceoryx2::prelude::{ipc, local};
use motion_client::ipc::{Reason, SignalFlags, SignalKind};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientError};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(5);

fn start() -> Result<(FakeServer, Client<local::Service>)> {
    let server = FakeServer::start::<local::Service>(FakeConfig::demo(&unique_name("signals")))?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

#[test]
fn signals_are_found_by_name_and_described() -> Result {
    let (_server, client) = start()?;
    let names: Vec<String> = client.signals().iter().map(|s| s.name()).collect();
    assert_eq!(names, ["door", "lamp", "pressure", "valve"]);
    let pressure = client.signal("pressure")?;
    assert_eq!(pressure.index(), 2);
    assert_eq!(pressure.kind(), Some(SignalKind::AnalogIn));
    let info = pressure.info();
    assert_eq!(
        (info.unit(), info.device(), info.pin()),
        ("bar", "aux", "ain0")
    );
    assert_eq!(pressure.tolerance(), 0.01);
    let missing = client.signal("nope").expect_err("no such signal");
    assert!(
        matches!(missing, ClientError::UnknownSignal(_)),
        "{missing:?}"
    );
    assert!(missing.to_string().contains("io list"), "{missing}");
    Ok(())
}

#[test]
fn inputs_are_read_and_waited_for() -> Result {
    let (server, client) = start()?;
    let door = client.signal("door")?;
    assert!(!door.is_on()?);
    server.set_input(0, 1.0);
    let state = door.wait_for(1.0, WAIT)?;
    assert!(state.is_on());
    assert_eq!(state.raw, 1.0);
    let pressure = client.signal("pressure")?;
    server.set_input(2, 250.0);
    let state = pressure.wait_for(2.5, WAIT)?;
    assert!((state.value - 2.5).abs() < 1e-9, "{}", state.value);
    assert_eq!(state.raw, 250.0);
    let state = pressure.wait_until(WAIT, |state| state.value > 2.0)?;
    assert!(state.value > 2.0);
    let timeout = pressure
        .wait_within(1.0, 0.05, Duration::from_millis(100))
        .expect_err("stays at 2.5 bar");
    let message = timeout.to_string();
    assert!(
        message.contains("signal pressure did not become 1 bar ± 0.05")
            && message.contains("last value 2.5 bar"),
        "{message}"
    );
    Ok(())
}

#[test]
fn outputs_are_set_and_inputs_refuse() -> Result {
    let (_server, client) = start()?;
    let lamp = client.signal("lamp")?;
    lamp.set(true)?;
    let state = lamp.wait_for(1.0, WAIT)?;
    assert!(state.is_on());
    // The inverted valve: logical on is electrical level 0.
    let valve = client.signal("valve")?;
    valve.set(true)?;
    let state = valve.wait_for(1.0, WAIT)?;
    assert_eq!((state.value, state.raw), (1.0, 0.0));
    let refused = client.signal("door")?.set(true).expect_err("an input");
    assert_eq!(refused.reason(), Some(Reason::NotAnOutput));
    assert!(refused.to_string().contains("signal door"), "{refused}");
    Ok(())
}

#[test]
fn the_estop_puts_outputs_in_their_safe_state_and_refuses_setting_them() -> Result {
    let (_server, client) = start()?;
    let lamp = client.signal("lamp")?;
    lamp.set(true)?;
    lamp.wait_for(1.0, WAIT)?;
    client.estop()?;
    let state = lamp.wait_for(0.0, WAIT)?;
    assert!(state.flags().contains(SignalFlags::SAFE_STATE));
    let refused = lamp.set(true).expect_err("e-stop latched");
    assert_eq!(refused.reason(), Some(Reason::EstopLatched));
    client.reset()?;
    lamp.set(true)?;
    let state = lamp.wait_for(1.0, WAIT)?;
    assert!(!state.flags().contains(SignalFlags::SAFE_STATE));
    Ok(())
}

#[test]
fn a_claimed_output_refuses_other_clients_until_released() -> Result {
    let server = FakeServer::start::<ipc::Service>(FakeConfig::demo(&unique_name("sigclaim")))?;
    let first = Client::<ipc::Service>::connect(server.name())?;
    let second = Client::<ipc::Service>::connect(server.name())?;
    {
        let _claim = first.signal("lamp")?.claim_guard()?;
        let state = first
            .signal("lamp")?
            .wait_until(WAIT, |state| state.flags().contains(SignalFlags::CLAIMED))?;
        assert_eq!(state.claimed_by, first.id());
        let refused = second.signal("lamp")?.set(true).expect_err("claimed");
        assert_eq!(refused.reason(), Some(Reason::ClaimedByOther));
        first.signal("lamp")?.set(true)?;
    }
    // Dropping the guard released it.
    second.signal("lamp")?.set(false)?;
    Ok(())
}

/// The demo machine with a probe (capture) and a camera trigger on `aux`, in mm.
fn start_with_events() -> Result<(FakeServer, Client<local::Service>)> {
    use motion_client::testing::FakeSignal;
    let mut config = FakeConfig::demo(&unique_name("events"));
    for (name, pin, kind) in [
        ("probe", "capture", SignalKind::Capture),
        ("camera", "trigger", SignalKind::Trigger),
    ] {
        let mut signal = FakeSignal::analog(name, 1, pin, "mm", 0.01, 0.0);
        signal.kind = kind;
        config.signals.push(signal);
    }
    let server = FakeServer::start::<local::Service>(config)?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

#[test]
fn captures_are_waited_for_as_events_and_missed_ones_are_counted() -> Result {
    let (server, client) = start_with_events()?;
    let probe = client.signal("probe")?;
    assert_eq!(probe.kind(), Some(SignalKind::Capture));
    let seen = probe.sequence()?;
    assert_eq!(seen, 0);
    let quiet = probe
        .wait_event(seen, Duration::from_millis(100))
        .expect_err("no capture yet");
    assert!(
        quiet.to_string().contains("an event after sequence 0"),
        "{quiet}"
    );
    server.capture(4, 1234.0);
    let event = probe.wait_event(seen, WAIT)?;
    assert_eq!((event.sequence, event.missed), (1, 0));
    assert!((event.value - 12.34).abs() < 1e-9, "{event:?}");
    assert!(event.tick > 0);
    // Two before the client looks again: the second, and one missed.
    server.capture(4, 100.0);
    server.capture(4, 200.0);
    let event = probe.wait_until(WAIT, |state| state.sequence == 3)?;
    assert_eq!(event.events_since(1), 2);
    let event = probe.wait_event(1, WAIT)?;
    assert_eq!((event.sequence, event.missed, event.value), (3, 1, 2.0));
    Ok(())
}

#[test]
fn a_trigger_s_compare_position_is_set_and_a_capture_refuses_it() -> Result {
    let (_server, client) = start_with_events()?;
    let camera = client.signal("camera")?;
    camera.set_value(62.5)?;
    let state = camera.wait_within(62.5, 1e-9, WAIT)?;
    assert_eq!(state.raw, 6250.0);
    let refused = client
        .signal("probe")?
        .set_value(1.0)
        .expect_err("an input");
    assert!(
        matches!(
            refused,
            ClientError::Refused {
                reason: Reason::NotAnOutput,
                ..
            }
        ),
        "{refused:?}"
    );
    Ok(())
}
