//! Device files: the links' ttys and spidev nodes, the USB-serial latency timer, and
//! `/dev/cpu_dma_latency`.

use std::path::Path;

use super::check::{Check, Context, Status};
use super::host::{Host, Identity};

const ACCESS: &str = "device-access";
const ACCESS_T: &str = "permissions of the links' ttys and spidev nodes";

/// Every serial and spidev path of the config exists and this user may read and write it;
/// world-writable nodes (anyone can drive the motors) and a check run as root (which proves
/// nothing about the service's user) warn.
pub fn access(cx: &Context<'_>) -> Check {
    let links: Vec<_> = cx.config.device_links().collect();
    if links.is_empty() {
        return Check::pass(ACCESS, ACCESS_T, "no serial or spidev links in the config");
    }
    let identity = match &cx.identity {
        Ok(id) => id,
        Err(e) => {
            return Check::warn(
                ACCESS,
                ACCESS_T,
                format!("unknown user: {e}"),
                "run the doctor on the machine itself, with /proc mounted",
            );
        }
    };
    let user = cx.host.user_name(identity.uid);
    let mut status = Status::Pass;
    let mut values = Vec::new();
    let mut fixes = Vec::new();
    for (link, path) in links {
        let shown = path.display();
        let Some(owner) = cx.host.owner(path) else {
            status = Status::Fail;
            values.push(format!("{}: {shown} is missing", link.name));
            fixes.push(format!(
                "plug in or wire up the device of link `{}`, or correct its path (prefer the stable \
                 /dev/serial/by-id/… names of USB adapters)",
                link.name
            ));
            continue;
        };
        let described = owner.describe(&cx.host);
        if !identity.can_read_write(owner.mode, owner.uid, owner.gid) {
            status = Status::Fail;
            values.push(format!(
                "{}: {shown} is {described}: {user} cannot read and write it",
                link.name
            ));
            fixes.push(format!(
                "install deploy/udev/60-motiond.rules (group `motion`, mode 0660) and `sudo udevadm \
                 trigger`, with {user} in group motion; or `sudo usermod -aG {} {user}` and log in again",
                cx.host.group_name(owner.gid)
            ));
        } else if owner.mode & 0o006 == 0o006 {
            status = status.max(Status::Warn);
            values.push(format!(
                "{}: {shown} is {described}: any local user can drive this link",
                link.name
            ));
            fixes.push(format!("sudo chmod o-rw {shown}, and give the device group `motion`, mode 0660 in a udev rule (deploy/udev/60-motiond.rules)"));
        } else if identity.uid == 0 {
            status = status.max(Status::Warn);
            values.push(format!(
                "{}: {shown} is {described}: root may open anything",
                link.name
            ));
            fixes.push(
                "run the doctor as the server's user to check its access: `sudo -u motion motionctl doctor`"
                    .to_owned(),
            );
        } else {
            values.push(format!("{}: {shown} is {described}", link.name));
        }
    }
    fixes.dedup();
    Check::with(
        ACCESS,
        ACCESS_T,
        status,
        values.join("; "),
        fixes.join("; "),
    )
}

const TIMER: &str = "usb-latency-timer";
const TIMER_T: &str = "USB-serial latency timer";

