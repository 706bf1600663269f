//! Golden vectors: the examples of the QSB Command List (document version 1.28), quoted by
//! section, plus the response formats of docs/ARCHITECTURE.md ("How we read the datasheets", QSB).

use core::time::Duration;
use qsb::*;

/// Decodes a command as the board would and re-encodes it as a host would.
fn command(text: &str) -> Request {
    let request = Request::decode(text.as_bytes()).expect(text);
    let mut buf = [0u8; MAX_COMMAND_LEN];
    let n = request.encode(&mut buf).unwrap();
    assert_eq!(
        &buf[..n],
        format!("{text}\r\n").as_bytes(),
        "re-encode {text}"
    );
    request
}

#[test]
fn mdr0_example_w0363_sync_index_reset_on_index_free_running_x4() {
    // Command List, MDR0 03: "Example: Sync Index, Reset on Index, Free Running, X4 mode, W0363"
    let Request::Write(Write::Mdr0(m)) = command("W0363") else {
        panic!("not an MDR0 write")
    };
    assert_eq!(
        m,
        Mdr0 {
            count: CountMode::X4,
            cycle: CycleMode::FreeRunning,
            index: IndexMode::ResetCntr,
            synchronous_index: true,
            filter_div2: false,
        }
    );
    assert_eq!(m.counts_per_cycle(), 4);
}

#[test]
fn dig_io_config_example_w02f00_all_outputs() {
    // Command List, DIG I/O CONFIG 02: "Example: Set All I/O as Outputs, W02F00"
    let Request::Write(Write::DigIoConfig(c)) = command("W02F00") else {
        panic!("not a DIG I/O CONFIG write")
    };
    assert_eq!(c.output, 0xF);
    assert_eq!(c.interrupt_enable, 0);
    assert_eq!(c.falling_edge, 0);
    assert!(!c.trigger_pulse);
}

#[test]
fn interval_rate_example_w0c5_is_9_8_ms() {
    // Command List, INTERVAL RATE 0C: "Example: Set 9.8ms Interval, W0C5" (1.95 ms steps)
    let Request::Write(Write::IntervalRate(r)) = command("W0C5") else {
        panic!("not an INTERVAL RATE write")
    };
    assert_eq!(r, IntervalRate(5));
    let period = r.period().unwrap();
    assert_eq!(period, Duration::from_nanos(9_765_625));
    assert_eq!(IntervalRate::DISABLED.period(), None);
    assert_eq!(IntervalRate(0).period(), Some(Duration::ZERO));
    // "Set 9.8ms Interval": 9.8 ms is nearest to 5 ticks; "0x0001 = 1.95ms delay,
    // 0x0002 = 3.9ms delay".
    assert_eq!(
        IntervalRate::nearest(Duration::from_micros(9_800)),
        Some(IntervalRate(5))
    );
    assert_eq!(
        IntervalRate::nearest(Duration::from_micros(1_950)),
        Some(IntervalRate(1))
    );
    assert_eq!(
        IntervalRate::nearest(Duration::from_micros(3_900)),
        Some(IntervalRate(2))
    );
    assert_eq!(
        IntervalRate::nearest(Duration::from_micros(900)),
        Some(IntervalRate(0))
    );
    // "A value of 0xFFFF will disable data output": never the nearest of a period.
    assert_eq!(
        IntervalRate::nearest(IntervalRate::LONGEST.period().unwrap()),
        Some(IntervalRate::LONGEST)
    );
    assert_eq!(IntervalRate::nearest(Duration::from_secs(128)), None);
}

#[test]
fn command_example_w163_save_parameters() {
    // Command List, COMMAND 16: "Example: Save Parameters, W163"
    assert_eq!(
        command("W163"),
        Request::Write(Write::Command(QsbCommand::SaveParameters))
    );
}

#[test]
fn command_example_w1660a_230400_baud() {
    // Command List, COMMAND 16: "Set 230400 Baud, W1660A" (X0A with X = 6)
    let request = command("W1660A");
    assert_eq!(
        request,
        Request::Write(Write::Command(QsbCommand::SetBaud(BaudRate::B230400)))
    );
    assert_eq!(BaudRate::B230400.bits_per_second(), 230_400);
    // "Data range: 0 – 70A"
    assert_eq!(
        QsbCommand::from_data(0x70A),
        Ok(QsbCommand::SetBaud(BaudRate::B256000))
    );
    assert_eq!(
        QsbCommand::from_data(0x00A),
        Ok(QsbCommand::SetBaud(BaudRate::B9600))
    );
    assert_eq!(QsbCommand::from_data(0x80A), Err(Error::OutOfRange));
    assert_eq!(QsbCommand::from_data(0x10), Err(Error::OutOfRange));
}

