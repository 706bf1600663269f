//! The simulated QSB-M as a machine: encoder counts per motor step (either sign) and the
//! external stepper driver's enable line on a DIG I/O bit. Quotes are from the QSB Command
//! List, document version 1.28.

use core::time::Duration;

use board_qsb::sim::{DriveEnable, QsbSim, QsbSimConfig};
use motion_link::sim::StreamDevice;
use qsb::{Response, ResponseDecoder, ResponseType};

const MS: Duration = Duration::from_millis(1);

/// A host on a perfect wire.
struct Host {
    sim: QsbSim,
    decoder: ResponseDecoder,
    now: Duration,
}

impl Host {
    fn new(config: QsbSimConfig) -> Self {
        Self {
            sim: QsbSim::new(config),
            decoder: ResponseDecoder::new(),
            now: Duration::ZERO,
        }
    }

    /// Sends `text` and returns its answer.
    fn ask(&mut self, text: &str) -> Response {
        self.sim.receive(self.now, format!("{text}\r\n").as_bytes());
        self.now += MS;
        let mut buf = [0u8; 256];
        let n = self.sim.transmit(self.now, &mut buf);
        let (_, response) = self.decoder.decode(&buf[..n]);
        let response = response.unwrap_or_else(|| panic!("no answer to {text}"));
        assert!(
            matches!(response.ty, ResponseType::Read | ResponseType::Write),
            "{text}: {response:?}"
        );
        response
    }

    fn run_for(&mut self, d: Duration) {
        let until = self.now + d;
        while self.now < until {
            self.now += MS;
            let mut buf = [0u8; 256];
            while self.sim.transmit(self.now, &mut buf) > 0 {}
        }
    }

    /// OTR: "A read of the OTR register returns an instantaneous snapshot of the
    /// quadrature counter register (CNTR)."
    fn count(&mut self) -> i32 {
        self.ask("R07").data as i32
    }

    /// x4 free-running counting, motor drive on, 1000 steps/s.
    fn drive(&mut self) {
        self.ask("W0343"); // "Sync Index, … Free Running, X4 mode" without the index
        self.ask("W162"); // "Activate motor drive mode"
        self.ask("W0F3E8"); // "1000 steps/sec, W0F3E8"
    }

    /// "2000 steps, W117D0" then COMMAND 8, and waits for the move to end.
    fn move_2000(&mut self) {
        self.ask("W117D0");
        self.ask("W168");
        self.run_for(Duration::from_secs(3));
        assert!(self.sim.md_status().done);
    }
}

#[test]
fn the_encoder_moves_counts_per_step_counts_per_step_and_a_negative_one_reverses() {
    for (counts_per_step, expected) in [(4.0, 8000), (10.0, 20_000), (-4.0, -8000)] {
        let config = QsbSimConfig::default().with_counts_per_step(counts_per_step);
        assert_eq!(config.cycles_per_step, counts_per_step / 4.0);
        let mut host = Host::new(config);
        host.drive();
        host.move_2000();
        assert_eq!(host.sim.motor_position(), 2000.0);
        assert_eq!(host.count(), expected, "{counts_per_step} counts per step");
    }
}

#[test]
fn an_inactive_enable_line_leaves_the_shaft_where_it_is() {
    let line = DriveEnable {
        bit: 3,
        active_high: false,
    };
    let mut host = Host::new(QsbSimConfig {
        drive_enable: Some(line),
        ..QsbSimConfig::default().with_counts_per_step(4.0)
    });
    host.drive();
    // "All I/O port pins will be set "high" after a write to this configuration
    // register": io3 an output, released high: an active-low enable is inactive.
    host.ask("W02800");
    assert_eq!(host.sim.digital_outputs(), (0x8, 0xF));
    assert!(!host.sim.drive_energised());
    host.move_2000();
    assert_eq!(host.sim.motor_position(), 2000.0, "the pulses were sent");
    assert_eq!(host.count(), 0, "but the motor did not follow");
    // io3 low: enabled; the next move turns the shaft.
    host.ask("W017");
    assert!(host.sim.drive_energised());
    assert_eq!(host.sim.digital_pins() & 0x8, 0);
    host.move_2000();
    assert_eq!(host.count(), 8000);
    // Without an enable line configured, the drive is always enabled.
    let host = Host::new(QsbSimConfig::default());
    assert!(host.sim.drive_energised());
}