/// An FTDI adapter holds received bytes up to its latency timer (16 ms from the factory)
/// before sending them to the host: every reply waits that long. 1 ms passes, up to 4 warns.
pub fn latency_timer(cx: &Context<'_>) -> Check {
    let serial: Vec<_> = cx
        .config
        .device_links()
        .filter(|(l, _)| l.is_serial())
        .collect();
    if serial.is_empty() {
        return Check::pass(TIMER, TIMER_T, "no serial links in the config");
    }
    let mut status = Status::Pass;
    let mut values = Vec::new();
    let mut fixes = Vec::new();
    for (link, path) in serial {
        let Some(name) = tty_name(&cx.host, path) else {
            status = status.max(Status::Warn);
            values.push(format!("{}: {} is missing", link.name, path.display()));
            continue;
        };
        let file = format!("/sys/bus/usb-serial/devices/{name}/latency_timer");
        match cx.host.read(&file).and_then(|t| t.parse::<u32>().ok()) {
            None => values.push(format!(
                "{name}: no latency timer (not an FTDI USB-serial adapter)"
            )),
            Some(ms) => {
                let verdict = match ms {
                    0..=1 => Status::Pass,
                    2..=4 => Status::Warn,
                    _ => Status::Fail,
                };
                status = status.max(verdict);
                values.push(format!(
                    "{name}: {ms} ms{}",
                    if verdict == Status::Pass {
                        String::new()
                    } else {
                        format!(", up to {ms} ms added to every reply")
                    }
                ));
                if verdict != Status::Pass {
                    fixes.push(format!("echo 1 | sudo tee {file}"));
                }
            }
        }
    }
    let fix = if fixes.is_empty() {
        "check the link paths".to_owned()
    } else {
        format!(
            "{} now; deploy/udev/60-motiond.rules sets it to 1 ms whenever the adapter is plugged in",
            fixes.join("; ")
        )
    };
    Check::with(TIMER, TIMER_T, status, values.join("; "), fix)
}

/// The kernel name (`ttyUSB0`) behind a tty path (`/dev/serial/by-id/…` links followed).
fn tty_name(host: &Host<'_>, path: &Path) -> Option<String> {
    host.resolve(path)?
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
}

const DMA: &str = "cpu-dma-latency";
const DMA_T: &str = "/dev/cpu_dma_latency access";

/// motiond holds `/dev/cpu_dma_latency` at 0 µs when it may open it (wake-up p50 42 → 15 µs
/// on our machines). Missing access fails when the config asks for real time
/// (`rt_priority`), and warns otherwise.
pub fn dma_latency(cx: &Context<'_>) -> Check {
    let path = Path::new("/dev/cpu_dma_latency");
    let fix = "install deploy/udev/60-motiond.rules (it gives /dev/cpu_dma_latency to group motion, \
               mode 0660) and `sudo udevadm trigger`; the server's user must be in group motion";
    let wanted = if cx.config.server.rt_priority.is_some() {
        Status::Fail
    } else {
        Status::Warn
    };
    let Some(owner) = cx.host.owner(path) else {
        return Check::with(
            DMA,
            DMA_T,
            wanted,
            "missing: this kernel has no PM QoS device",
            "none on this kernel: motiond runs without it (slower wake-ups from idle states)",
        );
    };
    let described = owner.describe(&cx.host);
    match &cx.identity {
        Ok(id) if writable(id, owner.mode, owner.uid, owner.gid) => Check::pass(
            DMA,
            DMA_T,
            format!("{described}: writable by {}", cx.host.user_name(id.uid)),
        ),
        Ok(id) => Check::with(
            DMA,
            DMA_T,
            wanted,
            format!(
                "{described}: not writable by {}; motiond runs without it (wake-up from idle states is slower){}",
                cx.host.user_name(id.uid),
                if wanted == Status::Fail {
                    ", though the config asks for real time"
                } else {
                    ""
                }
            ),
            fix,
        ),
        Err(e) => Check::warn(DMA, DMA_T, format!("{described}; unknown user: {e}"), fix),
    }
}

fn writable(id: &Identity, mode: u32, uid: u32, gid: u32) -> bool {
    // Opened for writing only.
    id.uid == 0 || {
        let bits = if id.uid == uid {
            mode >> 6
        } else if id.groups.contains(&gid) {
            mode >> 3
        } else {
            mode
        };
        bits & 0o2 != 0
    }
}

#[cfg(test)]
mod tests {
    use super::super::fake::{FakeRoot, UID};
    use super::*;

    const LINKS: &str = r#"
[[link]]
name = "rs485"
type = "serial"
path = "/dev/serial/by-id/usb-FTDI_FT232R-if00-port0"
[[link]]
name = "spi"
type = "spidev"
path = "/dev/spidev0.0"
"#;

