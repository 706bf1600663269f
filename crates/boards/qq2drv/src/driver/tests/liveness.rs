//! Liveness and resets on proof (issue 39 item 4): a stalled stream is checked with Get
//! Stream Period, nothing voided, and a board whose period went back to power-up's is found
//! reset by its probe; a board silent for `silence_ms` is not answering, with the evidence.

use super::*;

#[test]
fn a_stalled_stream_is_checked_and_a_reset_board_found() {
    let (mut driver, mut now) = running();
    let stall = driver.stall_timeout();
    let end = now + stall + 2 * MS;
    let mut check = None;
    while now < end {
        now += MS;
        for transaction in drain(&mut driver, now) {
            assert!(
                !transaction.starts_with(&[2, 4, 1, 249]),
                "no probe: nothing is voided on a stall"
            );
            if transaction.first() == Some(&2) {
                check = Some(transaction);
            }
        }
    }
    // Get Stream Period (5): its answer says whether the board still has the period
    // start-up wrote.
    let check = check.expect("the stream is checked");
    assert_eq!(packets(&check).len(), 1);
    assert_eq!(check[2], 5);
    assert_eq!(driver.status().fault, None, "not declared anything");
    // The period start-up wrote: the stream was only held up; checked again later.
    let code = ReturnCode::SUCCESS;
    let period = driver.config().stream_period_units();
    let mut answer = vec![0u8; 3];
    answer.extend(encode_reply(&Reply::StreamPeriod { code, period }));
    driver.handle_rx(now, &answer);
    assert_eq!(driver.status().resets, 0);
    assert!(
        drain(&mut driver, now)
            .iter()
            .all(|t| t.first() != Some(&2))
    );
    let again = now + stall + MS;
    let mut second = None;
    while now < again {
        now += MS;
        for transaction in drain(&mut driver, now) {
            if transaction.first() == Some(&2) {
                second = Some(transaction);
            }
        }
    }
    assert_eq!(second.expect("checked again")[2], 5);
    // Power-up's period 0: back to the probe, whose reading is the reset's evidence.
    let mut answer = vec![0u8; 3];
    answer.extend(encode_reply(&Reply::StreamPeriod { code, period: 0 }));
    driver.handle_rx(now, &answer);
    let probe = drain(&mut driver, now);
    assert!(probe[0].starts_with(&[2, 4, 1, 249]), "probed");
    driver.handle_rx(
        now,
        &probe_answers([DataMask::DEFAULT; 4], StreamConfig(0), 0),
    );
    assert_eq!(driver.status().fault, Some(DeviceFault::Reset));
    assert_eq!(driver.status().resets, 1);
    let evidence = driver.status().verdict.expect("verdict").evidence;
    assert!(
        evidence
            .as_str()
            .contains("read stream period 0, stream config 00, data masks")
            && evidence
                .as_str()
                .contains("the board lost its configuration"),
        "{}",
        evidence.as_str()
    );
    assert_eq!(driver.channel(0).fault, Some(DeviceFault::Reset));
    let sent = drain(&mut driver, now);
    assert_eq!(packets(&sent[0]).len(), 10, "configured again");
    driver.handle_rx(now + MS, &acks(&sent[0], 0));
    driver.handle_rx(now + MS, &ours_stream([1, 2, 3], [0; 3], [0; 3]));
    assert_eq!(driver.status().fault, None);
}

#[test]
fn a_silent_board_is_not_responding() {
    let mut driver = Qq2drvDriver::new(config());
    let mut now = Duration::ZERO;
    let mut probes = 0;
    let silence = driver.config().silence;
    while now <= silence + 10 * MS {
        for transaction in drain(&mut driver, now) {
            driver.handle_rx(now, &vec![0xFF; transaction.len()]);
            probes += usize::from(transaction.starts_with(&[2, 4, 1, 249]));
        }
        if now < silence {
            assert_eq!(
                driver.status().fault,
                None,
                "not before {silence:?}: {now:?}"
            );
        }
        now += MS;
    }
    assert_eq!(driver.status().fault, Some(DeviceFault::NotResponding));
    assert!(!driver.status().online);
    assert!(probes >= START_ATTEMPTS as usize);
    assert_eq!(driver.channel(0).fault, Some(DeviceFault::NotResponding));
    let status = driver.status();
    assert_eq!(status.verdicts, 1);
    let evidence = status.verdict.expect("verdict").evidence;
    assert!(
        evidence
            .as_str()
            .starts_with("no valid packet on MISO since 0.000 s")
            && evidence.as_str().contains("ms of silence (silence_ms 500)"),
        "{}",
        evidence.as_str()
    );
    // Goals wait for the board; a stop is still accepted.
    driver.set_goal(now, 0, Goal::Stop { decel: 1.0 }).unwrap();
}