#[test]
fn version_example_r14_00001201() {
    // Command List, VERSION 14: "Example, 00001201 = SN: 00001, Type: QSB-S, Version: 01"
    assert_eq!(command("R14"), Request::Read(Register::Version));
    for line in [
        &b"r 14 00001201 !\r\n"[..],
        b"r1400001201!\r\n",
        b"r1400001201!",
    ] {
        let response = Response::decode(line).unwrap();
        assert_eq!(response, Response::new(ResponseType::Read, 0x14, 0x1201));
        let Value::Version(v) = response.value().unwrap() else {
            panic!("not a version")
        };
        assert_eq!(v.serial, 0x00001);
        assert_eq!(v.product, ProductType::S);
        assert_eq!(v.firmware, 0x01);
        assert!(!v.supports_baud_selection());
    }
}

#[test]
fn factory_eor_0b_formats_with_spaces_cr_lf() {
    // Factory Default table: EOR 15 = B (CR, LF, spaces); docs/ARCHITECTURE.md: `r 14 00001201 !`
    let eor = Eor::from_data(defaults::EOR).unwrap();
    assert_eq!(eor, Eor::FACTORY);
    let mut buf = [0u8; MAX_RESPONSE_LEN];
    let n = Response::new(ResponseType::Read, 0x14, 0x1201)
        .encode(eor, &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], b"r 14 00001201 !\r\n");
    // docs/ARCHITECTURE.md wire budget example: `r0E00001234!\r\n` with EOR 3.
    let n = Response::new(ResponseType::Read, 0x0E, 0x1234)
        .encode(Eor::from_data(3).unwrap(), &mut buf)
        .unwrap();
    assert_eq!(&buf[..n], b"r0E00001234!\r\n");
    // "All Formatting Enabled, W15F": spaces, time stamp, CR, LF.
    let r = Response {
        ty: ResponseType::Stream,
        register: 0x0E,
        data: 0x1234,
        time_stamp: Some(0xABCD),
    };
    let n = r.encode(Eor::from_data(0xF).unwrap(), &mut buf).unwrap();
    assert_eq!(&buf[..n], b"s 0E 00001234 0000ABCD !\r\n");
    assert_eq!(Response::decode(&buf[..n]), Ok(r));
    // No termination at all: `!` ends the line.
    let n = r.encode(Eor::from_data(4).unwrap(), &mut buf).unwrap();
    assert_eq!(&buf[..n], b"s0E000012340000ABCD!");
    assert_eq!(Response::decode(&buf[..n]), Ok(r));
}

#[test]
fn write_acknowledgement_example_mode_quadrature() {
    // Command Acknowledgement Format: "w", "00", "00000000", "!", followed by the EOR.
    let r = Response::decode(b"w0000000000!\r\n").unwrap();
    assert_eq!(r.ty, ResponseType::Write);
    assert_eq!(
        r.value(),
        Ok(Value::Mode(Mode {
            encoder: EncoderMode::Quadrature,
            pwm_12bit: false
        }))
    );
}

#[test]
fn negative_values_are_twos_complement() {
    // Command Format: "Negative values must be entered as four hex bytes in two's-complement"
    // MD JOG RATE: "Data range: FFFFCD38 to 000032C8"
    assert_eq!(
        command("W12FFFFCD38"),
        Request::Write(Write::JogRate(-13000))
    );
    assert_eq!(command("W1232C8"), Request::Write(Write::JogRate(13000)));
    assert_eq!(Request::decode(b"W12FFFFCD37"), Err(Error::OutOfRange));
    // "less than 8 ASCII hex bytes ... converted to a positive signed long value"
    assert_eq!(Request::decode(b"W12CD38"), Err(Error::OutOfRange));
    // MD MOVE STEPS: "Data range: 80000001 to 7FFFFFFF"
    assert_eq!(
        command("W1180000001"),
        Request::Write(Write::MoveSteps(-i32::MAX))
    );
    assert_eq!(Request::decode(b"W1180000000"), Err(Error::OutOfRange));
    let r = Response::decode(b"r 0E FFFFFF9C !\r\n").unwrap();
    assert_eq!(r.signed(), -100);
}

