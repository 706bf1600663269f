//! Named board I/O: inputs read from the drivers every step, digital outputs set by
//! clients (claims apply, as for axes) and put into their safe state by an e-stop; the
//! events of capture and trigger signals (a sequence number and the tick that took the
//! newest in); a trigger's compare position set by clients.

use core::time::Duration;

use motion_drivers::Driver;
use motion_drivers::{GoalError, PinReading, SignalKind};
use motion_ipc::{ClientId, Reason};

use crate::Engine;
use crate::config::SignalConfig;

/// Runtime state of one signal.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Signal {
    pub config: SignalConfig,
    /// Link (bus) and driver index of its device.
    pub bus: usize,
    pub slot: usize,
    /// Raw value as last read (electrical level, ADC counts).
    pub raw: f64,
    pub refreshed_at: Option<Duration>,
    pub last_refresh_tick: u64,
    pub stale: bool,
    pub claimed_by: ClientId,
    pub claim_renewed_at: Duration,
    /// Output: the logical value last commanded (by a client or the e-stop).
    pub commanded: Option<bool>,
    /// Output: the e-stop put it into its safe state (until the next command or reset).
    pub safe_applied: bool,
    /// Trigger: the raw compare position last commanded, until the board reports it.
    pub commanded_raw: Option<f64>,
    /// Events seen (the driver's count of the last reading), the signal's sequence, and
    /// the tick that took the newest in.
    pub driver_events: u32,
    pub sequence: u32,
    pub event_tick: u64,
}

impl Signal {
    pub fn new(config: SignalConfig, bus: usize, slot: usize) -> Self {
        Self {
            config,
            bus,
            slot,
            raw: 0.0,
            refreshed_at: None,
            last_refresh_tick: 0,
            stale: true,
            claimed_by: ClientId::NONE,
            claim_renewed_at: Duration::ZERO,
            commanded: None,
            safe_applied: false,
            commanded_raw: None,
            driver_events: 0,
            sequence: 0,
            event_tick: 0,
        }
    }

    /// The logical value: digital 0/1 after `invert`, analogue (capture, trigger) raw ×
    /// scale + offset.
    pub fn value(&self) -> f64 {
        match self.config.kind {
            SignalKind::AnalogIn | SignalKind::Capture | SignalKind::Trigger => {
                self.raw * self.config.scale + self.config.offset
            }
            SignalKind::DigitalIn | SignalKind::DigitalOut => {
                f64::from(u8::from((self.raw >= 0.5) != self.config.invert))
            }
        }
    }

    /// An output whose commanded value the board has not confirmed yet.
    pub fn pending(&self) -> bool {
        if let Some(raw) = self.commanded_raw {
            return self.refreshed_at.is_none() || raw != self.raw;
        }
        self.commanded.is_some_and(|on| {
            self.refreshed_at.is_none() || (self.raw >= 0.5) != (on != self.config.invert)
        })
    }
}

impl<D: Driver> Engine<D> {
    /// Step 1c: every signal's reading from its driver.
    pub(crate) fn update_signals(&mut self) {
        let (now, tick) = (self.now, self.tick);
        for signal in &mut self.signals {
            let Some(driver) = self.buses[signal.bus].drivers().get(signal.slot) else {
                continue;
            };
            let reading = driver
                .read_pin(signal.config.pin)
                .unwrap_or(PinReading::UNKNOWN);
            if reading.value.is_finite() {
                signal.raw = reading.value;
            }
            if reading.refreshed_at > signal.refreshed_at {
                signal.refreshed_at = reading.refreshed_at;
                signal.last_refresh_tick = tick;
            }
            // Events the driver counted since the last step (only ever up, wrapping):
            // several in one step are one step of several in the sequence.
            let new_events = reading.events.wrapping_sub(signal.driver_events);
            signal.driver_events = reading.events;
            if new_events != 0 {
                signal.sequence = signal.sequence.wrapping_add(new_events);
                signal.event_tick = tick;
            }
            let budget = driver.refresh_budget();
            signal.stale = signal
                .refreshed_at
                .is_none_or(|at| now.saturating_sub(at) > budget);
        }
    }

    /// Sets the compare position of trigger `index` (accepted by the rulebook) to `value`,
    /// in the signal's unit: raw = (value − offset) / scale, handed to the driver.
    pub(crate) fn set_value(&mut self, index: usize, value: f64) -> Reason {
        let now = self.now;
        let signal = &self.signals[index];
        let raw = (value - signal.config.offset) / signal.config.scale;
        if !raw.is_finite() {
            return Reason::OutOfRange;
        }
        let (bus, slot, pin) = (signal.bus, signal.slot, signal.config.pin);
        let result = match self.buses[bus].driver_mut(slot) {
            Some(driver) => driver.set_pin_value(now, pin, raw),
            None => Err(GoalError::Offline),
        };
        match result {
            Ok(()) => {
                self.signals[index].commanded_raw = Some(raw.round());
                Reason::Accepted
            }
            Err(GoalError::Starting) => Reason::DeviceStarting,
            Err(GoalError::Offline) => Reason::DeviceOffline,
            Err(GoalError::OutOfBoardRange(_)) => Reason::OutOfRange,
            Err(_) => Reason::Unsupported,
        }
    }

    /// Sets output `index` (accepted by the rulebook) to the logical value `on`.
    pub(crate) fn set_output(&mut self, index: usize, on: bool) -> Reason {
        match self.drive_output(index, on) {
            Ok(()) => {
                self.signals[index].safe_applied = false;
                Reason::Accepted
            }
            Err(GoalError::Starting) => Reason::DeviceStarting,
            Err(GoalError::Offline) => Reason::DeviceOffline,
            Err(_) => Reason::Unsupported,
        }
    }

    /// Hands the logical value `on` of output `index` to its driver.
    fn drive_output(&mut self, index: usize, on: bool) -> Result<(), GoalError> {
        let now = self.now;
        let signal = &self.signals[index];
        let (bus, slot, pin) = (signal.bus, signal.slot, signal.config.pin);
        let level = on != signal.config.invert;
        let driver = self.buses[bus].driver_mut(slot).ok_or(GoalError::Offline)?;
        driver.set_output(now, pin, level)?;
        self.signals[index].commanded = Some(on);
        Ok(())
    }

    /// E-stop: every output with a safe state takes it.
    pub(crate) fn outputs_to_safe_state(&mut self) {
        for index in 0..self.signals.len() {
            let signal = &self.signals[index];
            if signal.config.kind != SignalKind::DigitalOut {
                continue;
            }
            if let Some(safe) = signal.config.safe
                && self.drive_output(index, safe).is_ok()
            {
                self.signals[index].safe_applied = true;
            }
        }
    }
}
