//! End to end through a real Unix socket: `motion-sim --spi-socket` serving two SPI_motor
//! boards on one bus, reached with motion-link's `spi-socket` transport.

mod pty_support;

use std::time::Duration;

use motion_link::Link;
use motion_link::spi_socket::{SpiSocketConfig, SpiSocketLink};
use spimotor::{Address, ReadPort, Reply, Transaction};

use pty_support::{Served, transact};

#[test]
fn two_spimotor_boards_share_the_socket_bus() {
    let socket = pty_support::temp_path("motors.sock");
    let served = Served::start(&[
        "--model",
        "spimotor",
        "--model",
        "spimotor",
        "--address",
        "0x92",
        "--drive",
        "brushed",
        "--spi-socket",
        socket.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(served.first_line, socket.to_str().unwrap());
    let mut link =
        SpiSocketLink::connect(SpiSocketConfig::new(&served.first_line)).expect("connect");

    // Spimotor datasheet, "read identification": 0x91, 0x01, then dummy bytes.
    for address in [0x90, 0x92] {
        let read = Transaction::read(Address::new(address).unwrap(), ReadPort::Identification);
        let mut mosi = [0u8; 40];
        let n = read.encode(&mut mosi).expect("encode");
        let miso = transact(&mut link, &mosi[..n]);
        assert_eq!(miso.len(), n);
        let Reply::Identification(id) =
            Reply::decode(ReadPort::Identification, &miso).expect("decode")
        else {
            panic!("not an identification: {miso:02x?}");
        };
        assert_eq!(id.as_str(), Some("spi_motor"), "board 0x{address:02x}");
    }
    // Nobody at 0x94: the floating MISO line reads 0xFF.
    let read = Transaction::read(Address::new(0x94).unwrap(), ReadPort::Identification);
    let mut mosi = [0u8; 40];
    let n = read.encode(&mut mosi).expect("encode");
    assert_eq!(transact(&mut link, &mosi[..n]), vec![0xFF; n]);
    assert_eq!(link.stats().transactions, 3);
    served.stop_and_check(Duration::from_secs(5));
    assert!(!socket.exists(), "the socket file is removed on exit");
}