#[test]
fn every_register_example_of_the_command_list() {
    use Request::*;
    let cases: [(&str, Request); 19] = [
        // "Example: Set PWM Encoder Mode, W0001"
        (
            "W001",
            Write(qsb::Write::Mode(Mode {
                encoder: EncoderMode::Pwm,
                pwm_12bit: false,
            })),
        ),
        // "Example: Stream Digital I/O Inputs: S01"
        ("S01", Stream(Register::DigIo)),
        // "Example: Count Up No Triggers, W04000"
        ("W040", Write(qsb::Write::Mdr1(Mdr1::default()))),
        // "Example: Read Captured Value, R05"
        ("R05", Read(Register::Capture)),
        // "Example: Read Status Register, R06"
        ("R06", Read(Register::Str)),
        // "Example: Read OTR Register, R07"
        ("R07", Read(Register::Otr)),
        // "Example: Write 499 decimal to DTR, W081F3"
        ("W081F3", Write(qsb::Write::Dtr(499))),
        // "Example: Clear CNTR, W092"
        ("W092", Write(qsb::Write::Clear(ClearTarget::Cntr))),
        // "Example: Transfer CNTR->OTR, W0A1"
        ("W0A1", Write(qsb::Write::Load(LoadTarget::CntrToOtr))),
        // "Example: Read THRESHOLD, R0B"
        ("R0B", Read(Register::Threshold)),
        // "Example: Reset TIME STAMP, W0D1"
        ("W0D1", Write(qsb::Write::TimeStamp(TIME_STAMP_CLEAR))),
        // "Example: Stream Encoder Value, S0E"
        ("S0E", Stream(Register::ReadEncoder)),
        // "Example: 1000 steps/sec, W0F3E8"
        ("W0F3E8", Write(qsb::Write::StepRate(1000))),
        // "Example: 100K steps/sec, W10186A0"
        ("W10186A0", Write(qsb::Write::Accel(100_000))),
        // "Example: 2000 steps, W117D0"
        ("W117D0", Write(qsb::Write::MoveSteps(2000))),
        // "Example: 1000 steps/sec, W123E8"
        ("W123E8", Write(qsb::Write::JogRate(1000))),
        // "Example: Read MD STATUS, R13"
        ("R13", Read(Register::MdStatus)),
        // "Example: All Formatting Enabled, W15F"
        ("W15F", Write(qsb::Write::Eor(Eor::from_data(0xF).unwrap()))),
        // "Example: Read VERSION, R14"
        ("R14", Read(Register::Version)),
    ];
    for (text, expected) in cases {
        assert_eq!(command(text), expected, "{text}");
    }
    // The datasheet spells the examples with leading zeros and lower case digits too.
    assert_eq!(
        Request::decode(b"W0001"),
        Request::decode(b"W001"),
        "leading zeros are ignored"
    );
    assert_eq!(Request::decode(b"W04000"), Ok(command("W040")));
    assert_eq!(
        Request::decode(b"r14"),
        Err(Error::BadType),
        "upper-case types only"
    );
    assert_eq!(Request::decode(b"R0e"), Ok(Read(Register::ReadEncoder)));
}

