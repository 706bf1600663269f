//! [`Signal`]: one board I/O signal of the server (`[[signal]]` in its config), by handle,
//! and the events of capture and trigger signals ([`SignalEvent`]).

use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{CommandKind, SignalFlags, SignalInfo, SignalKind, SignalState, Target};

use crate::{Accepted, ClaimGuard, Client, ClientError};

/// One signal of the server, found by name with [`Client::signal`]. Cheap to copy.
///
/// Values are logical: a digital signal is 0.0 (off) or 1.0 (on) after its `invert`; an
/// analogue one is `raw × scale + offset` in its unit. A value flagged stale (the board has
/// not reported it within its refresh budget) is returned by [`Signal::state`] as it is and
/// never satisfies a wait.
#[derive(Debug)]
pub struct Signal<'c, S: Service> {
    client: &'c Client<S>,
    index: u32,
}

impl<S: Service> Clone for Signal<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: Service> Copy for Signal<'_, S> {}

impl<S: Service> Client<S> {
    /// The handle of the signal called `name`.
    pub fn signal(&self, name: &str) -> Result<Signal<'_, S>, ClientError> {
        let index = self
            .info
            .current()
            .and_then(|info| info.signal_index(name))
            .ok_or_else(|| ClientError::UnknownSignal(name.to_owned()))?;
        Ok(Signal {
            client: self,
            index: u32::try_from(index).unwrap_or(u32::MAX),
        })
    }

    /// Handles of every signal, in config order.
    pub fn signals(&self) -> Vec<Signal<'_, S>> {
        let count = self.info.current().map_or(0, |info| info.signals().len());
        (0..count)
            .map(|index| Signal {
                client: self,
                index: u32::try_from(index).unwrap_or(u32::MAX),
            })
            .collect()
    }
}

/// A capture's or a trigger pulse's event, as [`Signal::wait_event`] found it in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalEvent {
    /// The signal's sequence: events since the server started (wrapping at 2³²).
    pub sequence: u32,
    /// The tick that took the event in.
    pub tick: u64,
    /// The signal's value then: a capture's position, a trigger's compare position.
    pub value: f64,
    /// Its raw value (counter counts).
    pub raw: f64,
    /// Events between the sequence waited after and this one that no frame showed
    /// apart (two taken in by one tick, or frames this client did not read): 0 when
    /// this is the next one.
    pub missed: u32,
}

/// A value as words: "on", "off", "1.25 bar".
pub fn signal_value_text(info: &SignalInfo, value: f64) -> String {
    match info.kind() {
        Ok(SignalKind::DigitalIn | SignalKind::DigitalOut) => {
            if value >= 0.5 { "on" } else { "off" }.to_owned()
        }
        _ => format!("{value} {}", info.unit()).trim_end().to_owned(),
    }
}

impl<'c, S: Service> Signal<'c, S> {
    /// The signal index (config order), as used in frames and requests.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The signal's static description (name, device, pin, kind, unit, scale).
    pub fn info(&self) -> SignalInfo {
        self.client.signal_info(self.index as usize)
    }

    /// The signal name.
    pub fn name(&self) -> String {
        self.info().name().to_owned()
    }

    /// The signal's kind (`None` for a kind this build does not know).
    pub fn kind(&self) -> Option<SignalKind> {
        self.info().kind().ok()
    }

    /// Whether it is digital (in or out).
    pub fn is_digital(&self) -> bool {
        matches!(
            self.kind(),
            Some(SignalKind::DigitalIn | SignalKind::DigitalOut)
        )
    }

    /// The signal's state in the newest frame (a copy).
    pub fn state(&self) -> Result<SignalState, ClientError> {
        let frame = self.client.latest()?;
        Ok(frame
            .signals()
            .get(self.index as usize)
            .copied()
            .unwrap_or(SignalState::UNKNOWN))
    }

    /// The logical value in the newest frame.
    pub fn value(&self) -> Result<f64, ClientError> {
        Ok(self.state()?.value)
    }

    /// Whether a digital signal is on in the newest frame.
    pub fn is_on(&self) -> Result<bool, ClientError> {
        Ok(self.state()?.is_on())
    }

    fn command(&self, kind: CommandKind, value: f64) -> Result<Accepted, ClientError> {
        self.client
            .command_to(Target::Signal, self.index, kind, [value, 0.0, 0.0])
    }

    /// Sets a digital output on or off (`SetOutput`; the logical value, before `invert`).
    /// Refused with `NotAnOutput` for an input, `ClaimedByOther` while another client
    /// holds it, `EstopLatched` while the e-stop holds outputs in their safe state.
    pub fn set(&self, on: bool) -> Result<Accepted, ClientError> {
        self.command(CommandKind::SetOutput, if on { 1.0 } else { 0.0 })
    }

