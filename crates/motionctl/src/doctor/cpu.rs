//! The cores: frequency governor, isolation of the tick's core, and where the interrupts of
//! the links' devices land.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::check::{Check, Context, Status};
use super::host::{Host, format_cpu_list, parse_cpu_list};

/// The cores a check is about: the configured `cpu`, else every online core.
fn cores(cx: &Context<'_>) -> BTreeSet<usize> {
    match cx.config.server.cpu {
        Some(cpu) => BTreeSet::from([cpu]),
        None => cx.host.online_cpus().unwrap_or_default(),
    }
}

const GOVERNOR: &str = "cpu-governor";
const GOVERNOR_T: &str = "CPU frequency governor";

/// `performance` passes (or no frequency scaling at all); a dynamic governor warns (each
/// wake-up may find the core slowed down); `powersave` under a driver where it means the
/// lowest frequency (acpi-cpufreq and other generic drivers) fails.
pub fn governor(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let cores = cores(cx);
    if cores.is_empty() {
        return Check::warn(
            GOVERNOR,
            GOVERNOR_T,
            "unknown (/sys/devices/system/cpu/online unreadable)",
            "run the doctor on the machine itself, with /sys mounted",
        );
    }
    let mut by_setting: BTreeMap<(Status, String), BTreeSet<usize>> = BTreeMap::new();
    for &cpu in &cores {
        let dir = format!("/sys/devices/system/cpu/cpu{cpu}/cpufreq");
        let (status, text) = match host.read(&format!("{dir}/scaling_governor")) {
            None => (Status::Pass, "not scaled (no cpufreq)".to_owned()),
            Some(governor) => {
                let driver = host
                    .read(&format!("{dir}/scaling_driver"))
                    .unwrap_or_else(|| "unknown driver".to_owned());
                // intel_pstate and amd-pstate-epp in active mode run their own dynamic
                // algorithm under the name `powersave`; elsewhere it pins the lowest speed.
                let dynamic_powersave =
                    matches!(driver.as_str(), "intel_pstate" | "amd-pstate-epp");
                let status = match governor.as_str() {
                    "performance" => Status::Pass,
                    "powersave" if !dynamic_powersave => Status::Fail,
                    _ => Status::Warn,
                };
                let note = match (governor.as_str(), status) {
                    ("powersave", Status::Fail) => ": the lowest frequency, always",
                    (_, Status::Warn) => ": the frequency follows the load",
                    _ => "",
                };
                (status, format!("{governor} ({driver}){note}"))
            }
        };
        by_setting.entry((status, text)).or_default().insert(cpu);
    }
    let status = by_setting
        .keys()
        .map(|(s, _)| *s)
        .max()
        .unwrap_or(Status::Pass);
    let value: Vec<String> = by_setting
        .iter()
        .map(|((_, text), cpus)| format!("cpu {}: {text}", format_cpu_list(cpus)))
        .collect();
    let list = format_cpu_list(&cores);
    Check::with(
        GOVERNOR,
        GOVERNOR_T,
        status,
        value.join("; "),
        format!(
            "sudo cpupower -c {list} frequency-set -g performance (or write `performance` to \
             /sys/devices/system/cpu/cpuN/cpufreq/scaling_governor for cpu {list}); keep it across \
             reboots with a oneshot unit or your distribution's cpufrequtils/tuned profile"
        ),
    )
}

const ISOLATION: &str = "cpu-isolation";
const ISOLATION_T: &str = "isolation of the tick's core (isolcpus, nohz_full, rcu_nocbs)";

