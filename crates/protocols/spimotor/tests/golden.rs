//! Golden vectors from `spi-motor-protocol.txt`, quoting the section each one comes from.

use spimotor::{
    Access, Address, Coils, DUMMY, Direction, Error, Header, Identification, Motor, PAD,
    REPLY_OFFSET, Read, ReadPort, Reply, Request, SerialNumber, StepDelay, Transaction, Write,
};

fn encode(t: Transaction) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = t.encode(&mut buf).expect("fits");
    assert_eq!(n, t.len());
    buf[..n].to_vec()
}

/// "examples / move stepper to step 0x12345678":
/// `0x90` select destination with address 0x90 for WRITE, `0x41` port 0x41: set target
/// position, then `0x78 0x56 0x34 0x12`.
#[test]
fn example_move_stepper_to_step_0x12345678() {
    let t = Transaction::write(Address::DEFAULT, Write::TargetPosition(0x1234_5678));
    let wire = [0x90, 0x41, 0x78, 0x56, 0x34, 0x12];
    assert_eq!(encode(t), wire);
    assert_eq!(Transaction::decode(&wire), Ok(t));
}

/// "examples / read identification": `0x91` select destination with address 0x90 for READ,
/// `0x01` identify, then the host sends `xx` while it receives `0x73 's'`, `0x70 'p'`,
/// `0x69 'i'`, … "(spi_motor)".
#[test]
fn example_read_identification() {
    let t = Transaction::read(Address::DEFAULT, ReadPort::Identification);
    let mosi = encode(t);
    assert_eq!(&mosi[..2], &[0x91, 0x01]);
    assert!(mosi[2..].iter().all(|&b| b == DUMMY));
    assert_eq!(Transaction::decode(&mosi), Ok(t));

    // The board's answer, as the table prints it, from the third byte on.
    let mut miso = vec![0xA5u8; mosi.len()];
    miso[2..12].copy_from_slice(&[0x73, 0x70, 0x69, b'_', b'm', b'o', b't', b'o', b'r', 0]);
    let reply = Reply::decode(ReadPort::Identification, &miso).expect("terminated");
    let Reply::Identification(id) = reply else {
        panic!("wrong reply {reply:?}")
    };
    assert_eq!(id.as_str(), Some("spi_motor"));
    assert_eq!(id, Identification::default());

    // And a board encodes it at the same offsets, leaving the header positions alone.
    let mut out = vec![0xEEu8; mosi.len()];
    let written = reply.encode_miso(&mut out);
    assert_eq!(written, 10);
    assert_eq!(&out[..2], &[0xEE, 0xEE]);
    assert_eq!(&out[REPLY_OFFSET..REPLY_OFFSET + 3], &[0x73, 0x70, 0x69]);
    assert!(out[12..].iter().all(|&b| b == PAD));
}

/// "Introduction": "The lower bit specifies if the transaction is to be a read or a write.
/// Write transactions have the lower bit cleared (0), read transactions have the lower bit
/// set (1)."
#[test]
fn introduction_address_read_write_bit() {
    assert_eq!(Address::DEFAULT.get(), 0x90);
    assert_eq!(Address::DEFAULT.seven_bit(), 0x48);
    assert_eq!(Address::DEFAULT.byte(Access::Write), 0x90);
    assert_eq!(Address::DEFAULT.byte(Access::Read), 0x91);
    assert_eq!(Access::of_byte(0x91), Access::Read);
    assert_eq!(Address::of_byte(0x91), Address::DEFAULT);
    assert_eq!(Address::new(0x91), Err(Error::OddAddress(0x91)));
    assert_eq!(
        Header::decode(&[0x93, 0x40]),
        Ok(Header {
            address: Address::new(0x92).unwrap(),
            access: Access::Read,
            port: 0x40
        })
    );
}

