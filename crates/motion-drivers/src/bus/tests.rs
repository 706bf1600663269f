//! Arbitration rules of [`LinkBus`], with scripted drivers.

use core::time::Duration;

use super::*;
use crate::Model;
use crate::goal::{Goal, GoalError, GoalKinds};
use crate::state::{ChannelState, DeviceStatus};

/// A driver that sends scripted messages and waits for `reply_len` bytes after each one
/// that expects a reply.
#[derive(Debug)]
struct Scripted {
    tag: u8,
    queue: Vec<(Priority, usize, bool)>,
    reply_len: usize,
    awaiting: usize,
    received: Vec<u8>,
}

impl Scripted {
    fn new(tag: u8, queue: &[(Priority, usize, bool)], reply_len: usize) -> Box<Self> {
        Box::new(Self {
            tag,
            queue: queue.to_vec(),
            reply_len,
            awaiting: 0,
            received: Vec::new(),
        })
    }
}

impl Driver for Scripted {
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
    fn handle_rx(&mut self, _: Duration, bytes: &[u8]) {
        self.received.extend_from_slice(bytes);
        self.awaiting = self.awaiting.saturating_sub(bytes.len());
    }
    fn handle_timeout(&mut self, _: Duration) {}
    fn poll_timeout(&self) -> Option<Duration> {
        None
    }
    fn wants_transmit(&self, _: Duration) -> Option<Priority> {
        self.queue.first().map(|(priority, _, _)| *priority)
    }
    fn poll_transmit(&mut self, _: Duration, buf: &mut [u8]) -> Option<Transmit> {
        if self.queue.is_empty() {
            return None;
        }
        let (_, len, expects_reply) = self.queue.remove(0);
        buf[..len].fill(self.tag);
        if expects_reply {
            self.awaiting = self.reply_len;
        }
        Some(Transmit {
            len,
            expects_reply,
            goal_starts: 0,
        })
    }
    fn awaiting_reply(&self) -> bool {
        self.awaiting > 0
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
    fn link_down(&mut self, _: Duration) {
        self.awaiting = 0;
    }
    fn link_up(&mut self, _: Duration) {}
}

const T0: Duration = Duration::ZERO;

fn received<D: Driver>(bus: &LinkBus<D>, index: usize) -> String {
    format!("{:?}", bus.drivers()[index])
}

#[test]
fn stream_bus_holds_everyone_while_a_reply_is_awaited() {
    let a = Scripted::new(
        1,
        &[(Priority::Poll, 9, true), (Priority::Poll, 9, true)],
        9,
    );
    let b = Scripted::new(2, &[(Priority::Poll, 9, true)], 9);
    let mut bus = LinkBus::new(LinkKind::Stream, vec![a, b]);
    let mut buf = [0u8; 256];

    let (first, _) = bus.poll_transmit(T0, &mut buf).expect("a sends");
    assert_eq!(first, 0);
    assert_eq!(
        bus.poll_transmit(T0, &mut buf),
        None,
        "second request while one in flight"
    );

    bus.handle_rx(T0, &[0xAA; 4]);
    assert_eq!(
        bus.poll_transmit(T0, &mut buf),
        None,
        "partial reply keeps the bus busy"
    );
    bus.handle_rx(T0, &[0xAA; 5]);

    let (second, _) = bus.poll_transmit(T0, &mut buf).expect("bus free again");
    assert_eq!(second, 1, "round robin: b's turn");
    assert_eq!(buf[0], 2);
}

#[test]
fn commands_go_before_polls() {
    let a = Scripted::new(1, &[(Priority::Poll, 9, false)], 0);
    let b = Scripted::new(2, &[(Priority::Command, 9, false)], 0);
    let mut bus = LinkBus::new(LinkKind::Stream, vec![a, b]);
    let mut buf = [0u8; 256];
    assert_eq!(bus.poll_transmit(T0, &mut buf).map(|(i, _)| i), Some(1));
    assert_eq!(bus.poll_transmit(T0, &mut buf).map(|(i, _)| i), Some(0));
    assert_eq!(bus.poll_transmit(T0, &mut buf), None);
}

/// A stop goes before another driver's command (and its overdue poll, also `Command`) even
/// when round robin gives that driver the turn: it waits for nothing but the exchange in
/// flight (docs/ARCHITECTURE.md "The deadman's bound per board").
#[test]
fn stops_go_before_commands_whoever_has_the_turn() {
    let a = Scripted::new(
        1,
        &[(Priority::Command, 9, true), (Priority::Stop, 9, false)],
        9,
    );
    let b = Scripted::new(2, &[(Priority::Command, 9, false)], 0);
    let mut bus = LinkBus::new(LinkKind::Stream, vec![a, b]);
    let mut buf = [0u8; 256];
    assert_eq!(bus.poll_transmit(T0, &mut buf).map(|(i, _)| i), Some(0));
    assert_eq!(bus.poll_transmit(T0, &mut buf), None, "a's query in flight");
    bus.handle_rx(T0, &[0xAA; 9]);
    // b has the turn now, but a's stop goes first.
    assert_eq!(bus.poll_transmit(T0, &mut buf).map(|(i, _)| i), Some(0));
    assert_eq!(buf[0], 1);
    assert_eq!(bus.poll_transmit(T0, &mut buf).map(|(i, _)| i), Some(1));
}

#[test]
fn spi_miso_bytes_go_back_to_the_transaction_owner_in_order() {
    let a = Scripted::new(1, &[(Priority::Poll, 3, false)], 0);
    let b = Scripted::new(2, &[(Priority::Poll, 2, false)], 0);
    let mut bus = LinkBus::new(LinkKind::Spi, vec![a, b]);
    let mut buf = [0u8; 256];
    assert!(bus.poll_transmit(T0, &mut buf).is_some());
    assert!(bus.poll_transmit(T0, &mut buf).is_some());
    // MISO of both transactions arrives in one read, split oddly.
    bus.handle_rx(T0, &[10, 11]);
    bus.handle_rx(T0, &[12, 20, 21, 99]);
    assert!(received(&bus, 0).contains("received: [10, 11, 12]"));
    assert!(received(&bus, 1).contains("received: [20, 21]"));
    assert_eq!(bus.stray_bytes(), 1);
}

#[test]
fn link_down_frees_the_bus() {
    let a = Scripted::new(
        1,
        &[(Priority::Poll, 9, true), (Priority::Poll, 9, true)],
        9,
    );
    let mut bus = LinkBus::new(LinkKind::Stream, vec![a]);
    let mut buf = [0u8; 256];
    assert!(bus.poll_transmit(T0, &mut buf).is_some());
    assert_eq!(bus.poll_transmit(T0, &mut buf), None);
    bus.link_down(T0);
    assert!(bus.poll_transmit(T0, &mut buf).is_some());
}
