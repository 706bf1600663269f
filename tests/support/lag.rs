//! The starvation defect (issue 18): an I/O side that lags must not make a healthy board
//! look dead, while a silent board is still found. Shared by the four boards' tests.

use core::time::Duration;

use motion_ipc::{AxisFlags, DeviceState, FaultCode};

use super::rig::{IoLag, Rig};

/// Messages reach the wire 100 ms after they were queued (a full transmit buffer, or an
/// I/O thread that got no CPU to write), reads are prompt; stamps reported.
pub const LATE_WRITES: IoLag = IoLag {
    write_delay: Duration::from_millis(100),
    runs_every: Duration::ZERO,
    report: true,
};

/// The whole I/O side runs only every 100 ms (a starved I/O thread); stamps reported.
pub const STARVED: IoLag = IoLag {
    write_delay: Duration::ZERO,
    runs_every: Duration::from_millis(100),
    report: true,
};

/// A prompt I/O side that reports its stamps (as motiond's does on an idle machine).
pub const PROMPT: IoLag = IoLag {
    write_delay: Duration::ZERO,
    runs_every: Duration::ZERO,
    report: true,
};

/// The same lag as `lag`, but the engine is not told (what happened before issue 18).
pub const fn unreported(lag: IoLag) -> IoLag {
    IoLag {
        report: false,
        ..lag
    }
}

/// Runs until device 0 is online (within `online_within`), then `span` more: in every
/// frame from then on device 0 stays online and none of the first `axes` axes has a
/// fault, and the drivers count no reply timeout. Returns how many frames had data fresh
/// on every axis (the lag may make data old, which is true and not a fault).
pub fn stays_healthy(rig: &mut Rig, axes: usize, online_within: Duration, span: Duration) -> usize {
    assert!(
        rig.run_until(online_within, |frame| frame.device_state(0)
            == DeviceState::Online),
        "the board comes online despite the lag"
    );
    let timeouts_before = rig.engine.driver(0).expect("driver").status().timeouts;
    let end = rig.now + span;
    let mut fresh = 0;
    while rig.now < end {
        rig.tick();
        assert_eq!(
            rig.frame.device_state(0),
            DeviceState::Online,
            "at {:?} the board left the online state",
            rig.now
        );
        for index in 0..axes {
            let axis = rig.axis(index);
            assert_eq!(axis.fault, 0, "axis {index} faulted at {:?}", rig.now);
        }
        if (0..axes).all(|index| !rig.axis(index).flags().contains(AxisFlags::STALE)) {
            fresh += 1;
        }
    }
    let status = rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.timeouts, timeouts_before, "no reply timed out");
    assert!(status.online);
    fresh
}

/// Runs up to `within`; returns when axis 0 showed `BoardNotResponding`, if it did.
pub fn not_responding_after(rig: &mut Rig, within: Duration) -> Option<Duration> {
    let start = rig.now;
    rig.run_until(within, |frame| {
        frame.axes[0].fault == FaultCode::BoardNotResponding as u16
    })
    .then(|| rig.now - start)
}

/// Runs until device 0 is online and 500 ms more (the board settled: its first polls
/// answered), silences the board (nothing reaches the host any more), and returns how
/// long until axis 0 shows `BoardNotResponding` (panics after 5 s).
pub fn silence_found_after(
    rig: &mut Rig,
    faults: &motion_link::sim::SimFaults,
    online_within: Duration,
) -> Duration {
    assert!(
        rig.run_until(online_within, |frame| frame.device_state(0)
            == DeviceState::Online),
        "the board comes online"
    );
    rig.run(500);
    faults.set_drop_probability(motion_link::sim::Direction::ToHost, 1.0);
    not_responding_after(rig, Duration::from_secs(5)).expect("a silent board is found")
}

/// How long after going silent a board is found (see [`silence_found_after`]): without
/// stamps (today's bound), with prompt stamps, with writes reported 100 ms late, and with
/// an I/O side that runs only every 100 ms.
#[derive(Debug, Clone, Copy)]
pub struct SilenceFound {
    pub today: Duration,
    pub prompt: Duration,
    pub late: Duration,
    pub starved: Duration,
}

impl SilenceFound {
    /// Measures each case on a fresh rig from `make` (the rig and its link's faults).
    pub fn measure(
        mut make: impl FnMut() -> (Rig, motion_link::sim::SimFaults),
        online_within: Duration,
    ) -> Self {
        let mut found = |lag: Option<IoLag>| {
            let (mut rig, faults) = make();
            if let Some(lag) = lag {
                rig.stamp_io(lag);
            }
            silence_found_after(&mut rig, &faults, online_within)
        };
        Self {
            today: found(None),
            prompt: found(Some(PROMPT)),
            late: found(Some(LATE_WRITES)),
            starved: found(Some(STARVED)),
        }
    }

    /// Prompt stamps cost at most two ticks over today's bound; late writes at most `late`
    /// more, a starved I/O side at most `starved` more (each board's reasons beside its
    /// call).
    pub fn assert_within(&self, late: Duration, starved: Duration) {
        let today = self.today;
        assert!(
            self.prompt <= today + 2 * TICK,
            "{:?} vs {today:?}",
            self.prompt
        );
        assert!(self.late <= today + late, "{:?} vs {today:?}", self.late);
        assert!(
            self.starved <= today + starved,
            "{:?} vs {today:?}",
            self.starved
        );
    }
}

/// One tick of the rigs (1 kHz).
pub const TICK: Duration = Duration::from_millis(1);