    /// Sets a trigger's compare position (`SetOutput` on a `trigger` signal), in the
    /// signal's unit (by default the axis's): the board pulses its output when the count
    /// matches it. Refused with `NotAnOutput` for any other kind, `OutOfRange` for a
    /// position the board's counter cannot hold, `Unsupported` when the trigger does not
    /// fire on "match".
    pub fn set_value(&self, value: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::SetOutput, value)
    }

    /// The signal's sequence in the newest frame: captures or trigger pulses since the
    /// server started (0 for other kinds). Pass it to [`wait_event`](Self::wait_event).
    pub fn sequence(&self) -> Result<u32, ClientError> {
        Ok(self.state()?.sequence)
    }

    /// Waits for the next event (a capture, a trigger pulse) after sequence `after`: the
    /// first frame whose sequence differs from it. [`SignalEvent::missed`] counts the
    /// events in between that no frame showed apart (only the newest value of a tick is
    /// in the frame). Times out with `SignalTimeout`.
    pub fn wait_event(&self, after: u32, timeout: Duration) -> Result<SignalEvent, ClientError> {
        let wanted = format!("an event after sequence {after}");
        let state = self.wait_described(&wanted, timeout, |state| state.sequence != after)?;
        Ok(SignalEvent {
            sequence: state.sequence,
            tick: state.event_tick,
            value: state.value,
            raw: state.raw,
            missed: state.events_since(after).saturating_sub(1),
        })
    }

    /// Takes an exclusive claim on the output: other clients' `set` is then refused.
    pub fn claim(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Claim, 0.0)
    }

    /// Gives a claim back.
    pub fn release(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Release, 0.0)
    }

    /// A claim held by a guard (see [`ClaimGuard`]).
    pub fn claim_guard(&self) -> Result<ClaimGuard<'c, S>, ClientError> {
        ClaimGuard::take(self.client, Target::Signal, self.index)
    }

    /// How close an analogue value must be for [`Signal::wait_for`]: one converter count in
    /// the signal's unit (`|scale|`). Digital signals compare on/off.
    pub fn tolerance(&self) -> f64 {
        self.info().scale.abs()
    }

    /// Waits until the signal has `value`: a digital signal is on when `value >= 0.5`, an
    /// analogue one must be within [`Signal::tolerance`] of it. Returns the state that
    /// matched.
    pub fn wait_for(&self, value: f64, timeout: Duration) -> Result<SignalState, ClientError> {
        if self.is_digital() {
            let on = value >= 0.5;
            let wanted = if on { "on" } else { "off" }.to_owned();
            return self.wait_described(&wanted, timeout, |state| state.is_on() == on);
        }
        self.wait_within(value, self.tolerance(), timeout)
    }

    /// Waits until an analogue value is within `tolerance` of `value`.
    pub fn wait_within(
        &self,
        value: f64,
        tolerance: f64,
        timeout: Duration,
    ) -> Result<SignalState, ClientError> {
        let wanted = format!("{} ± {tolerance}", signal_value_text(&self.info(), value));
        self.wait_described(&wanted, timeout, |state| {
            (state.value - value).abs() <= tolerance
        })
    }

    /// Waits until `done` holds for a fresh (not stale) state of the signal.
    pub fn wait_until(
        &self,
        timeout: Duration,
        done: impl FnMut(&SignalState) -> bool,
    ) -> Result<SignalState, ClientError> {
        self.wait_described("as awaited", timeout, done)
    }

    fn wait_described(
        &self,
        wanted: &str,
        timeout: Duration,
        mut done: impl FnMut(&SignalState) -> bool,
    ) -> Result<SignalState, ClientError> {
        let deadline = Instant::now() + timeout;
        let info = self.info();
        let mut frame = self.client.latest()?;
        loop {
            let state = frame
                .signals()
                .get(self.index as usize)
                .copied()
                .unwrap_or(SignalState::UNKNOWN);
            let stale = state.flags().contains(SignalFlags::STALE);
            if !stale && done(&state) {
                return Ok(state);
            }
            let now = Instant::now();
            let next = if now < deadline {
                drop(frame);
                self.client.next_frame(deadline - now)
            } else {
                Err(ClientError::NoFrame(timeout))
            };
            frame = match next {
                Ok(next) => next,
                Err(ClientError::NoFrame(_)) => {
                    return Err(ClientError::SignalTimeout {
                        signal: info.name().to_owned(),
                        wanted: wanted.to_owned(),
                        last: if stale {
                            "stale".to_owned()
                        } else {
                            signal_value_text(&info, state.value)
                        },
                        waited: timeout,
                    });
                }
                Err(error) => return Err(error),
            };
        }
    }
}
