//! Property round trips for every request and reply type.

use proptest::prelude::*;
use spimotor::{
    Address, Coils, Direction, IDENTIFICATION_CAPACITY, Identification, Motor, REPLY_OFFSET, Read,
    ReadPort, Reply, Request, SerialNumber, StepDelay, Transaction, Write,
};

fn address() -> impl Strategy<Value = Address> {
    any::<u8>().prop_map(Address::of_byte)
}

fn motor() -> impl Strategy<Value = Motor> {
    prop_oneof![Just(Motor::A), Just(Motor::B)]
}

fn direction() -> impl Strategy<Value = Direction> {
    prop_oneof![Just(Direction::A), Just(Direction::B)]
}

fn write() -> impl Strategy<Value = Write> {
    prop_oneof![
        any::<u8>().prop_map(Write::StepperIntensity),
        (motor(), direction(), any::<u8>()).prop_map(|(motor, direction, intensity)| {
            Write::Spin {
                motor,
                direction,
                intensity,
            }
        }),
        motor().prop_map(Write::Stop),
        any::<i32>().prop_map(Write::CurrentPosition),
        any::<i32>().prop_map(Write::TargetPosition),
        any::<i32>().prop_map(Write::RelativePosition),
        any::<u8>().prop_map(|b| Write::StepDelay(StepDelay::from_tenths_ms(b))),
        prop_oneof![Just(Coils::One), Just(Coils::Two)].prop_map(Write::Coils),
        Just(Write::UnlockAddress1),
        Just(Write::UnlockAddress2),
        address().prop_map(Write::ChangeAddress),
    ]
}

fn read_port() -> impl Strategy<Value = ReadPort> {
    proptest::sample::select(ReadPort::ALL.to_vec())
}

fn read() -> impl Strategy<Value = Read> {
    (read_port(), 1..=80u16).prop_map(|(port, len)| Read { port, len })
}

fn transaction() -> impl Strategy<Value = Transaction> {
    (
        address(),
        prop_oneof![
            write().prop_map(Request::Write),
            read().prop_map(Request::Read)
        ],
    )
        .prop_map(|(address, request)| Transaction { address, request })
}

fn identification() -> impl Strategy<Value = Identification> {
    proptest::collection::vec(1..=255u8, 0..=IDENTIFICATION_CAPACITY)
        .prop_map(|text| Identification::new(&text).expect("no zero, within capacity"))
}

fn reply() -> impl Strategy<Value = Reply> {
    prop_oneof![
        identification().prop_map(Reply::Identification),
        any::<u32>().prop_map(|v| Reply::Serial(SerialNumber(v))),
        any::<i32>().prop_map(Reply::CurrentPosition),
        any::<i32>().prop_map(Reply::TargetPosition),
        any::<u8>().prop_map(|b| Reply::StepDelay(StepDelay::from_tenths_ms(b))),
    ]
}

proptest! {
    #[test]
    fn transaction_round_trips(t in transaction()) {
        let mut buf = [0u8; 128];
        let n = t.encode(&mut buf).expect("fits");
        prop_assert_eq!(n, t.len());
        prop_assert_eq!(Transaction::decode(&buf[..n]), Ok(t));
        // The header is readable on its own, before the rest is decoded.
        prop_assert_eq!(spimotor::Header::decode(&buf[..n]), Ok(t.header()));
    }

    #[test]
    fn write_round_trips_through_port_and_data(w in write()) {
        let mut buf = [0u8; 8];
        let n = Transaction::write(Address::DEFAULT, w).encode(&mut buf).expect("fits");
        prop_assert_eq!(n, 2 + w.data_len());
        prop_assert_eq!(Write::decode(buf[1], &buf[2..n]), Ok(w));
    }

    #[test]
    fn reply_round_trips(r in reply()) {
        let mut data = [0u8; 64];
        let n = r.encode(&mut data).expect("fits");
        prop_assert_eq!(n, r.len());
        prop_assert_eq!(Reply::decode_data(r.port(), &data[..n]), Ok(r));
    }

    #[test]
    fn reply_round_trips_through_a_miso_buffer(r in reply(), extra in 0usize..8, junk in any::<[u8; 2]>()) {
        // The host clocks at least the whole answer; the header positions hold anything.
        let mut miso = vec![0u8; REPLY_OFFSET + r.len() + extra];
        miso[..2].copy_from_slice(&junk);
        prop_assert_eq!(r.encode_miso(&mut miso), r.len());
        prop_assert_eq!(&miso[..2], &junk[..]);
        prop_assert_eq!(Reply::decode(r.port(), &miso), Ok(r));
    }

    #[test]
    fn decoded_transactions_re_encode_to_something_equivalent(mosi in proptest::collection::vec(any::<u8>(), 0..12)) {
        if let Ok(t) = Transaction::decode(&mosi) {
            let mut buf = [0u8; 64];
            let n = t.encode(&mut buf).expect("fits");
            prop_assert_eq!(Transaction::decode(&buf[..n]), Ok(t));
            prop_assert_eq!(buf[0], mosi[0]);
            prop_assert_eq!(buf[1], mosi[1]);
        }
    }

    #[test]
    fn step_delay_round_trips_through_duration(b in any::<u8>()) {
        let d = StepDelay::from_tenths_ms(b);
        prop_assert_eq!(StepDelay::at_least(d.duration()), Ok(d));
    }

    #[test]
    fn step_delay_at_least_never_shorter(us in 0u64..=25_500) {
        let want = std::time::Duration::from_micros(us);
        let d = StepDelay::at_least(want).expect("in range");
        prop_assert!(d.duration() >= want);
        prop_assert!(d.duration() < want + StepDelay::UNIT);
    }

    #[test]
    fn identification_round_trips(id in identification()) {
        prop_assert_eq!(Identification::new(id.as_bytes()), Ok(id));
        prop_assert_eq!(id.wire_len(), id.as_bytes().len() + 1);
    }

    #[test]
    fn coils_round_trip(c in prop_oneof![Just(Coils::One), Just(Coils::Two)]) {
        prop_assert_eq!(Coils::from_byte(c.to_byte()), c);
    }

    #[test]
    fn motor_channel_round_trips(m in motor()) {
        prop_assert_eq!(Motor::from_channel(m.channel()), Some(m));
    }
}
