//! Start-up: the sequence of the module docs ("Start-up"), the VERSION register as the
//! driver records it (the firmware description of the board's status, "QSB-M SN 00001 fw
//! 13"), and what happens when the board stops answering or resets.

use core::fmt::Write as _;
use motion_base::FixedQueue;

use ::qsb::{Mode, ProductType, QsbCommand, Register, Request, Write};

use super::config::DRIVER_EOR;
use super::program::{self, Step};
use super::{QsbDriver, REGISTERS};
use motion_drivers::FIRMWARE_LEN;

impl QsbDriver {
    /// (Re)starts the start-up sequence; the last known position stays.
    pub(super) fn begin_startup(&mut self) {
        self.setup.replace(&[
            Step::Send(Request::Write(Write::Command(QsbCommand::StopStreaming))),
            Step::Send(Request::Read(Register::Version)),
            Step::Configure,
        ]);
        self.preset.clear();
        self.goal.clear();
        self.goal_kind = None;
        self.in_flight = None;
        self.eor_until = None;
        self.attempts = 0;
        self.restart_at = None;
        self.probe_due = false;
        self.status.online = false;
        self.board = [None; REGISTERS];
        self.eor_configured = false;
        self.rebase_pending = true;
        self.md = None;
        self.md_disabled_once = false;
        self.str_streaming = false;
        self.index_armed = false;
        self.index_seen = false;
        self.home_start = None;
        self.home_deadline = None;
        self.home_failed = false;
        // Outputs keep the levels the signals asked for; the enable line comes up active
        // (the engine's start-up stop holds the motor energised).
        self.io.energised = true;
        self.io.refused = None;
        self.io.dio_streaming = false;
        self.io.capture_streaming = false;
        self.events.latched = false;
    }

    /// The configuration of the product VERSION reported (module docs, "Start-up").
    pub(super) fn configure(&mut self, product: ProductType) {
        let (rate, accel) = self.config.default_profile();
        let drive = self.drive_active();
        let mdr1 = self.normal_mdr1();
        // DTR before MDR0: a range-limit or modulo-n mode starts with its limit (the
        // compare position, otherwise).
        let counter = self.config.counter;
        let dtr = self
            .normal_dtr()
            .map(|value| Step::Ensure(Write::Dtr(value)));
        let common = [
            Step::Ensure(Write::Eor(DRIVER_EOR)),
            Step::Ensure(Write::Mode(Mode {
                encoder: self.config.input_mode,
                pwm_12bit: false,
            })),
        ];
        let counter_steps = [
            Step::Ensure(Write::Mdr0(counter.mdr0())),
            Step::Ensure(Write::Mdr1(mdr1)),
            Step::Ensure(Write::Threshold(0)),
            Step::Ensure(Write::IntervalRate(self.config.interval())),
        ];
        let mut steps = FixedQueue::<Step, { program::PROGRAM_CAPACITY }>::new();
        let mut push = |step: Step| {
            steps.push(step);
        };
        let has_dio = product.digital_io_bits() > 0;
        if product == ProductType::M {
            // Whatever the motor was doing, it stops, at the axis's acceleration.
            push(Step::Ensure(Write::Accel(accel)));
            push(Step::Send(Request::Write(Write::Command(
                QsbCommand::MotorStop,
            ))));
        }
        common.into_iter().for_each(&mut push);
        dtr.into_iter().for_each(&mut push);
        counter_steps.into_iter().for_each(&mut push);
        if drive {
            push(Step::Ensure(Write::StepRate(rate)));
        }
        if has_dio && self.dio_used() {
            // Read first: a configuration the board already holds is not written again,
            // because a write sets every pin high for a moment.
            push(Step::Send(Request::Read(Register::DigIoConfig)));
            push(Step::Ensure(Write::DigIoConfig(self.dio_config())));
            push(Step::Outputs);
        }
        if drive {
            push(Step::Send(Request::Write(Write::Command(
                QsbCommand::EnableMotorDrive,
            ))));
        }
        self.stream_steps(product, &mut push);
        push(Step::Online);
        self.setup.expand_front(steps.iter());
    }

    /// The stream requests of the configuration, READ ENCODER last.
    fn stream_steps(&self, product: ProductType, push: &mut impl FnMut(Step)) {
        let has_dio = product.digital_io_bits() > 0;
        if product == ProductType::M && self.drive_active() {
            push(Step::Send(Request::Stream(Register::MdStatus)));
        }
        if has_dio && self.dio_streamed() {
            push(Step::Send(Request::Stream(Register::DigIo)));
        }
        if self.config.io.capture.is_some() || self.config.trigger.index {
            push(Step::Send(Request::Stream(Register::Capture)));
        }
        if self.str_wanted() && has_dio {
            // The trigger's pulses, as STR latches (cleared once the board is online).
            push(Step::Send(Request::Stream(Register::Str)));
        }
        push(Step::Send(Request::Stream(Register::ReadEncoder)));
    }

    /// Asks for the streams again, ahead of any goal: the board answers without having
    /// restarted (its TIME STAMP went on), so the rest of its configuration holds, but its
    /// stream stayed quiet over two probes.
    pub(super) fn restream(&mut self) {
        let Some(product) = self.product else {
            return;
        };
        let mut steps = FixedQueue::<Step, { program::PROGRAM_CAPACITY }>::new();
        self.stream_steps(product, &mut |step| {
            steps.push(step);
        });
        // A placeholder at the front for `expand_front` to replace.
        self.setup.replace(&[Step::Online]);
        self.setup.expand_front(steps.iter());
    }

    /// Records the VERSION answer as the firmware description.
    pub(super) fn record_version(&mut self, version: ::qsb::Version) {
        let mut text = motion_base::FixedText::<FIRMWARE_LEN>::new();
        let product = match version.product {
            ProductType::D => 'D',
            ProductType::M => 'M',
            ProductType::S => 'S',
        };
        // The buffer is larger than the longest description; a failure only cuts it.
        let _ = write!(
            text,
            "QSB-{product} SN {:05X} fw {:02X}",
            version.serial, version.firmware
        );
        self.status.set_firmware(text.as_str());
        self.product = Some(version.product);
        self.serial = Some(version.serial);
    }
}
