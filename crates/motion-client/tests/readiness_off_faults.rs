//! Off, device readiness, fault sentences, identity and machine parameters against the fake
//! server. Every wait has a timeout; every test uses its own instance name.

use core::time::Duration;

use iceoryx2::prelude::local;
use motion_client::ipc::{
    AxisMode, CommandKind, DeviceState, EstopCategory, FaultCode, ParamOwner, Reason,
};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientError};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(5);

fn start(config: FakeConfig) -> Result<(FakeServer, Client<local::Service>)> {
    let server = FakeServer::start::<local::Service>(config)?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

#[test]
fn off_de_energises_and_off_all_reports_each_axis() -> Result {
    let (server, client) = start(FakeConfig::demo(&unique_name("off")))?;
    let x = client.axis("x")?;
    x.off()?;
    client.next_frame(WAIT)?;
    assert_eq!(x.state()?.mode(), Ok(AxisMode::Off));
    let report = client.off_all();
    let outcome: Vec<(String, Option<Reason>)> = report
        .iter()
        .map(|(axis, result)| {
            (
                axis.name(),
                result.as_ref().err().and_then(ClientError::reason),
            )
        })
        .collect();
    assert_eq!(
        outcome,
        [
            ("x".to_owned(), None),
            ("y".to_owned(), None),
            ("a".to_owned(), Some(Reason::Unsupported)), // the demo's `a` cannot de-energise
        ]
    );
    let offs: Vec<u32> = server
        .requests()
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::Off))
        .map(|request| request.axis)
        .collect();
    assert_eq!(offs, [0, 0, 1, 2], "one Off per axis, never ALL_AXES");
    Ok(())
}

#[test]
fn a_starting_device_refuses_goals_naming_itself_until_ready() -> Result {
    // 500 Hz: starting for 0.4 s.
    let (_server, client) = start(FakeConfig::demo(&unique_name("starting")).starting_for(200))?;
    let x = client.axis("x")?;
    let refused = x.position(1.0).expect_err("device starting");
    assert_eq!(refused.reason(), Some(Reason::DeviceStarting));
    let message = refused.to_string();
    assert!(
        message.contains("device `pack` is starting: waiting for the board's first answer"),
        "{message}"
    );
    let states = client.devices()?;
    assert_eq!(states[0].state, DeviceState::Starting);
    client.wait_ready(WAIT)?;
    assert!(
        client
            .devices()?
            .iter()
            .all(|d| d.state == DeviceState::Online)
    );
    x.position(1.0)?;
    x.wait_until_arrived(WAIT)?;
    Ok(())
}

#[test]
fn wait_ready_names_the_devices_still_not_online() -> Result {
    let (server, client) = start(FakeConfig::demo(&unique_name("notready")))?;
    server.set_device_state(1, DeviceState::Offline);
    // Device `pack` is online: x is ready even though `aux` is not.
    client.axis("x")?.wait_ready(WAIT)?;
    let until = std::time::Instant::now() + WAIT;
    while client.devices()?[1].state != DeviceState::Offline {
        assert!(std::time::Instant::now() < until, "control never applied");
        client.next_frame(WAIT)?;
    }
    let error = client
        .wait_ready(Duration::from_millis(100))
        .expect_err("aux is offline");
    let ClientError::NotReady { devices, .. } = &error else {
        return Err(format!("{error:?}").into());
    };
    assert_eq!(devices.len(), 1);
    assert_eq!(
        (devices[0].name.as_str(), devices[0].state),
        ("aux", DeviceState::Offline)
    );
    let message = error.to_string();
    assert!(message.contains("device `aux` is offline"), "{message}");
    assert!(!message.contains("`pack`"), "{message}");
    let refused = client.axis("a")?.position(1.0).expect_err("offline");
    assert_eq!(refused.reason(), Some(Reason::DeviceOffline));
    assert!(
        refused.to_string().contains("device `aux` is offline"),
        "{refused}"
    );
    // A faulted device ends the wait at once: waiting does not clear it.
    server.set_device_state(1, DeviceState::Faulted);
    let started = std::time::Instant::now();
    let error = client.axis("a")?.wait_ready(WAIT).expect_err("faulted");
    assert!(started.elapsed() < WAIT, "did not wait out the timeout");
    assert!(
        error.to_string().contains("device `aux` is faulted"),
        "{error}"
    );
    Ok(())
}

#[test]
fn a_fault_ends_a_wait_with_the_fault_sentence() -> Result {
    let (server, client) = start(FakeConfig::demo(&unique_name("fault")))?;
    let x = client.axis("x")?;
    x.ramp_to(80.0, 5.0, 0.0)?;
    server.fault_axis(0, FaultCode::FollowingError, 0.75, 0.5);
    let error = x.wait_until_arrived(WAIT).expect_err("faulted");
    let expected = FaultCode::FollowingError.explain("x", 0.75, 0.5, "mm");
    match &error {
        ClientError::AxisFaulted { axis, fault, text } => {
            assert_eq!((axis.as_str(), *fault), ("x", FaultCode::FollowingError));
            assert_eq!(text, &expected);
        }
        other => return Err(format!("{other:?}").into()),
    }
    assert_eq!(error.to_string(), expected);
    assert_eq!(x.fault_text(), Some(expected.clone()));
    // A goal for the faulted axis is refused with the same sentence.
    let refused = x.position(1.0).expect_err("faulted");
    assert_eq!(refused.reason(), Some(Reason::AxisFaulted));
    assert!(refused.to_string().contains(&expected), "{refused}");
    client.reset()?;
    x.position(1.0)?;
    x.wait_until_arrived(WAIT)?;
    Ok(())
}

#[test]
fn requests_carry_the_node_id_and_the_description_the_supervision() -> Result {
    let (server, client) = start(FakeConfig::demo(&unique_name("identity")))?;
    client.axis("y")?.stop()?;
    let request = *server.requests().last().ok_or("no request")?;
    assert_eq!(request.client, client.id());
    assert_eq!(client.id().as_u128(), client.node().id().value());
    let info = client.info()?;
    let x = &info.axes()[0];
    assert_eq!((x.following_error, x.overspeed_factor), (0.5, 1.2));
    assert_eq!(x.home_max_travel, 250.0);
    assert_eq!(x.estop(), Ok(EstopCategory::StopOff));
    assert_eq!(info.devices()[1].name(), "aux");
    assert_eq!(info.devices()[1].state(), DeviceState::Online);
    Ok(())
}

#[test]
fn machine_params_come_from_the_params_service() -> Result {
    let (_server, client) = start(FakeConfig::demo(&unique_name("params")))?;
    let params = client.machine_params()?;
    let rows: Vec<(Option<ParamOwner>, u16, &str, &str, u8)> = params
        .entries()
        .iter()
        .map(|p| {
            (
                p.owner().ok(),
                p.owner_index,
                p.key(),
                p.value(),
                p.from_config,
            )
        })
        .collect();
    assert_eq!(rows.len(), 6);
    assert!(rows.contains(&(Some(ParamOwner::Device), 0, "baud", "19200 baud", 0)));
    assert!(rows.contains(&(Some(ParamOwner::Axis), 0, "current.run", "80 %", 1)));
    // Read again: the same sample, no new subscription.
    assert_eq!(client.machine_params()?.count, 6);
    Ok(())
}