/// With `[server] cpu = N`: the core is online (else motiond cannot pin), and the kernel
/// command line keeps other work (`isolcpus`), the periodic tick (`nohz_full`) and RCU
/// callbacks (`rcu_nocbs`) off it.
pub fn isolation(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let Some(cpu) = cx.config.server.cpu else {
        return Check::warn(
            ISOLATION,
            ISOLATION_T,
            "no [server] cpu in the config: the tick thread runs on any core, beside everything else",
            "set [server] cpu = N (a core other than 0) and boot with `isolcpus=N nohz_full=N \
             rcu_nocbs=N` (Debian: GRUB_CMDLINE_LINUX in /etc/default/grub, then update-grub)",
        );
    };
    let online = host.online_cpus();
    if let Some(online) = &online
        && !online.contains(&cpu)
    {
        return Check::fail(
            ISOLATION,
            ISOLATION_T,
            format!(
                "cpu {cpu} is not online (online: {}): motiond cannot pin its tick there",
                format_cpu_list(online)
            ),
            format!(
                "set [server] cpu to an online core ({}), or bring cpu {cpu} online",
                format_cpu_list(online)
            ),
        );
    }
    let cmdline = host.read("/proc/cmdline").unwrap_or_default();
    let param = |name: &str| -> Option<BTreeSet<usize>> {
        cmdline
            .split_whitespace()
            .filter_map(|w| w.strip_prefix(name)?.strip_prefix('='))
            .filter_map(parse_cpu_list)
            .next_back()
    };
    // rcu_nocbs without a list (recent kernels) offloads every core.
    let rcu_all = cmdline.split_whitespace().any(|w| w == "rcu_nocbs");
    let isolated = param("isolcpus")
        .or_else(|| {
            host.read("/sys/devices/system/cpu/isolated")
                .and_then(|t| parse_cpu_list(&t))
        })
        .unwrap_or_default();
    let nohz = param("nohz_full")
        .or_else(|| {
            host.read("/sys/devices/system/cpu/nohz_full")
                .and_then(|t| parse_cpu_list(&t))
        })
        .unwrap_or_default();
    let rcu = param("rcu_nocbs").unwrap_or_default();
    let mut have = Vec::new();
    let mut missing = Vec::new();
    for (name, covered) in [
        ("isolcpus", isolated.contains(&cpu)),
        ("nohz_full", nohz.contains(&cpu)),
        ("rcu_nocbs", rcu_all || rcu.contains(&cpu)),
    ] {
        if covered {
            have.push(name);
        } else {
            missing.push(name);
        }
    }
    if missing.is_empty() {
        return Check::pass(
            ISOLATION,
            ISOLATION_T,
            format!("cpu {cpu}: isolcpus, nohz_full and rcu_nocbs"),
        );
    }
    Check::warn(
        ISOLATION,
        ISOLATION_T,
        format!(
            "cpu {cpu}: {} (missing {})",
            if have.is_empty() {
                "not isolated".to_owned()
            } else {
                have.join(", ")
            },
            missing.join(", ")
        ),
        format!(
            "boot with `{}` on the kernel command line (Debian: GRUB_CMDLINE_LINUX in \
             /etc/default/grub, then update-grub; Raspberry Pi: /boot/firmware/cmdline.txt)",
            missing
                .iter()
                .map(|name| format!("{name}={cpu}"))
                .collect::<Vec<_>>()
                .join(" ")
        ),
    )
}

const IRQ: &str = "irq-affinity";
const IRQ_T: &str = "interrupts of the links' devices";