    fn devices(fake: &FakeRoot) {
        fake.file("/dev/ttyUSB0", "");
        fake.symlink(
            "/dev/serial/by-id/usb-FTDI_FT232R-if00-port0",
            "../../ttyUSB0",
        );
        fake.file("/dev/spidev0.0", "");
        fake.file("/etc/group", &format!("motion:x:{}:\n", fake.file_gid()));
        fake.file(
            "/etc/passwd",
            &format!("motion:x:{UID}:{UID}::/:/usr/sbin/nologin\n"),
        );
    }

    #[test]
    fn access_pass_warn_fail() {
        let fake = FakeRoot::new();
        assert_eq!(fake.check(access).status, Status::Pass, "no links");
        devices(&fake);
        fake.set_config(LINKS);
        fake.chmod("/dev/ttyUSB0", 0o660);
        fake.chmod("/dev/spidev0.0", 0o660);
        // Not in the devices' group: fail, and the fix names the udev rules.
        let check = fake.check(access);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(
            check.value.contains("motion cannot read and write it"),
            "{check:?}"
        );
        assert!(check.fix.contains("60-motiond.rules"), "{check:?}");
        // In the group: pass.
        fake.identity(UID, &[fake.file_gid()], 0);
        let check = fake.check(access);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("0660"), "{check:?}");
        // World-writable: warn.
        fake.chmod("/dev/spidev0.0", 0o666);
        let check = fake.check(access);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(check.fix.contains("chmod o-rw /dev/spidev0.0"), "{check:?}");
        // Root proves nothing: warn.
        fake.chmod("/dev/spidev0.0", 0o600);
        fake.identity(0, &[], u64::MAX);
        let check = fake.check(access);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(check.fix.contains("sudo -u motion motionctl doctor"));
        // Missing: fail.
        fake.remove("/dev/ttyUSB0");
        let check = fake.check(access);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.value.contains("is missing"));
    }

    #[test]
    fn latency_timer_pass_warn_fail() {
        let fake = FakeRoot::new();
        assert_eq!(fake.check(latency_timer).status, Status::Pass, "no links");
        devices(&fake);
        fake.set_config(LINKS);
        // A CDC-ACM or CP210x adapter has no latency timer.
        let check = fake.check(latency_timer);
        assert_eq!(check.status, Status::Pass);
        assert!(
            check.value.contains("ttyUSB0: no latency timer"),
            "{check:?}"
        );
        let file = "/sys/bus/usb-serial/devices/ttyUSB0/latency_timer";
        fake.file(file, "16");
        let check = fake.check(latency_timer);
        assert_eq!(check.status, Status::Fail);
        assert!(check.value.contains("ttyUSB0: 16 ms"), "{check:?}");
        assert!(
            check.fix.contains(&format!("echo 1 | sudo tee {file}")),
            "{check:?}"
        );
        fake.file(file, "4");
        assert_eq!(fake.check(latency_timer).status, Status::Warn);
        fake.file(file, "1");
        assert_eq!(fake.check(latency_timer).status, Status::Pass);
        fake.remove("/dev/ttyUSB0");
        assert_eq!(fake.check(latency_timer).status, Status::Warn);
    }

    #[test]
    fn dma_latency_pass_warn_fail() {
        let fake = FakeRoot::new();
        devices(&fake);
        fake.file("/dev/cpu_dma_latency", "");
        fake.chmod("/dev/cpu_dma_latency", 0o600);
        let check = fake.check(dma_latency);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        fake.set_config("[server]\nrt_priority = 80\n");
        let check = fake.check(dma_latency);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.fix.contains("60-motiond.rules"));
        fake.chmod("/dev/cpu_dma_latency", 0o660);
        fake.identity(UID, &[fake.file_gid()], 0);
        let check = fake.check(dma_latency);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        fake.remove("/dev/cpu_dma_latency");
        assert_eq!(fake.check(dma_latency).status, Status::Fail);
    }
}
