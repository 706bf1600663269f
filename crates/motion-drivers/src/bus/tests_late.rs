//! A stream bus shares the answers each board may still send late ([`LateAnswer`]).

use core::time::Duration;

use super::*;
use crate::Model;
use crate::goal::{Goal, GoalError, GoalKinds};
use crate::state::{ChannelState, DeviceStatus};

/// A driver with late answers of its own that records the others' it is handed.
#[derive(Debug, Default)]
struct Late {
    own: Vec<LateAnswer>,
    /// What `handle_late_answers` gave, call by call.
    handed: Vec<Vec<LateAnswer>>,
    sends: bool,
    /// Wants to send but has nothing after all (its question must wait).
    holds: bool,
    /// Holds the line without a request of its own in flight (bytes it did not ask for
    /// are coming).
    busy: bool,
    priority: Option<Priority>,
}

impl Driver for Late {
    fn model(&self) -> Model {
        Model::TMCPACK
    }
    fn channel_count(&self) -> usize {
        1
    }
    fn capabilities(&self, _: usize) -> GoalKinds {
        GoalKinds::NONE
    }
    fn refresh_budget(&self) -> Duration {
        Duration::from_millis(100)
    }
    fn handle_rx(&mut self, _: Duration, _: &[u8]) {}
    fn handle_timeout(&mut self, _: Duration) {}
    fn late_answers(&self) -> &[LateAnswer] {
        &self.own
    }
    fn handle_late_answers(&mut self, others: &[LateAnswer]) {
        self.handed.push(others.to_vec());
    }
    fn poll_timeout(&self) -> Option<Duration> {
        None
    }
    fn wants_transmit(&self, _: Duration) -> Option<Priority> {
        self.sends
            .then_some(self.priority.unwrap_or(Priority::Poll))
    }
    fn poll_transmit(&mut self, _: Duration, buf: &mut [u8]) -> Option<Transmit> {
        if self.holds {
            return None;
        }
        buf[0] = 1;
        Some(Transmit {
            len: 1,
            expects_reply: false,
            goal_starts: 0,
        })
    }
    fn awaiting_reply(&self) -> bool {
        self.busy
    }
    fn goals_pending(&self) -> bool {
        false
    }
    fn set_goal(&mut self, _: Duration, _: usize, _: Goal) -> Result<(), GoalError> {
        Ok(())
    }
    fn channel(&self, _: usize) -> ChannelState {
        ChannelState::UNKNOWN
    }
    fn status(&self) -> DeviceStatus {
        DeviceStatus::UNKNOWN
    }
    fn link_down(&mut self, _: Duration) {}
    fn link_up(&mut self, _: Duration) {}
}

const MS: Duration = Duration::from_millis(1);

#[test]
fn every_driver_learns_the_other_drivers_late_answers_before_a_pick_and_before_bytes() {
    let a20 = LateAnswer::new(&[0xFE, 0x20, 0], 500 * MS);
    let a43 = LateAnswer::new(&[0xFE, 0x43], 500 * MS);
    let b21 = LateAnswer::new(&[0xFE, 0x21, 3], 400 * MS);
    let a = Late {
        own: vec![a20, a43],
        ..Late::default()
    };
    let b = Late {
        own: vec![b21],
        sends: true,
        ..Late::default()
    };
    let c = Late::default();
    let mut bus: LinkBus<Late> = LinkBus::new(LinkKind::Stream, vec![a, b, c]);
    let mut buf = [0u8; 16];
    assert!(bus.poll_transmit(MS, &mut buf).is_some());
    let last = |bus: &LinkBus<Late>, i: usize| bus.drivers()[i].handed.last().cloned();
    assert_eq!(last(&bus, 0), Some(vec![b21]), "a: b's, not its own");
    assert_eq!(last(&bus, 1), Some(vec![a20, a43]));
    assert_eq!(last(&bus, 2), Some(vec![a20, a43, b21]));
    bus.handle_rx(2 * MS, &[0xFE]);
    assert_eq!(
        bus.drivers()[2].handed.len(),
        2,
        "again before bytes are routed"
    );
    // Gone everywhere: handed once empty, then no more calls.
    for i in 0..3 {
        bus.driver_mut(i).expect("driver").own.clear();
    }
    bus.handle_rx(3 * MS, &[0xFE]);
    assert_eq!(last(&bus, 2), Some(vec![]));
    let calls = bus.drivers()[2].handed.len();
    bus.handle_rx(4 * MS, &[0xFE]);
    assert!(bus.poll_transmit(5 * MS, &mut buf).is_some());
    assert_eq!(bus.drivers()[2].handed.len(), calls, "nothing to share");
}

