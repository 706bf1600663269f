//! The simulated QuadQuad2Drv counts a request that begins while a packet begun in an
//! earlier transaction is still being clocked out: "3. Master reads out one entire
//! packet." ("QuadQuad2Drv PCB Datasheet", interface protocol v1, SPI Interface).

use core::time::Duration;

use board_qq2drv::sim::{Qq2drvSim, Qq2drvSimConfig};
use motion_link::sim::SpiDevice;

/// The worked example "Read Version Numbers": send 2, 4, 1, 249.
const GET_VERSION: [u8; 4] = [2, 4, 1, 249];
/// Its reply: 2, 8, 1, 0, 0, 1, 0, 244.
const VERSION: [u8; 8] = [2, 8, 1, 0, 0, 1, 0, 244];

/// One transaction completing at `*now + 1 ms`; its MISO.
fn xfer(sim: &mut Qq2drvSim, now: &mut Duration, mosi: &[u8]) -> Vec<u8> {
    *now += Duration::from_millis(1);
    let mut miso = vec![0xEE; mosi.len()];
    assert!(sim.transfer(*now, mosi, &mut miso));
    miso
}

#[test]
fn a_request_while_a_reply_is_half_read_is_counted() {
    let mut sim = Qq2drvSim::new(Qq2drvSimConfig::default());
    let mut now = Duration::ZERO;
    xfer(&mut sim, &mut now, &GET_VERSION);
    // Two bytes of the reply, then a request: the reply was not read out entirely.
    assert_eq!(xfer(&mut sim, &mut now, &[0, 0]), VERSION[..2]);
    let miso = xfer(&mut sim, &mut now, &GET_VERSION);
    assert_eq!(miso, VERSION[2..6], "the reply goes on meanwhile");
    assert_eq!(sim.stats().interlaced, 1);
}

#[test]
fn its_rest_clocked_first_in_the_same_transaction_is_not() {
    let mut sim = Qq2drvSim::new(Qq2drvSimConfig::default());
    let mut now = Duration::ZERO;
    xfer(&mut sim, &mut now, &GET_VERSION);
    assert_eq!(xfer(&mut sim, &mut now, &[0, 0]), VERSION[..2]);
    // Six filler bytes read the rest, then the request.
    let mut mosi = vec![0u8; 6];
    mosi.extend(GET_VERSION);
    let miso = xfer(&mut sim, &mut now, &mosi);
    assert_eq!(miso[..6], VERSION[2..]);
    assert_eq!(sim.stats().interlaced, 0);
    // A request whose own transaction starts to clock out the next reply is full duplex,
    // not an interruption: the packet began in that transaction.
    let mut mosi = GET_VERSION.to_vec();
    mosi.extend([0u8; 8]);
    let miso = xfer(&mut sim, &mut now, &mosi);
    assert_eq!(miso[..8], VERSION, "the reply to the second request");
    assert_eq!(sim.stats().interlaced, 0);
}