/// Finds the interrupts of a tty or spidev: its class directory's `irq` (8250 UARTs), else
/// the first device up its sysfs path with an `irq` or `msi_irqs` (a USB adapter's host
/// controller), else a `/proc/interrupts` line naming one of those devices or their drivers.
fn irqs_of(
    host: &Host<'_>,
    link_path: &Path,
    spidev: bool,
) -> Result<(String, BTreeSet<u32>), String> {
    let resolved = host
        .resolve(link_path)
        .ok_or_else(|| format!("{}: missing", link_path.display()))?;
    let name = resolved
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let class = host.path(&format!(
        "/sys/class/{}/{name}",
        if spidev { "spidev" } else { "tty" }
    ));
    let mut irqs = BTreeSet::new();
    if let Some(irq) = host
        .read_path(&class.join("irq"))
        .and_then(|t| t.parse().ok())
        && irq != 0
    {
        irqs.insert(irq);
        return Ok((name, irqs));
    }
    let device = host
        .resolve(&host.unroot(&class.join("device")))
        .ok_or_else(|| {
            format!(
                "{name}: no device in /sys/class (not a {} device?)",
                if spidev { "spidev" } else { "tty" }
            )
        })?;
    let sys_devices = host.path("/sys/devices");
    let mut names: Vec<String> = Vec::new();
    let mut dir: Option<PathBuf> = Some(device);
    while let Some(current) = dir {
        if !current.starts_with(&sys_devices) || current == sys_devices {
            break;
        }
        if let Some(irq) = host
            .read_path(&current.join("irq"))
            .and_then(|t| t.parse::<u32>().ok())
            && irq != 0
        {
            irqs.insert(irq);
        }
        if let Ok(entries) = std::fs::read_dir(current.join("msi_irqs")) {
            irqs.extend(entries.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok()));
        }
        if !irqs.is_empty() {
            return Ok((name, irqs));
        }
        if let Some(base) = current.file_name() {
            names.push(base.to_string_lossy().into_owned());
        }
        if let Ok(driver) = std::fs::read_link(current.join("driver"))
            && let Some(base) = driver.file_name()
        {
            names.push(base.to_string_lossy().into_owned());
        }
        dir = current.parent().map(Path::to_path_buf);
    }
    let interrupts = host.read("/proc/interrupts").unwrap_or_default();
    for line in interrupts.lines() {
        let Some((number, rest)) = line.split_once(':') else {
            continue;
        };
        let Ok(number) = number.trim().parse::<u32>() else {
            continue;
        };
        if rest
            .split(|c: char| c.is_whitespace() || c == ',')
            .any(|word| !word.is_empty() && names.iter().any(|n| n == word))
        {
            irqs.insert(number);
        }
    }
    if irqs.is_empty() {
        Err(format!(
            "{name}: its interrupt was not found in sysfs or /proc/interrupts"
        ))
    } else {
        Ok((name, irqs))
    }
}

/// Where each link's device interrupts may land, against the tick's core: an interrupt that
/// can land on it warns, one that always lands there fails.
pub fn irq_affinity(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let links: Vec<_> = cx.config.device_links().collect();
    if links.is_empty() {
        return Check::pass(IRQ, IRQ_T, "no serial or spidev links in the config");
    }
    let tick = cx.config.server.cpu;
    let mut status = Status::Pass;
    let mut values = Vec::new();
    let mut fixes = Vec::new();
    for (link, path) in links {
        match irqs_of(host, path, link.is_spidev()) {
            Err(e) => {
                status = status.max(Status::Warn);
                values.push(e);
            }
            Ok((name, irqs)) => {
                for irq in irqs {
                    let affinity = host
                        .read(&format!("/proc/irq/{irq}/effective_affinity_list"))
                        .filter(|t| !t.is_empty())
                        .or_else(|| host.read(&format!("/proc/irq/{irq}/smp_affinity_list")))
                        .and_then(|t| parse_cpu_list(&t));
                    let Some(affinity) = affinity else {
                        status = status.max(Status::Warn);
                        values.push(format!("{name}: irq {irq}, affinity unreadable"));
                        continue;
                    };
                    let cpus = format_cpu_list(&affinity);
                    let verdict = match tick {
                        Some(cpu) if affinity == BTreeSet::from([cpu]) => Status::Fail,
                        Some(cpu) if affinity.contains(&cpu) => Status::Warn,
                        _ => Status::Pass,
                    };
                    status = status.max(verdict);
                    values.push(format!("{name}: irq {irq} on cpu {cpus}"));
                    if verdict != Status::Pass
                        && let Some(cpu) = tick
                    {
                        let others: BTreeSet<usize> = host
                            .online_cpus()
                            .unwrap_or_default()
                            .into_iter()
                            .filter(|&c| c != cpu)
                            .collect();
                        fixes.push(format!(
                            "echo {} | sudo tee /proc/irq/{irq}/smp_affinity_list",
                            format_cpu_list(&others)
                        ));
                    }
                }
            }
        }
    }
    let value = match tick {
        Some(cpu) => format!("{} (tick on cpu {cpu})", values.join("; ")),
        None => format!(
            "{} (no [server] cpu: nothing to keep them off)",
            values.join("; ")
        ),
    };
    let fix = if fixes.is_empty() {
        "check the link paths (a device the doctor cannot find has no interrupt to place)"
            .to_owned()
    } else {
        format!(
            "keep the links' interrupts off the tick's core: {}; at boot with `irqaffinity=` on the \
             kernel command line (isolcpus=managed_irq,… does it for managed interrupts)",
            fixes.join("; ")
        )
    };
    Check::with(IRQ, IRQ_T, status, value, fix)
}

