//! The line rate of a stream bus: a message goes at the rate its driver asks for
//! ([`Driver::line_rate`]), the change noted before the message is handed out.

use core::time::Duration;

use super::*;
use crate::Model;
use crate::goal::{Goal, GoalError, GoalKinds};
use crate::state::{ChannelState, DeviceStatus};

/// A driver whose messages (one byte: its tag) each go at the rate scripted for them.
#[derive(Debug)]
struct AtRate {
    tag: u8,
    rates: Vec<Option<u32>>,
}

impl Driver for AtRate {
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
    fn poll_timeout(&self) -> Option<Duration> {
        None
    }
    fn wants_transmit(&self, _: Duration) -> Option<Priority> {
        (!self.rates.is_empty()).then_some(Priority::Poll)
    }
    fn poll_transmit(&mut self, _: Duration, buf: &mut [u8]) -> Option<Transmit> {
        if self.rates.is_empty() {
            return None;
        }
        self.rates.remove(0);
        buf[0] = self.tag;
        Some(Transmit {
            len: 1,
            expects_reply: false,
            goal_starts: 0,
        })
    }
    fn line_rate(&self) -> Option<u32> {
        self.rates.first().copied().flatten()
    }
    fn awaiting_reply(&self) -> bool {
        false
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

/// Every message with the rate change the shell must make before it.
fn drain(bus: &mut LinkBus) -> Vec<(u8, Option<u32>)> {
    let mut buf = [0u8; 256];
    let mut out = Vec::new();
    while let Some((_, t)) = bus.poll_transmit(Duration::ZERO, &mut buf) {
        assert_eq!(t.len, 1);
        out.push((buf[0], bus.take_rate_change()));
    }
    out
}

#[test]
fn a_message_at_another_rate_is_preceded_by_the_change_and_only_once() {
    let rates = vec![
        None,
        Some(19_200),
        Some(19_200),
        Some(115_200),
        Some(115_200),
        None,
        Some(19_200),
    ];
    let mut bus = LinkBus::new(
        LinkKind::Stream,
        vec![Box::new(AtRate { tag: 1, rates }) as Box<dyn Driver>],
    );
    assert_eq!(
        drain(&mut bus),
        [
            (1, None),
            // The link's own rate is not known to the bus: said once.
            (1, Some(19_200)),
            (1, None),
            (1, Some(115_200)),
            (1, None),
            // No wish: the link stays where it is.
            (1, None),
            (1, Some(19_200)),
        ]
    );
    assert_eq!(bus.line_rate(), Some(19_200));
    bus.link_up(Duration::ZERO);
    assert_eq!(bus.line_rate(), None, "reopened at its configured rate");
}

#[test]
fn two_drivers_at_two_rates_each_get_theirs_and_spi_has_none() {
    let mut bus = LinkBus::new(
        LinkKind::Stream,
        vec![
            Box::new(AtRate {
                tag: 1,
                rates: vec![Some(115_200); 2],
            }) as Box<dyn Driver>,
            Box::new(AtRate {
                tag: 2,
                rates: vec![Some(19_200); 2],
            }),
        ],
    );
    assert_eq!(
        drain(&mut bus),
        [
            (1, Some(115_200)),
            (2, Some(19_200)),
            (1, Some(115_200)),
            (2, Some(19_200)),
        ]
    );
    let mut spi = LinkBus::new(
        LinkKind::Spi,
        vec![Box::new(AtRate {
            tag: 3,
            rates: vec![Some(115_200)],
        }) as Box<dyn Driver>],
    );
    assert_eq!(drain(&mut spi), [(3, None)]);
}
