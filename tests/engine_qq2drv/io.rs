//! The IN pins and Status bits of the QuadQuad2Drv as signals, read from the stream.

use super::*;

#[test]
fn a_switch_on_an_in_pin_is_read_within_the_refresh_budget() {
    use board_qq2drv::driver::{PINS, pin_of};
    use motion_drivers::find_pin;
    // Signals on QUAD2's IN pin (the axis y's home switch) and on QUAD4, which has no axis.
    let mut config = driver_config();
    let in2 = find_pin(PINS, "in2").unwrap();
    let in4 = find_pin(PINS, "in4").unwrap();
    let in4_seen = find_pin(PINS, "in4_seen").unwrap();
    assert_eq!(in4, pin_of(3, 0).unwrap());
    config.channels[1].pins = 1 << 0;
    config.channels[3].pins = (1 << 0) | (1 << 1);
    let (mut rig, board, _) = rig_with(Qq2drvDriver::new(config), sim());
    wait_online(&mut rig);
    rig.run(10);
    let driver = rig.engine.driver(0).unwrap();
    let budget = driver.refresh_budget();
    // QUAD4 is streamed with its Status byte alone.
    assert_eq!(board.lock().unwrap().data_masks()[3], STATUS_MASK);
    // Nothing pulls QUAD4's pin: it idles high, and the board's power-up polarity (0x00,
    // "Input is active when low") makes that inactive.
    let reading = driver.read_pin(in4).expect("configured");
    assert_eq!(reading.value, 0.0);
    assert!(reading.refreshed_at.is_some());
    assert_eq!(
        driver.read_pin(find_pin(PINS, "in3").unwrap()),
        None,
        "no signal there"
    );
    // y's switch (active low, polarity written by the driver) is open.
    assert_eq!(driver.read_pin(in2).unwrap().value, 0.0);
    // Close QUAD4's switch to ground, and press y's.
    board.lock().unwrap().force_input_level(3, Some(false));
    board.lock().unwrap().force_input_level(1, Some(false));
    let closed_at = rig.now;
    let mut seen = None;
    while rig.now - closed_at <= budget {
        rig.tick();
        let driver = rig.engine.driver(0).unwrap();
        if driver.read_pin(in4).unwrap().value == 1.0 && driver.read_pin(in2).unwrap().value == 1.0
        {
            seen = Some(rig.now - closed_at);
            break;
        }
    }
    let seen = seen.expect("seen within the refresh budget");
    assert!(seen <= budget);
    let driver = rig.engine.driver(0).unwrap();
    assert_eq!(driver.read_pin(in4_seen).unwrap().value, 1.0);
    // Released: the level follows; the accumulator saw it active in the last packet.
    board.lock().unwrap().force_input_level(3, Some(true));
    rig.run(5);
    let driver = rig.engine.driver(0).unwrap();
    assert_eq!(driver.read_pin(in4).unwrap().value, 0.0);
    assert_eq!(driver.read_pin(in4_seen).unwrap().value, 0.0);
    // No outputs on this board.
    assert!(
        PINS.iter()
            .all(|p| !p.kinds.contains(motion_drivers::SignalKind::DigitalOut))
    );
}
