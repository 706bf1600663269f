//! End to end through a real Unix socket: `motion-sim --model qq2drv --spi-socket`,
//! reached with motion-link's `spi-socket` transport, answers the datasheet's worked example
//! "Read Version Numbers" (request 2,4,1,249).

mod pty_support;

use std::time::{Duration, Instant};

use motion_link::spi_socket::{SpiSocketConfig, SpiSocketLink};
use pty_support::{Served, transact};

#[test]
fn qq2drv_on_a_socket_answers_the_version_request_after_filler() {
    let socket = pty_support::temp_path("qq2drv.sock");
    let served = Served::start(&[
        "--model",
        "qq2drv",
        "--spi-socket",
        socket.to_str().expect("utf-8 path"),
    ]);
    let mut link =
        SpiSocketLink::connect(SpiSocketConfig::new(&served.first_line)).expect("connect");
    let mut request = [0u8; 8];
    let n = qq2drv::Request::GetVersion
        .encode(&mut request)
        .expect("encode");
    assert_eq!(&request[..n], &[2, 4, 1, 249], "datasheet worked example");
    // MISO is clocked while the request comes in: no reply can be in this transaction.
    let first = transact(&mut link, &request[..n]);
    let mut decoder = qq2drv::StreamDecoder::new();
    decoder.push(&first);
    assert!(decoder.next_packet().is_none(), "{first:02x?}");
    // Poll with filler (docs/ARCHITECTURE.md: without SRDY the master clocks out 0x00 and looks for STX).
    let start = Instant::now();
    let packet = loop {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "no reply; stderr:\n{}",
            served.stderr()
        );
        let miso = transact(&mut link, &[0u8; 16]);
        decoder.push(&miso);
        if let Some(packet) = decoder.next_packet() {
            break packet;
        }
    };
    let reply = qq2drv::Reply::decode(packet.frame(), &qq2drv::ReplyLayout::default())
        .expect("a valid reply");
    assert!(matches!(reply, qq2drv::Reply::Version { .. }), "{reply:?}");
    served.stop_and_check(Duration::from_secs(5));
}
