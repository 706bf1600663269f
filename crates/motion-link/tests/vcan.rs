//! The SocketCAN link on a real virtual CAN interface (`vcan`), where the kernel has one.
//!
//! Each test looks for the interface named by `MOTIOND_TEST_VCAN` (default `vcan0`) and,
//! as root, creates it when it is missing (`ip link add dev vcan0 type vcan`, `ip link set
//! up vcan0`). Where the kernel has no SocketCAN (`EAFNOSUPPORT`) or no `vcan` module
//! ("Unknown device type"), the test prints that it skipped and why, and passes: a kernel
//! without CAN cannot say anything about the link.

use std::time::{Duration, Instant};

use motion_base::{CAN_RECORD_LEN, CanRecord};
use motion_link::socketcan::{SocketCanConfig, SocketCanLink, kernel_support};
use motion_link::{Link, LinkErrorKind};

/// The vcan interface to test on, or why there is none (printed by the caller).
fn vcan() -> Result<String, String> {
    let name = std::env::var("MOTIOND_TEST_VCAN").unwrap_or_else(|_| "vcan0".to_owned());
    kernel_support().map_err(|errno| {
        format!("the kernel has no SocketCAN (socket(AF_CAN): {errno}); load can_raw")
    })?;
    if std::path::Path::new("/sys/class/net").join(&name).exists() {
        return up(&name).map(|()| name);
    }
    let add = std::process::Command::new("ip")
        .args(["link", "add", "dev", &name, "type", "vcan"])
        .output()
        .map_err(|e| format!("`ip` could not run ({e}) to create {name}"))?;
    if !add.status.success() {
        return Err(format!(
            "`ip link add dev {name} type vcan` failed: {} (no vcan module in this kernel, \
             or not root)",
            String::from_utf8_lossy(&add.stderr).trim()
        ));
    }
    up(&name).map(|()| name)
}

fn up(name: &str) -> Result<(), String> {
    let out = std::process::Command::new("ip")
        .args(["link", "set", "up", name])
        .output()
        .map_err(|e| format!("`ip link set up {name}` could not run: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "`ip link set up {name}` failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// Says on the terminal that `test` skipped and why: written to the process's stderr
/// directly, past the test harness's capture of `println!`, so a plain `cargo test` shows
/// it.
fn skipped(test: &str, why: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "vcan: skipped {test}: {why}");
}

macro_rules! vcan_or_skip {
    ($test:literal) => {
        match vcan() {
            Ok(name) => name,
            Err(why) => {
                skipped($test, &why);
                return;
            }
        }
    };
}

fn read_frames(link: &mut SocketCanLink, want: usize) -> Vec<CanRecord> {
    let start = Instant::now();
    let mut bytes = Vec::new();
    let mut buf = [0u8; 256];
    while bytes.len() < want * CAN_RECORD_LEN && start.elapsed() < Duration::from_secs(2) {
        let n = link
            .read_wait(start.elapsed(), &mut buf, Duration::from_millis(50))
            .expect("read");
        bytes.extend_from_slice(&buf[..n]);
    }
    assert_eq!(bytes.len() % CAN_RECORD_LEN, 0, "whole records");
    bytes
        .chunks_exact(CAN_RECORD_LEN)
        .map(|c| CanRecord::from_bytes(c.try_into().expect("16")).expect("valid"))
        .collect()
}

/// Two sockets on one vcan: what one writes the other reads, record for record; nobody
/// reads its own frames.
#[test]
fn two_sockets_on_a_vcan_exchange_records() {
    let name = vcan_or_skip!("two_sockets_on_a_vcan_exchange_records");
    let config = SocketCanConfig::new(name.as_str(), 250_000);
    let mut host = SocketCanLink::open(config.clone()).expect("host socket");
    let mut pack = SocketCanLink::open(config).expect("pack socket");
    assert!(host.poll_fd().is_some());
    let query = CanRecord::standard(0x010, &[0x20, 1, 0xFE, 0, 0, 0, 0, 0]).expect("valid");
    let bytes = query.to_bytes();
    // In two pieces: one frame.
    assert_eq!(host.write(Duration::ZERO, &bytes[..3]).expect("write"), 3);
    assert_eq!(host.write(Duration::ZERO, &bytes[3..]).expect("write"), 13);
    assert_eq!(read_frames(&mut pack, 1), [query]);
    let answer = CanRecord::standard(0x7F0, &[0x20, 1, 0xD0, 7, 0, 0, 5, 0]).expect("valid");
    pack.write(Duration::ZERO, &answer.to_bytes())
        .expect("write");
    assert_eq!(read_frames(&mut host, 1), [answer]);
    // The host did not hear its own query (nor the pack its answer).
    assert_eq!(host.read(Duration::ZERO, &mut [0u8; 64]).expect("read"), 0);
    assert_eq!(pack.read(Duration::ZERO, &mut [0u8; 64]).expect("read"), 0);
    assert_eq!(host.frames(), (1, 1));
    // A burst of 20 arrives whole and in order.
    let burst: Vec<CanRecord> = (0..20u8)
        .map(|n| CanRecord::standard(0x008, &[n]).expect("valid"))
        .collect();
    for frame in &burst {
        assert_eq!(
            host.write(Duration::ZERO, &frame.to_bytes())
                .expect("write"),
            16
        );
    }
    assert_eq!(read_frames(&mut pack, 20), burst);
}

/// A vcan link that goes down is Disconnected, and reopens once it is up again.
#[test]
fn a_vcan_taken_down_disconnects_the_link() {
    let name = vcan_or_skip!("a_vcan_taken_down_disconnects_the_link");
    let mut link = SocketCanLink::open(SocketCanConfig::new(name.as_str(), 250_000)).expect("open");
    let down = std::process::Command::new("ip")
        .args(["link", "set", "down", &name])
        .status();
    if !down.is_ok_and(|s| s.success()) {
        skipped(
            "a_vcan_taken_down_disconnects_the_link",
            &format!("cannot take {name} down"),
        );
        return;
    }
    let frame = CanRecord::standard(0x008, &[1]).expect("valid").to_bytes();
    let err = link.write(Duration::ZERO, &frame).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
    up(&name).expect("up again");
    link.reopen(Duration::ZERO).expect("reopen");
    assert_eq!(link.write(Duration::ZERO, &frame).expect("write"), 16);
}

/// On every kernel: an interface that does not exist is Disconnected (the server retries),
/// with a message saying how to create it.
#[test]
fn an_absent_interface_is_disconnected_on_any_kernel() {
    let err = SocketCanLink::open(SocketCanConfig::new("motiondnocan", 250_000)).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
    assert!(err.to_string().contains("ip link add"), "{err}");
}