#[test]
fn command_types_not_allowed_and_unknown_registers_are_not_permitted() {
    assert_eq!(Request::decode(b"W0712"), Err(Error::NotPermitted)); // OTR is R only
    assert_eq!(Request::decode(b"S00"), Err(Error::NotPermitted));
    assert_eq!(Request::decode(b"R16"), Err(Error::NotPermitted));
    assert_eq!(Request::decode(b"R17"), Err(Error::UnknownRegister));
    assert_eq!(Request::decode(b"W00"), Err(Error::MissingData));
    assert_eq!(Request::decode(b"W0013"), Err(Error::OutOfRange)); // "Data range: 00 – 12"
    assert_eq!(Request::decode(b"W0003"), Err(Error::OutOfRange)); // type 11 undefined
    assert_eq!(Request::decode(b"W0F1F"), Err(Error::OutOfRange)); // step rate < 0x20
    assert_eq!(Request::decode(b"W0F32C9"), Err(Error::OutOfRange));
    assert_eq!(Request::decode(b"W1057E41"), Err(Error::OutOfRange));
    assert_eq!(Request::decode(b"W0410001"), Err(Error::OutOfRange));
    // Products: "-D, -M" for DIG I/O; "-M" for the motor registers; COMMAND "-D and -S
    // Data=1, 3, x0A".
    let dig = Request::Read(Register::DigIo);
    assert_eq!(dig.check(ProductType::S), Err(Error::NotPermitted));
    assert_eq!(dig.check(ProductType::D), Ok(()));
    let jog = Request::Write(Write::Command(QsbCommand::MotorJog));
    assert_eq!(jog.check(ProductType::D), Err(Error::OutOfRange));
    assert_eq!(jog.check(ProductType::M), Ok(()));
    let save = Request::Write(Write::Command(QsbCommand::SaveParameters));
    assert_eq!(save.check(ProductType::S), Ok(()));
}

#[test]
fn error_and_unsupported_replies_surface_as_errors() {
    // "'e'=error, 'x'=unsupported command"; "Data will be the incorrect data value sent"
    let e = Response::decode(b"e 0F 0000001F !\r\n").unwrap();
    assert_eq!(
        e.check(),
        Err(Error::Rejected {
            register: 0x0F,
            data: 0x1F
        })
    );
    assert_eq!(e.value(), e.check().map(|_| Value::StepRate(0)));
    let x = Response::decode(b"x1700000000!").unwrap();
    assert_eq!(x.check(), Err(Error::Unsupported { register: 0x17 }));
    assert!(x.value().is_err());
}

#[test]
fn status_registers_decode_to_their_bits() {
    // STR factory default 0A: CEN and U/D.
    let s = Str::from_data(defaults::STR).unwrap();
    assert!(s.count_enabled && s.up && !s.carry && !s.power_loss);
    // MD STATUS factory default 1: Done/Ready.
    assert_eq!(
        MdStatus::from_data(defaults::MD_STATUS),
        Ok(MdStatus::POWER_UP)
    );
    // MDR0 factory 4F: x4, modulo-n, index disabled, synchronous index.
    let m = Mdr0::from_data(defaults::MDR0).unwrap();
    assert_eq!(
        (m.count, m.cycle, m.index, m.synchronous_index),
        (CountMode::X4, CycleMode::ModuloN, IndexMode::Disabled, true)
    );
    // Special analog format: time stamp 16 bits, digital 4 bits, 00, analog 10 bits.
    let a = AnalogSample::from_data(0x1234_A3FF).unwrap();
    assert_eq!((a.time_stamp, a.digital, a.analog), (0x1234, 0xA, 0x3FF));
    assert!((a.volts() - 5.0).abs() < 1e-9);
    assert_eq!(AnalogSample::from_data(0x0000_0400), Err(Error::OutOfRange));
    for r in Register::ALL {
        if let Some(d) = r.factory_default() {
            assert!(Value::decode(r, d).is_ok(), "{r:?} default decodes");
        }
    }
}

