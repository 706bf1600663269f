//! Property round trips for every request and reply type.

use proptest::prelude::*;
use qsb::*;

fn any_register() -> impl Strategy<Value = Register> {
    proptest::sample::select(Register::ALL.to_vec())
}

fn any_data() -> impl Strategy<Value = u32> {
    prop_oneof![
        0u32..0x20,
        0u32..0x2000,
        (0u32..8).prop_map(|x| (x << 8) | 0x0A),
        0x20u32..0x57E41,
        any::<u32>(),
        (-13000i32..=13000).prop_map(|v| v as u32),
    ]
}

fn any_write() -> impl Strategy<Value = Write> {
    (any_register(), any_data())
        .prop_filter_map("not a valid write", |(r, d)| Write::from_data(r, d).ok())
}

fn any_request() -> impl Strategy<Value = Request> {
    prop_oneof![
        any_register()
            .prop_filter("readable", |r| r.allows(CommandType::Read))
            .prop_map(Request::Read),
        any_register()
            .prop_filter("streamable", |r| r.allows(CommandType::Stream))
            .prop_map(Request::Stream),
        any_write().prop_map(Request::Write),
    ]
}

fn any_command_type() -> impl Strategy<Value = CommandType> {
    proptest::sample::select(vec![
        CommandType::Read,
        CommandType::Write,
        CommandType::Stream,
    ])
}

fn any_response_type() -> impl Strategy<Value = ResponseType> {
    proptest::sample::select(vec![
        ResponseType::Read,
        ResponseType::Write,
        ResponseType::Stream,
        ResponseType::Error,
        ResponseType::Unsupported,
    ])
}

fn any_response() -> impl Strategy<Value = Response> {
    (
        any_response_type(),
        any::<u8>(),
        any::<u32>(),
        proptest::option::of(any::<u32>()),
    )
        .prop_map(|(ty, register, data, time_stamp)| Response {
            ty,
            register,
            data,
            time_stamp,
        })
}

fn any_eor() -> impl Strategy<Value = Eor> {
    (0u32..16).prop_map(|d| Eor::from_data(d).unwrap_or_default())
}

proptest! {
    /// INTERVAL RATE: the period of a rate is nearest to that rate, and any period within
    /// half a tick of it rounds back to it.
    #[test]
    fn interval_rate_nearest_inverts_period(ticks in 0u16..=0xFFFE, jitter in -0.49f64..0.49) {
        let rate = IntervalRate(ticks);
        let period = rate.period().unwrap();
        prop_assert_eq!(IntervalRate::nearest(period), Some(rate));
        let nanos = period.as_nanos() as f64 + jitter * TICK.as_nanos() as f64;
        let near = core::time::Duration::from_nanos(nanos.max(0.0) as u64);
        prop_assert_eq!(IntervalRate::nearest(near), Some(rate));
    }

    #[test]
    fn request_roundtrip(request in any_request()) {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let n = request.encode(&mut buf).unwrap();
        let mut decoder = CommandDecoder::new();
        let (used, line) = decoder.decode(&buf[..n]);
        let line = line.expect("a line").unwrap();
        prop_assert_eq!(Request::from_line(&line), Ok(request));
        // The LF of the CR LF pair is an empty line: consumed without a result.
        prop_assert_eq!(decoder.decode(&buf[used..n]), (n - used, None));
        prop_assert_eq!(decoder.bad_lines(), 0);
    }

    #[test]
    fn command_line_roundtrip(
        ty in any_command_type(),
        register in any::<u8>(),
        data in proptest::option::of(any::<u32>()),
    ) {
        let line = CommandLine { ty, register, data };
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let n = line.encode(&mut buf).unwrap();
        prop_assert_eq!(CommandLine::decode(&buf[..n - EOC.len()]), Ok(line));
        for short in 0..n {
            prop_assert_eq!(line.encode(&mut buf[..short]), Err(Error::BufferTooSmall));
        }
    }

    #[test]
    fn response_roundtrip(response in any_response(), eor in any_eor()) {
        let mut buf = [0u8; MAX_RESPONSE_LEN];
        let n = response.encode(eor, &mut buf).unwrap();
        prop_assert_eq!(Response::decode(&buf[..n]), Ok(response));
        let mut decoder = ResponseDecoder::new();
        let (used, decoded) = decoder.decode(&buf[..n]);
        prop_assert_eq!(decoded, Some(response));
        prop_assert!(used <= n);
        prop_assert_eq!(decoder.decode(&buf[used..n]), (n - used, None));
        prop_assert_eq!(decoder.bad_frames(), 0);
        for short in 0..n {
            prop_assert_eq!(response.encode(eor, &mut buf[..short]), Err(Error::BufferTooSmall));
        }
    }

    #[test]
    fn value_roundtrip(register in any_register(), data in any_data()) {
        if let Ok(value) = Value::decode(register, data) {
            prop_assert_eq!(value.register(), register);
            prop_assert_eq!(Value::decode(register, value.data()), Ok(value));
            let response = Response::new(ResponseType::Read, register.number(), value.data());
            prop_assert_eq!(response.value(), Ok(value));
        }
    }

    #[test]
    fn write_roundtrip(write in any_write()) {
        prop_assert_eq!(Write::from_data(write.register(), write.data()), Ok(write));
        // A write echo decodes to the same typed value.
        let echo = Response::new(ResponseType::Write, write.register().number(), write.data());
        prop_assert_eq!(echo.value().map(|v| v.data()), Ok(write.data()));
    }

    #[test]
    fn typed_values_roundtrip(data in any::<u32>()) {
        let small = data & 0x1FFF;
        if let Ok(v) = Mode::from_data(small) { prop_assert_eq!(Mode::from_data(v.data()), Ok(v)); }
        if let Ok(v) = DigIo::from_data(small) { prop_assert_eq!(DigIo::from_data(v.data()), Ok(v)); }
        if let Ok(v) = DigIoConfig::from_data(small) {
            prop_assert_eq!(v.data(), small);
        }
        if let Ok(v) = Mdr0::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = Mdr1::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = Str::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = Eor::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = MdStatus::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = QsbCommand::from_data(small) { prop_assert_eq!(v.data(), small); }
        if let Ok(v) = Version::from_data(data) { prop_assert_eq!(v.data(), data); }
        if let Ok(v) = AnalogSample::from_data(data) { prop_assert_eq!(v.data(), data); }
        if let Ok(v) = IntervalRate::from_data(data) { prop_assert_eq!(v.data(), data); }
    }
}