/// "write ports": every row of the table, on a board at 0x90.
#[test]
fn write_ports_table() {
    let a = Address::DEFAULT;
    let cases: [(Write, &[u8]); 16] = [
        // "0x10 Set drive intensity for stepper mode (default is 0x20)"
        (Write::StepperIntensity(0x20), &[0x90, 0x10, 0x20]),
        // "0x20 Spin motor A in direction A with intensity <byte>"
        (
            Write::Spin {
                motor: Motor::A,
                direction: Direction::A,
                intensity: 0x80,
            },
            &[0x90, 0x20, 0x80],
        ),
        // "0x21 Spin motor A in direction B with intensity <byte>"
        (
            Write::Spin {
                motor: Motor::A,
                direction: Direction::B,
                intensity: 0xff,
            },
            &[0x90, 0x21, 0xff],
        ),
        // "0x22 Stop motor A"
        (Write::Stop(Motor::A), &[0x90, 0x22]),
        // "0x30 Spin motor B in direction A with intensity <byte>"
        (
            Write::Spin {
                motor: Motor::B,
                direction: Direction::A,
                intensity: 1,
            },
            &[0x90, 0x30, 0x01],
        ),
        // "0x31 Spin motor B in direction B with intensity <byte>"
        (
            Write::Spin {
                motor: Motor::B,
                direction: Direction::B,
                intensity: 0,
            },
            &[0x90, 0x31, 0x00],
        ),
        // "0x32 Stop motor B"
        (Write::Stop(Motor::B), &[0x90, 0x32]),
        // "0x40 set current position. <4 bytes>"
        (
            Write::CurrentPosition(-2),
            &[0x90, 0x40, 0xfe, 0xff, 0xff, 0xff],
        ),
        // "0x41 set target position. <4 bytes>"
        (
            Write::TargetPosition(1000),
            &[0x90, 0x41, 0xe8, 0x03, 0x00, 0x00],
        ),
        // "0x42 set relative position. <4 bytes>"
        (
            Write::RelativePosition(-100),
            &[0x90, 0x42, 0x9c, 0xff, 0xff, 0xff],
        ),
        // "0x43 set stepdelay. (in tenths of a millisecond, default 200: 20ms between steps)"
        (Write::StepDelay(StepDelay::DEFAULT), &[0x90, 0x43, 200]),
        // "0x44 Set number of driven coils. Writing 0x00 means driving one coil"
        (Write::Coils(Coils::One), &[0x90, 0x44, 0x00]),
        // "… other values mean driving two coils"
        (Write::Coils(Coils::Two), &[0x90, 0x44, 0x01]),
        // "0xf1 write 0x55 here to start unlocking the change address register."
        (Write::UnlockAddress1, &[0x90, 0xf1, 0x55]),
        // "write 0xaa here to unlock the change address register." (0xf2, see docs/ARCHITECTURE.md)
        (Write::UnlockAddress2, &[0x90, 0xf2, 0xaa]),
        // "0xf0 change address. Requires a write to 0xf1 and 0xf2 first."
        (
            Write::ChangeAddress(Address::new(0x92).unwrap()),
            &[0x90, 0xf0, 0x92],
        ),
    ];
    for (write, wire) in cases {
        let t = Transaction::write(a, write);
        assert_eq!(encode(t), wire, "{write:?}");
        assert_eq!(Transaction::decode(wire), Ok(t), "{write:?}");
    }
}