#[cfg(test)]
mod tests {
    use super::super::fake::FakeRoot;
    use super::*;

    #[test]
    fn governor_pass_warn_fail() {
        let fake = FakeRoot::new();
        fake.file("/sys/devices/system/cpu/online", "0-1");
        // No cpufreq (a VM, or fixed frequency).
        let check = fake.check(governor);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("cpu 0-1: not scaled"), "{check:?}");
        for cpu in 0..2 {
            fake.file(
                &format!("/sys/devices/system/cpu/cpu{cpu}/cpufreq/scaling_driver"),
                "acpi-cpufreq",
            );
            fake.file(
                &format!("/sys/devices/system/cpu/cpu{cpu}/cpufreq/scaling_governor"),
                "performance",
            );
        }
        assert_eq!(fake.check(governor).status, Status::Pass);
        fake.file(
            "/sys/devices/system/cpu/cpu1/cpufreq/scaling_governor",
            "schedutil",
        );
        let check = fake.check(governor);
        assert_eq!(check.status, Status::Warn);
        assert!(check.value.contains("cpu 1: schedutil"), "{check:?}");
        assert!(check.fix.contains("frequency-set -g performance"));
        fake.file(
            "/sys/devices/system/cpu/cpu1/cpufreq/scaling_governor",
            "powersave",
        );
        assert_eq!(fake.check(governor).status, Status::Fail);
        // intel_pstate's powersave is dynamic: a warning.
        fake.file(
            "/sys/devices/system/cpu/cpu1/cpufreq/scaling_driver",
            "intel_pstate",
        );
        assert_eq!(fake.check(governor).status, Status::Warn);
        // Only the configured core counts.
        fake.set_config("[server]\ncpu = 0\n");
        assert_eq!(fake.check(governor).status, Status::Pass);
    }

    #[test]
    fn isolation_pass_warn_fail() {
        let fake = FakeRoot::new();
        fake.file("/sys/devices/system/cpu/online", "0-3");
        fake.file("/proc/cmdline", "root=/dev/sda1 quiet");
        let check = fake.check(isolation);
        assert_eq!(check.status, Status::Warn, "no cpu configured");
        assert!(check.fix.contains("[server] cpu"));
        fake.set_config("[server]\ncpu = 3\n");
        let check = fake.check(isolation);
        assert_eq!(check.status, Status::Warn);
        assert!(check.value.contains("not isolated"), "{check:?}");
        assert!(
            check.fix.contains("isolcpus=3 nohz_full=3 rcu_nocbs=3"),
            "{check:?}"
        );
        fake.file(
            "/proc/cmdline",
            "root=/dev/sda1 isolcpus=domain,managed_irq,2-3 nohz_full=2-3",
        );
        let check = fake.check(isolation);
        assert_eq!(check.status, Status::Warn);
        assert!(
            check
                .value
                .contains("isolcpus, nohz_full (missing rcu_nocbs)"),
            "{check:?}"
        );
        fake.file("/proc/cmdline", "isolcpus=2-3 nohz_full=2-3 rcu_nocbs=1,3");
        assert_eq!(fake.check(isolation).status, Status::Pass);
        fake.file("/proc/cmdline", "isolcpus=3 nohz_full=3 rcu_nocbs");
        assert_eq!(fake.check(isolation).status, Status::Pass);
        fake.set_config("[server]\ncpu = 5\n");
        let check = fake.check(isolation);
        assert_eq!(check.status, Status::Fail);
        assert!(
            check.value.contains("not online (online: 0-3)"),
            "{check:?}"
        );
    }

    /// A USB adapter on an xHCI controller with MSI interrupts 40 and 41, a native UART
    /// with its own `irq`, and a spidev found by its controller's name in /proc/interrupts.
    fn machine(fake: &FakeRoot) {
        fake.file("/sys/devices/system/cpu/online", "0-3");
        let usb = "/sys/devices/pci0000:00/0000:00:14.0";
        fake.file(&format!("{usb}/irq"), "0");
        fake.file(&format!("{usb}/msi_irqs/40"), "msix");
        fake.file(&format!("{usb}/msi_irqs/41"), "msix");
        fake.dir(&format!("{usb}/usb1/1-1/1-1:1.0/ttyUSB0/tty/ttyUSB0"));
        fake.symlink(
            "/sys/class/tty/ttyUSB0/device",
            "../../../devices/pci0000:00/0000:00:14.0/usb1/1-1/1-1:1.0/ttyUSB0",
        );
        fake.file("/dev/ttyUSB0", "");
        fake.symlink(
            "/dev/serial/by-id/usb-FTDI_FT232R-if00-port0",
            "../../ttyUSB0",
        );
        fake.file("/sys/class/tty/ttyS1/irq", "4");
        fake.file("/dev/ttyS1", "");
        let spi = "/sys/devices/platform/soc/fe204000.spi";
        fake.dir(&format!("{spi}/spi_master/spi0/spi0.0"));
        fake.symlink(
            "/sys/class/spidev/spidev0.0/device",
            "../../../devices/platform/soc/fe204000.spi/spi_master/spi0/spi0.0",
        );
        fake.file("/dev/spidev0.0", "");
        fake.file(
            "/proc/interrupts",
            "           CPU0       CPU1\n 36:   10  0  GICv2 150 Level  fe204000.spi\n 40:  5 6 PCI-MSI xhci_hcd\nNMI: 0 0 Non-maskable interrupts\n",
        );
        for (irq, cpus) in [(4, "0-3"), (36, "0-1"), (40, "0-3"), (41, "2")] {
            fake.file(&format!("/proc/irq/{irq}/smp_affinity_list"), cpus);
        }
    }

    const LINKS: &str = r#"