#[test]
fn one_driver_alone_and_spi_buses_share_nothing() {
    let a = Late {
        own: vec![LateAnswer::new(&[0xFE, 0x20, 0], 500 * MS)],
        sends: true,
        ..Late::default()
    };
    let mut bus: LinkBus<Late> = LinkBus::new(LinkKind::Stream, vec![a]);
    let mut buf = [0u8; 16];
    assert!(bus.poll_transmit(MS, &mut buf).is_some());
    bus.handle_rx(2 * MS, &[0]);
    assert!(bus.drivers()[0].handed.is_empty());
    let spi = |own| Late {
        own,
        sends: true,
        ..Late::default()
    };
    let late = vec![LateAnswer::new(&[1], MS)];
    let mut bus: LinkBus<Late> = LinkBus::new(LinkKind::Spi, vec![spi(late), spi(vec![])]);
    assert!(bus.poll_transmit(MS, &mut buf).is_some());
    assert!(bus.drivers().iter().all(|d| d.handed.is_empty()));
}

#[test]
fn the_share_is_bounded_by_its_capacity() {
    let many: Vec<LateAnswer> = (0..LATE_ANSWERS as u8 + 5)
        .map(|i| LateAnswer::new(&[0xFE, 0x20, i], MS))
        .collect();
    let a = Late {
        own: many.clone(),
        ..Late::default()
    };
    let b = Late {
        sends: true,
        ..Late::default()
    };
    let mut bus: LinkBus<Late> = LinkBus::new(LinkKind::Stream, vec![a, b]);
    let mut buf = [0u8; 16];
    assert!(bus.poll_transmit(MS, &mut buf).is_some());
    let handed = bus.drivers()[1].handed.last().cloned().expect("handed");
    assert_eq!(handed, many[..LATE_ANSWERS].to_vec());
}

#[test]
fn a_driver_whose_question_must_wait_gives_way_to_the_next() {
    let holding = |priority| Late {
        sends: true,
        holds: true,
        priority: Some(priority),
        ..Late::default()
    };
    let willing = Late {
        sends: true,
        ..Late::default()
    };
    let mut bus: LinkBus<Late> = LinkBus::new(
        LinkKind::Stream,
        vec![holding(Priority::Command), holding(Priority::Poll), willing],
    );
    let mut buf = [0u8; 16];
    for step in 1..4 {
        let (index, _) = bus
            .poll_transmit(step * MS, &mut buf)
            .expect("someone sends");
        assert_eq!(index, 2, "step {step}");
    }
    bus.driver_mut(2).expect("driver").sends = false;
    assert!(bus.poll_transmit(5 * MS, &mut buf).is_none());
}

#[test]
fn a_driver_that_holds_the_line_without_a_request_holds_it_for_everyone() {
    let quiet = Late {
        busy: true,
        ..Late::default()
    };
    let willing = Late {
        sends: true,
        ..Late::default()
    };
    let mut bus: LinkBus<Late> = LinkBus::new(LinkKind::Stream, vec![quiet, willing]);
    let mut buf = [0u8; 16];
    assert!(bus.poll_transmit(MS, &mut buf).is_none());
    bus.driver_mut(0).expect("driver").busy = false;
    assert_eq!(bus.poll_transmit(2 * MS, &mut buf).map(|(i, _)| i), Some(1));
}