/// "read ports": every row, as the host clocks it and as the board answers.
#[test]
fn read_ports_table() {
    let a = Address::DEFAULT;
    let cases: [(Reply, &[u8], &[u8]); 5] = [
        // "0x01 identification string. (terminated with 0)."
        (
            Reply::Identification(Identification::new(b"spi_motor").unwrap()),
            &[0x91, 0x01, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
            b"xxspi_motor\0",
        ),
        // "0x02 read eeprom (serial number)." (4 bytes LE, our reading)
        (
            Reply::Serial(SerialNumber(0x0102_0304)),
            &[0x91, 0x02, 0, 0, 0, 0],
            &[b'x', b'x', 4, 3, 2, 1],
        ),
        // "0x40 read current position. <4 bytes>"
        (
            Reply::CurrentPosition(0x1234_5678),
            &[0x91, 0x40, 0, 0, 0, 0],
            &[b'x', b'x', 0x78, 0x56, 0x34, 0x12],
        ),
        // "0x41 read target position. <4 bytes>"
        (
            Reply::TargetPosition(-1),
            &[0x91, 0x41, 0, 0, 0, 0],
            &[b'x', b'x', 0xff, 0xff, 0xff, 0xff],
        ),
        // "0x43 read stepdelay. (… default 200: 20ms between steps)."
        (
            Reply::StepDelay(StepDelay::DEFAULT),
            &[0x91, 0x43, 0],
            &[b'x', b'x', 200],
        ),
    ];
    for (reply, mosi, miso) in cases {
        let port = reply.port();
        let t = Transaction {
            address: a,
            request: Request::Read(Read {
                port,
                len: u16::try_from(mosi.len() - 2).unwrap(),
            }),
        };
        assert_eq!(encode(t), mosi, "{reply:?}");
        assert_eq!(Transaction::decode(mosi), Ok(t), "{reply:?}");
        assert_eq!(Reply::decode(port, miso), Ok(reply), "{reply:?}");
        let mut out = vec![b'x'; miso.len()];
        reply.encode_miso(&mut out);
        assert_eq!(out, miso, "{reply:?}");
    }
    // Fixed-size reads clock exactly their value by default.
    assert_eq!(Transaction::read(a, ReadPort::CurrentPosition).len(), 6);
    assert_eq!(Transaction::read(a, ReadPort::TargetPosition).len(), 6);
    assert_eq!(Transaction::read(a, ReadPort::Serial).len(), 6);
    assert_eq!(Transaction::read(a, ReadPort::StepDelay).len(), 3);
}

/// "0x43 set stepdelay. (in tenths of a millisecond, default 200: 20ms between steps)";
/// the read table's "tenths of a microsecond" is a slip (docs/ARCHITECTURE.md).
#[test]
fn step_delay_is_tenths_of_a_millisecond_both_ways() {
    assert_eq!(StepDelay::DEFAULT.tenths_ms(), 200);
    assert_eq!(
        StepDelay::DEFAULT.duration(),
        std::time::Duration::from_millis(20)
    );
    assert_eq!(
        StepDelay::at_least(std::time::Duration::from_micros(1001)),
        Ok(StepDelay::from_tenths_ms(11))
    );
    assert_eq!(
        StepDelay::at_least(std::time::Duration::from_millis(26)),
        Err(Error::StepDelayRange)
    );
}

/// "Writing 0x00 means driving one coil, other values mean driving two coils".
#[test]
fn coils_any_nonzero_byte_is_two() {
    for b in 0..=255u8 {
        let t = Transaction::decode(&[0x90, 0x44, b]).unwrap();
        let expected = if b == 0 { Coils::One } else { Coils::Two };
        assert_eq!(t.request, Request::Write(Write::Coils(expected)));
    }
}

/// "Some ports just set a single value. So writing more than one byte to such a port is
/// redundant." Each byte sets the value again: the last one counts. A stop takes no data
/// and ignores any.
#[test]
fn redundant_bytes_on_single_value_ports() {
    let t = Transaction::decode(&[0x90, 0x10, 0x11, 0x22, 0x33]).unwrap();
    assert_eq!(t.request, Request::Write(Write::StepperIntensity(0x33)));
    let t = Transaction::decode(&[0x90, 0x22, 0x11, 0x22]).unwrap();
    assert_eq!(t.request, Request::Write(Write::Stop(Motor::A)));
}

#[test]
fn malformed_transactions_are_rejected() {
    let cases: [(&[u8], Error); 11] = [
        (&[], Error::MissingHeader),
        (&[0x90], Error::MissingHeader),
        (&[0x90, 0x41, 1, 2, 3], Error::Length { port: 0x41, got: 3 }),
        (
            &[0x90, 0x41, 1, 2, 3, 4, 5],
            Error::Length { port: 0x41, got: 5 },
        ),
        (&[0x90, 0x10], Error::Length { port: 0x10, got: 0 }),
        (&[0x91, 0x40], Error::Length { port: 0x40, got: 0 }),
        (
            &[0x91, 0x10, 0],
            Error::UnknownPort {
                port: 0x10,
                read: true,
            },
        ),
        (
            &[0x90, 0x01, 0],
            Error::UnknownPort {
                port: 0x01,
                read: false,
            },
        ),
        (
            &[0x90, 0xf1, 0x54],
            Error::WrongUnlockKey {
                port: 0xf1,
                value: 0x54,
            },
        ),
        (
            &[0x90, 0xf2, 0x55],
            Error::WrongUnlockKey {
                port: 0xf2,
                value: 0x55,
            },
        ),
        (&[0x90, 0xf0, 0x93], Error::OddAddress(0x93)),
    ];
    for (mosi, err) in cases {
        assert_eq!(Transaction::decode(mosi), Err(err), "{mosi:02x?}");
    }
}

#[test]
fn malformed_replies_are_rejected() {
    // An undriven MISO line reads 0xff: no terminator.
    assert_eq!(
        Reply::decode(ReadPort::Identification, &[0xff; 40]),
        Err(Error::Unterminated)
    );
    assert_eq!(
        Reply::decode(ReadPort::CurrentPosition, &[0, 0, 1, 2, 3]),
        Err(Error::Length { port: 0x40, got: 3 })
    );
    assert_eq!(
        Reply::decode(ReadPort::StepDelay, &[0, 0]),
        Err(Error::Length { port: 0x43, got: 0 })
    );
    assert_eq!(
        Reply::decode(ReadPort::Serial, &[0]),
        Err(Error::MissingHeader)
    );
    let mut long = [b'a'; 40];
    long[39] = 0;
    assert_eq!(
        Reply::decode(ReadPort::Identification, &long),
        Err(Error::InvalidIdentification)
    );
}

#[test]
fn encode_reports_the_size_it_needs() {
    let t = Transaction::write(Address::DEFAULT, Write::TargetPosition(5));
    assert_eq!(
        t.encode(&mut [0u8; 5]),
        Err(Error::BufferTooSmall { needed: 6 })
    );
    let r = Reply::CurrentPosition(5);
    assert_eq!(
        r.encode(&mut [0u8; 3]),
        Err(Error::BufferTooSmall { needed: 4 })
    );
    let zero = Transaction {
        address: Address::DEFAULT,
        request: Request::Read(Read {
            port: ReadPort::StepDelay,
            len: 0,
        }),
    };
    assert_eq!(
        zero.encode(&mut [0u8; 8]),
        Err(Error::Length { port: 0x43, got: 0 })
    );
}

#[test]
fn a_short_read_gets_the_first_bytes_of_the_answer() {
    let mut miso = [0xEEu8; 4];
    assert_eq!(
        Reply::CurrentPosition(0x1234_5678).encode_miso(&mut miso),
        2
    );
    assert_eq!(miso, [0xEE, 0xEE, 0x78, 0x56]);
}