#[test]
fn mdr0_bit_table_each_row() {
    // Command List, MDR0 03, "BITS: B7 B6 B5 B4 B3 B2 B1 B0", one row at a time.
    let rows: [(u32, CountMode, CycleMode, IndexMode, bool, bool); 11] = [
        // "B1 B0 = 00: non-quadrature count mode. (A = clock, B = direction)."
        (
            0x00,
            CountMode::NonQuadrature,
            CycleMode::FreeRunning,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "= 01: x1 quadrature count mode (one count per quadrature cycle)."
        (
            0x01,
            CountMode::X1,
            CycleMode::FreeRunning,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "= 10: x2 quadrature count mode (two counts per quadrature cycle)."
        (
            0x02,
            CountMode::X2,
            CycleMode::FreeRunning,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "= 11: x4 quadrature count mode (four counts per quadrature cycle)."
        (
            0x03,
            CountMode::X4,
            CycleMode::FreeRunning,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "B3 B2 = 01: single-cycle count mode."
        (
            0x04,
            CountMode::NonQuadrature,
            CycleMode::SingleCycle,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "= 10: range-limit count mode."
        (
            0x08,
            CountMode::NonQuadrature,
            CycleMode::RangeLimit,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "= 11: modulo-n count mode."
        (
            0x0C,
            CountMode::NonQuadrature,
            CycleMode::ModuloN,
            IndexMode::Disabled,
            false,
            false,
        ),
        // "B5 B4 = 01: configure index as the "load CNTR" input (transfers DTR to CNTR)."
        (
            0x10,
            CountMode::NonQuadrature,
            CycleMode::FreeRunning,
            IndexMode::LoadCntr,
            false,
            false,
        ),
        // "= 10: configure index as the "reset CNTR" input (clears CNTR to 0)."
        (
            0x20,
            CountMode::NonQuadrature,
            CycleMode::FreeRunning,
            IndexMode::ResetCntr,
            false,
            false,
        ),
        // "= 11: configure index as the "load OTR" input (transfers CNTR to OTR)."
        (
            0x30,
            CountMode::NonQuadrature,
            CycleMode::FreeRunning,
            IndexMode::LoadOtr,
            false,
            false,
        ),
        // "B6 = 1: Synchronous Index", "B7 = 1: Filter clock division factor = 2".
        (
            0xC0,
            CountMode::NonQuadrature,
            CycleMode::FreeRunning,
            IndexMode::Disabled,
            true,
            true,
        ),
    ];
    for (data, count, cycle, index, synchronous_index, filter_div2) in rows {
        let m = Mdr0 {
            count,
            cycle,
            index,
            synchronous_index,
            filter_div2,
        };
        assert_eq!(Mdr0::from_data(data), Ok(m), "{data:#04x}");
        assert_eq!(m.data(), data);
    }
    // The counts each count mode makes per quadrature cycle.
    let per_cycle = [(0x00, 1), (0x01, 1), (0x02, 2), (0x03, 4)];
    for (data, counts) in per_cycle {
        assert_eq!(Mdr0::from_data(data).unwrap().counts_per_cycle(), counts);
    }
    // "Data range: 00 – FF".
    assert_eq!(Mdr0::from_data(0x100), Err(Error::OutOfRange));
    // The modes motiond writes: x1 modulo-n with the index resetting CNTR, synchronous.
    let Request::Write(Write::Mdr0(m)) = command("W036D") else {
        panic!("not an MDR0 write")
    };
    assert_eq!(
        (m.count, m.cycle, m.index, m.synchronous_index),
        (
            CountMode::X1,
            CycleMode::ModuloN,
            IndexMode::ResetCntr,
            true
        )
    );
}

#[test]
fn mdr1_bit_table_each_row_and_the_example_w04000() {
    // Command List, MDR1 04: "Example: Count Up No Triggers, W04000" ("leading zeros are
    // ignored": the host writes it as W040).
    let Ok(Request::Write(Write::Mdr1(m))) = Request::decode(b"W04000") else {
        panic!("not an MDR1 write")
    };
    assert_eq!(command("W040"), Request::Write(Write::Mdr1(m)));
    assert_eq!(m, Mdr1::default());
    let bit = |data: u32| Mdr1::from_data(data).unwrap();
    // "B2 = 1: Disable counting", "B3 … = 1: Invert Index", "B4 Trigger/Capture on Index",
    // "B5 Trigger on Match", "B6 Trigger on Underflow", "B7 Trigger on Overflow",
    // "B8 Counter Direction =1: Count-down mode (quad encoder only)".
    assert!(bit(0x004).disable_counting);
    assert!(bit(0x008).invert_index);
    assert!(bit(0x010).trigger_on_index);
    assert!(bit(0x020).trigger_on_match);
    assert!(bit(0x040).trigger_on_underflow);
    assert!(bit(0x080).trigger_on_overflow);
    assert!(bit(0x100).count_down);
    // "B1 B0 = Reserved – always set to 00 (32-bit counter mode only)": no other width.
    for reserved in [0x001, 0x002, 0x003] {
        assert_eq!(Mdr1::from_data(reserved), Err(Error::OutOfRange));
    }
    // "Data range: 00 - 1FF".
    assert_eq!(Mdr1::from_data(0x200), Err(Error::OutOfRange));
}