[[link]]
name = "rs485"
type = "serial"
path = "/dev/serial/by-id/usb-FTDI_FT232R-if00-port0"
[[link]]
name = "uart"
type = "serial"
path = "/dev/ttyS1"
[[link]]
name = "spi"
type = "spidev"
path = "/dev/spidev0.0"
[[link]]
name = "sim"
type = "sim"
"#;

    #[test]
    fn irq_affinity_pass_warn_fail() {
        let fake = FakeRoot::new();
        assert_eq!(fake.check(irq_affinity).status, Status::Pass, "no links");
        machine(&fake);
        fake.set_config(LINKS);
        let check = fake.check(irq_affinity);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        for part in [
            "ttyUSB0: irq 40 on cpu 0-3",
            "ttyUSB0: irq 41 on cpu 2",
            "ttyS1: irq 4 on cpu 0-3",
            "spidev0.0: irq 36 on cpu 0-1",
            "no [server] cpu",
        ] {
            assert!(check.value.contains(part), "{part} not in {check:?}");
        }
        // The tick on cpu 3: irqs 4 and 40 may land there.
        fake.set_config(&format!("[server]\ncpu = 3\n{LINKS}"));
        let check = fake.check(irq_affinity);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(
            check
                .fix
                .contains("echo 0-2 | sudo tee /proc/irq/4/smp_affinity_list"),
            "{check:?}"
        );
        // The tick on cpu 2: irq 41 always lands there.
        fake.set_config(&format!("[server]\ncpu = 2\n{LINKS}"));
        let check = fake.check(irq_affinity);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(
            check
                .fix
                .contains("echo 0-1,3 | sudo tee /proc/irq/41/smp_affinity_list"),
            "{check:?}"
        );
        // The effective affinity wins over the requested one.
        fake.file("/proc/irq/41/effective_affinity_list", "0");
        fake.file("/proc/irq/40/effective_affinity_list", "1");
        fake.file("/proc/irq/4/effective_affinity_list", "1");
        assert_eq!(fake.check(irq_affinity).status, Status::Pass);
        // A device that is not there cannot be placed: a warning.
        fake.remove("/dev/ttyS1");
        let check = fake.check(irq_affinity);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(check.value.contains("/dev/ttyS1: missing"), "{check:?}");
    }
}
