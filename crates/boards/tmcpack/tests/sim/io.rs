//! Manual 8.5 "Additional Inputs / Outputs": what a test can drive into the pack and read
//! back from it.

use super::host::*;

fn input(h: &mut Host<TmcpackSim>, channel: u8) -> Reply {
    let (_, frame) = h
        .query(
            1,
            Request::ReadInput {
                channel,
                reply_to: HOST,
            },
        )
        .expect("a $30 answer");
    frame.reply
}

/// $30: "The reference inputs are inverted"; P5 "logic state at TTLIO1"; channel 6 "is the
/// external input".
#[test]
fn manual_8_5_inputs_follow_what_the_test_drives() {
    let mut h = Host::new(TmcpackSim::new(TmcpackSimConfig {
        analog_noise_lsb: 0,
        ..TmcpackSimConfig::default()
    }));
    // Motor 0's switch as an opener, not actuated: closed, Ref_In low → the bit reads 1.
    h.dev.set_ref_switch(
        0,
        Some(RefSwitch {
            from: 1000,
            to: 2000,
            opener: true,
        }),
    );
    h.dev.set_analog(6, 700);
    h.dev.set_ttlio1_input(true);
    let Reply::Input {
        value,
        inputs,
        ttlio1,
        ..
    } = input(&mut h, 6)
    else {
        panic!("not a $30 answer");
    };
    assert_eq!(value, 700);
    assert!(
        inputs.contains(tmcpack::RefInputs::REF0),
        "low level reads 1"
    );
    assert!(
        !inputs.contains(tmcpack::RefInputs::REF1),
        "nothing connected floats high"
    );
    assert!(ttlio1);
    // The switch opens (actuated): high level → the bit reads 0.
    h.dev.set_ref_switch(
        0,
        Some(RefSwitch {
            from: -10,
            to: 10,
            opener: true,
        }),
    );
    let Reply::Input { inputs, .. } = input(&mut h, 0) else {
        panic!("not a $30 answer");
    };
    assert!(!inputs.contains(tmcpack::RefInputs::REF0));
}

/// $32: "P1 bit 0: output enable for TTLIO1 (1=input, 0=output)", "P2 … level at TTLIO1";
/// $31 limits per channel.
#[test]
fn manual_8_5_outputs_and_stop_limits_can_be_read_back() {
    let mut h = pack();
    assert_eq!(h.dev.ttlio1_output(), None, "an input until told otherwise");
    h.send(
        1,
        Request::Outputs {
            ttlout1: true,
            ttlio1_input: false,
            ttlio1: true,
            ttlout1_ready: false,
        },
    );
    h.wait(2 * MS);
    assert_eq!(h.dev.ttlio1_output(), Some(true));
    assert!(h.dev.ttlout1());
    assert_eq!(h.dev.ready_output(), None);
    h.send(
        1,
        Request::StopLimits {
            channel: 2,
            left_min: 100,
            right_max: 900,
        },
    );
    h.wait(2 * MS);
    assert_eq!(h.dev.stop_limits(2), Some((100, 900)));
    assert_eq!(
        h.dev.stop_limits(0),
        Some((0, 1023)),
        "no function by default"
    );
}
