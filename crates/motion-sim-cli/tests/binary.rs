//! End to end through a real pseudo-terminal and `serialport`: a test process opens the
//! path that `motion-sim --pty` printed, as motiond or `screen` would, and reads the QSB
//! VERSION register and a Trinamic unit information ($43). Every wait has a timeout.

mod pty_support;

use std::time::{Duration, Instant};

use motion_link::Link;
use motion_link::serial::{SerialConfig, SerialLink};
use pty_support::{Served, read_until};

fn open(served: &Served, path: &str, baud: u32) -> SerialLink {
    SerialLink::open(SerialConfig::new(path, baud)).unwrap_or_else(|e| {
        panic!(
            "open the printed pty path: {e}; stderr:\n{}",
            served.stderr()
        )
    })
}

#[test]
fn qsb_on_a_pty_answers_the_version_register() {
    let link_path = pty_support::temp_path("qsb");
    let served = Served::start(&[
        "--model",
        "qsb",
        "--pty",
        "--link",
        link_path.to_str().expect("utf-8 path"),
    ]);
    assert!(
        served.first_line.starts_with("/dev/"),
        "{}",
        served.first_line
    );
    assert_eq!(
        std::fs::read_link(&link_path).expect("--link made a symlink"),
        std::path::Path::new(&served.first_line)
    );
    let mut link = open(&served, link_path.to_str().unwrap(), 230_400);

    // QSB command list, 14 VERSION: "R14" read request.
    let mut request = [0u8; qsb::MAX_COMMAND_LEN];
    let n = qsb::Request::Read(qsb::Register::Version)
        .encode(&mut request)
        .expect("encode");
    assert_eq!(&request[..n], b"R14\r\n");
    assert_eq!(link.write(Duration::ZERO, &request[..n]).expect("write"), n);

    let mut decoder = qsb::ResponseDecoder::new();
    let mut response = None;
    let got = read_until(&mut link, Duration::from_secs(5), |bytes| {
        let mut rest = bytes;
        decoder.clear();
        while !rest.is_empty() {
            let (used, line) = decoder.decode(rest);
            if line.is_some() {
                response = line;
                return true;
            }
            rest = rest.get(used.max(1)..).unwrap_or_default();
        }
        false
    });
    let response = response.unwrap_or_else(|| {
        panic!(
            "no response line in {:?}; stderr:\n{}",
            String::from_utf8_lossy(&got),
            served.stderr()
        )
    });
    assert_eq!(response.ty, qsb::ResponseType::Read, "{response:?}");
    assert_eq!(response.register, 0x14, "{response:?}");
    assert!(
        matches!(response.value(), Ok(qsb::Value::Version(_))),
        "{response:?}"
    );
    served.stop_and_check(Duration::from_secs(5));
    assert!(
        std::fs::symlink_metadata(&link_path).is_err(),
        "the --link symlink is removed on exit"
    );
}

/// Sends the $43 request to `address` until a 9-byte reply comes (the pack ignores
/// everything for about a second after power-up, manual $CC / 5.1) and decodes it.
fn unit_info(link: &mut SerialLink, address: u8) -> tmcpack::ReplyFrame {
    let request =
        tmcpack::RequestFrame::new(address, tmcpack::Request::UnitInfo { reply_to: 0xFE });
    let mut frame = [0u8; 9];
    assert_eq!(request.encode(&mut frame).expect("encode"), 9);
    assert_eq!(frame, [address, 0x43, 0xFE, 0, 0, 0, 0, 0, 0]);
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(6) {
        assert_eq!(link.write(start.elapsed(), &frame).expect("write"), 9);
        // One round trip at 19200 baud: 2 × 4.7 ms plus the switch-over delay.
        let got = read_until(link, Duration::from_millis(300), |b| b.len() >= 9);
        if got.len() >= 9 {
            assert_eq!(got.len(), 9, "exactly one reply: {got:02x?}");
            return tmcpack::ReplyFrame::decode(&got).expect("a valid reply frame");
        }
        assert!(got.is_empty(), "a partial reply: {got:02x?}");
    }
    panic!("pack {address} never answered $43");
}

#[test]
fn tmcpack_on_a_pty_answers_unit_info() {
    let served = Served::start(&["--model", "tmcpack", "--pty", "--baud", "19200"]);
    let mut link = open(&served, &served.first_line, 19_200);
    let reply = unit_info(&mut link, 1);
    assert!(
        matches!(reply.reply, tmcpack::Reply::UnitInfo { .. }),
        "{reply:?}"
    );
    served.stop_and_check(Duration::from_secs(5));
}

#[test]
fn two_tmcpacks_share_one_pty_bus() {
    let served = Served::start(&[
        "--model",
        "tmcpack",
        "--address",
        "1",
        "--model",
        "tmcpack",
        "--address",
        "2",
        "--variant",
        "quadpack",
        "--pty",
    ]);
    let mut link = open(&served, &served.first_line, 19_200);
    for address in [1, 2] {
        let reply = unit_info(&mut link, address);
        assert!(
            matches!(reply.reply, tmcpack::Reply::UnitInfo { .. }),
            "pack {address}: {reply:?}"
        );
    }
    served.stop_and_check(Duration::from_secs(5));
}

#[test]
fn help_documents_every_option_and_a_manual_session() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_motion-sim"))
        .arg("--help")
        .output()
        .expect("run --help");
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "--model",
        "--address",
        "--variant",
        "--drive",
        "--seed",
        "--pty",
        "--link",
        "--baud",
        "--spi-socket",
        "--spi-hz",
        "--trace",
        "screen",
        "python3",
        "SIGTERM",
    ] {
        assert!(help.contains(needle), "--help lacks {needle}:\n{help}");
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_motion-sim"))
        .args(["--model", "qsb"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--pty"));
}
