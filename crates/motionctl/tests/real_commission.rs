//! Commissioning as a user sees it, against a real `motiond` on the simulated robot
//! (`config/sim.toml`: a SIXpack and a QUADpack on one RS-485 bus, two SPI_motors):
//! `motionctl commission` moves the QUADpack to address 5 and the SIXpack to 115200 baud
//! and prints the config line; refuses an address another device has, a rate the pack's
//! `$40` does not reach, a factory reset without --yes, a board without the setting, an
//! unknown device, a commission while the e-stop is latched, a rate while another client
//! holds a claim on the neighbour pack, and — through the Rust client — a client without
//! the device's claims and a device whose axis moves; an SPI_motor moves to a new even
//! address.

mod common;

use core::time::Duration;

use common::real::RealServer;
use common::*;
use iceoryx2::prelude::ipc;
use motion_client::Client;
use motion_client::ipc::{CommissionWhat, Reason};

#[test]
fn real_commission_moves_address_and_rate_and_refuses_what_it_must() -> Result {
    let server = RealServer::start()?;
    let name = server.name.clone();

    // The QUADpack (address 2) to 5: found there, the line for the config printed.
    let output = run(&name, &["commission", "pack_aux", "--address", "5"])?;
    assert!(output.status.success(), "{output:?}");
    let text = stdout(&output);
    assert!(text.contains("pack_aux answers at address 5"), "{text}");
    assert!(text.contains("Put `address = 5`"), "{text}");
    assert!(text.contains("rotary switches"), "{text}");
    // Address 1 is the SIXpack's, on the same link.
    assert_fails(
        &run(&name, &["commission", "pack_aux", "--address", "1"])?,
        4,
        "taken by another device on link `rs485`",
    );
    // 230400 is not a rate of $40 (divisor 5 gives 250000).
    assert_fails(
        &run(&name, &["commission", "pack_xyz", "--baud", "230400"])?,
        2,
        "allowed: 300, 600",
    );
    assert_fails(
        &run(&name, &["commission", "pack_xyz", "--factory-reset"])?,
        2,
        "give --yes to confirm",
    );
    assert_fails(
        &run(&name, &["commission", "feeder_qsb", "--address", "3"])?,
        4,
        "refused",
    );
    assert_fails(
        &run(&name, &["commission", "no_such", "--address", "3"])?,
        4,
        "no device named \"no_such\"",
    );

    // Issue 40 item 8: refused while the e-stop is latched, said so; and a rate while
    // another client holds a claim on the neighbour pack's `gripper` (it would be left at
    // 19200), the device named.
    let estop = run(&name, &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    assert_fails(
        &run(&name, &["commission", "pack_xyz", "--baud", "115200"])?,
        4,
        "the e-stop is latched",
    );
    let reset = run(&name, &["reset"])?;
    assert!(reset.status.success(), "{reset:?}");
    {
        let other = Client::<ipc::Service>::connect(&name)?;
        let gripper = other.axis("gripper")?;
        gripper.claim()?;
        assert_fails(
            &run(&name, &["commission", "pack_xyz", "--baud", "115200"])?,
            4,
            "device `pack_aux` shares link `rs485` and client 0x",
        );
        let output = run(&name, &["commission", "pack_xyz", "--baud", "115200"])?;
        assert!(
            stderr(&output).contains("holds a claim on its axis `gripper`"),
            "{output:?}"
        );
        gripper.release()?;
    }

    // The SIXpack to 115200; its neighbour on the bus keeps 19200 (said so).
    let output = run(
        &name,
        &["commission", "pack_xyz", "--baud", "115200", "--json"],
    )?;
    assert!(output.status.success(), "{output:?}");
    let json = json_of(&output)?;
    assert_eq!(json["config"], "baud = 115200");
    assert!(
        json["advice"]
            .as_str()
            .is_some_and(|a| a.contains("pack_aux") && a.contains("still talk at their own rate")),
        "{json}"
    );
    // Both packs answer: the link changes its rate for each.
    let ready = run(&name, &["wait-ready", "--timeout", "5s"])?;
    assert!(ready.status.success(), "{ready:?}");

    // The SPI_motor of `focus` to 0x94.
    let output = run(
        &name,
        &["commission", "focus_drv", "--address", "0x94", "--json"],
    )?;
    assert!(output.status.success(), "{output:?}");
    let json = json_of(&output)?;
    assert_eq!(
        (json["address"].as_u64(), &json["config"]),
        (Some(0x94), &"address = 0x94".into())
    );

    // Through the Rust client: without the device's claims, then while an axis moves.
    let client = Client::<ipc::Service>::connect(&name)?;
    match client.commission("pack_xyz", CommissionWhat::Address, 9) {
        Err(error) => assert_eq!(error.reason(), Some(Reason::NotClaimed), "{error}"),
        Ok(accepted) => panic!("accepted without the claims: {accepted:?}"),
    }
    let x = client.axis("x")?;
    let claims = client.claim_device("pack_xyz")?;
    // A slow move (5 mm at 1 mm/s: no deadman to expire under load, as a jog's would).
    let from = x.state()?.position;
    x.ramp_to(if from < 50.0 { from + 5.0 } else { from - 5.0 }, 1.0, 0.0)?;
    std::thread::sleep(Duration::from_millis(100));
    match client.commission("pack_xyz", CommissionWhat::Address, 9) {
        Err(error) => assert_eq!(error.reason(), Some(Reason::GroupBusy), "{error}"),
        Ok(accepted) => panic!("accepted while x moves: {accepted:?}"),
    }
    x.stop()?;
    x.wait_until_arrived(Duration::from_secs(5)).ok();
    std::thread::sleep(Duration::from_millis(500));
    let accepted = client.commission("pack_xyz", CommissionWhat::Address, 9)?;
    let found = client.wait_commissioned("pack_xyz", accepted, Duration::from_secs(5))?;
    assert_eq!(found.address, 9);
    assert!(found.firmware.starts_with("SIXpack"), "{found:?}");
    drop(claims);
    Ok(())
}
