//! Running figures: [`ServerStats`], published about once a second on `motiond/<name>/stats`.

use iceoryx2::prelude::ZeroCopySend;

use crate::read_text;
use crate::{MAX_LINKS, NAME_LEN, SCHEMA_VERSION};

payload! {
    /// Percentiles of one latency distribution, in nanoseconds.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    #[type_name("motiond::LatencySummary")]
    pub struct LatencySummary {
        /// Number of samples.
        pub samples: u64,
        /// Median.
        pub p50_ns: u64,
        /// 99th percentile.
        pub p99_ns: u64,
        /// 99.9th percentile.
        pub p999_ns: u64,
        /// Maximum.
        pub max_ns: u64,
    }
}

payload! {
    /// Counters of one link since start.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[type_name("motiond::LinkStats")]
    pub struct LinkStats {
        /// Link name.
        pub name: [u8; NAME_LEN],
        /// Bytes received.
        pub bytes_in: u64,
        /// Bytes sent.
        pub bytes_out: u64,
        /// Replies decoded.
        pub frames: u64,
        /// Bad frames, I/O errors, timeouts.
        pub errors: u64,
        /// Successful reopens.
        pub reconnects: u64,
        /// 1 when the link is open.
        pub up: u32,
        /// Messages a link the tick runs itself (`io = "tick"`) put off to a later tick
        /// because the tick's wire-time budget was spent (saturating; 0 on other links).
        pub deferred: u32,
    }
}

impl LinkStats {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        name: [0; NAME_LEN],
        bytes_in: 0,
        bytes_out: 0,
        frames: 0,
        errors: 0,
        reconnects: 0,
        up: 0,
        deferred: 0,
    };

    /// The link name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }
}

payload! {
    /// The I/O side of one link: when bytes last went out and came in, and how often. Stamps are
    /// CLOCK_MONOTONIC ns taken by the link's I/O thread right after the transport accepted or
    /// returned the bytes; 0 when it never did.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    #[type_name("motiond::LinkIo")]
    pub struct LinkIo {
        /// CLOCK_MONOTONIC ns of the last write that moved bytes; 0: never.
        pub last_write_ns: u64,
        /// CLOCK_MONOTONIC ns of the last read that returned bytes; 0: never.
        pub last_read_ns: u64,
        /// Messages written whole (SPI: transactions).
        pub transactions: u64,
        /// Reads that returned bytes.
        pub reads: u64,
    }
}

impl LinkIo {
    /// Nothing yet.
    pub const EMPTY: Self = Self {
        last_write_ns: 0,
        last_read_ns: 0,
        transactions: 0,
        reads: 0,
    };
}

payload! {
    /// Server figures, published about once a second on `motiond/<name>/stats`.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[type_name("motiond::ServerStats")]
    pub struct ServerStats {
        /// [`SCHEMA_VERSION`] of the server.
        pub schema_version: u32,
        /// Valid entries in `links`.
        pub link_count: u32,
        /// Tick at which these figures were taken.
        pub tick: u64,
        /// CLOCK_MONOTONIC ns of that tick.
        pub time_ns: u64,
        /// Wake-up latency (actual wake − deadline) since start.
        pub wakeup: LatencySummary,
        /// Tick work time since start.
        pub work: LatencySummary,
        /// Ticks that missed their deadline since start.
        pub overruns: u64,
        /// Longest run of consecutive overruns.
        pub max_consecutive_overruns: u64,
        /// Requests answered.
        pub commands: u64,
        /// Requests refused.
        pub rejected: u64,
        /// Live client nodes at the last liveness check.
        pub clients: u32,
        /// Real-time set-up bits (`RtFlags`): bit 0 SCHED_FIFO, bit 1 memory locked, bit 2 pinned,
        /// bit 3 cpu_dma_latency held.
        pub rt_flags: u32,
        /// Per-link counters.
        pub links: [LinkStats; MAX_LINKS],
        /// Axis faults latched by the server's supervision since start.
        pub faults: u64,
        /// Ticks whose frame could not be loaned or sent, since start.
        pub frames_lost: u64,
        /// Services whose port slots are all taken now (`FullServices` bits, the `FULL_*`
        /// constants): new clients are refused there until a slot frees.
        pub full_services: u32,
        /// Times a service was found with all its slots taken, since start.
        pub full_events: u32,
        /// Info, stats and params samples that could not be loaned or sent, and tick
        /// notifications that failed, since start (a lost frame counts in `frames_lost`).
        pub publish_failures: u64,
        /// Command replies that could not be sent (the client vanished before its answer),
        /// since start.
        pub replies_lost: u64,
        /// Log reports the main thread's queue had no room for, and failed iceoryx2
        /// housekeeping (connection updates, e-stop event reads), since start.
        pub events_dropped: u64,
        /// Per link (same index as `links`): the I/O thread's stamps.
        pub link_io: [LinkIo; MAX_LINKS],
        /// Records of dead iceoryx2 nodes removed from the service root (crashed clients,
        /// clients killed while they started), since start.
        pub nodes_cleaned: u64,
        /// Black-box records the tick dropped because the recorder's queue was full, since
        /// start: a saved black box has a hole there, and a replay stops at it.
        pub blackbox_lost: u64,
        /// Paths taken from the `paths` service and dropped, since start: no room left for
        /// their node or among the claimants' paths, or their publisher gone before the
        /// tick looked (docs/SECURITY.md "Paths and setpoints no other process can starve").
        pub paths_dropped: u64,
        /// Setpoints taken from the `setpoints` service and dropped unread, since start:
        /// beyond their node's budget of the tick, or their publisher gone before the tick
        /// looked (the engine's own refusals count in `GroupState::refused`).
        pub setpoints_dropped: u64,
    }
}

impl ServerStats {
    /// Bit of `rt_flags`: the tick thread runs SCHED_FIFO.
    pub const RT_FIFO: u32 = 1 << 0;
    /// Bit of `rt_flags`: memory is locked.
    pub const RT_LOCKED: u32 = 1 << 1;
    /// Bit of `rt_flags`: the tick thread is pinned to a core.
    pub const RT_PINNED: u32 = 1 << 2;
    /// Bit of `rt_flags`: `/dev/cpu_dma_latency` is held at 0.
    pub const RT_DMA_LATENCY: u32 = 1 << 3;
    /// Bit of `full_services`: the frame service's subscriber slots.
    pub const FULL_FRAME: u32 = 1 << 0;
    /// Bit of `full_services`: the tick event's listener slots.
    pub const FULL_TICK: u32 = 1 << 1;
    /// Bit of `full_services`: the command service's client slots.
    pub const FULL_COMMAND: u32 = 1 << 2;
    /// Bit of `full_services`: the info service's subscriber slots.
    pub const FULL_INFO: u32 = 1 << 3;
    /// Bit of `full_services`: the stats service's subscriber slots.
    pub const FULL_STATS: u32 = 1 << 4;
    /// Bit of `full_services`: the params service's subscriber slots.
    pub const FULL_PARAMS: u32 = 1 << 5;
    /// Bit of `full_services`: the e-stop event's notifier slots.
    pub const FULL_ESTOP: u32 = 1 << 6;
    /// Bit of `full_services`: the paths service's publisher slots.
    pub const FULL_PATHS: u32 = 1 << 7;
    /// Bit of `full_services`: the setpoints service's publisher slots.
    pub const FULL_SETPOINTS: u32 = 1 << 8;

    /// Empty figures of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        link_count: 0,
        tick: 0,
        time_ns: 0,
        wakeup: LatencySummary {
            samples: 0,
            p50_ns: 0,
            p99_ns: 0,
            p999_ns: 0,
            max_ns: 0,
        },
        work: LatencySummary {
            samples: 0,
            p50_ns: 0,
            p99_ns: 0,
            p999_ns: 0,
            max_ns: 0,
        },
        overruns: 0,
        max_consecutive_overruns: 0,
        commands: 0,
        rejected: 0,
        clients: 0,
        rt_flags: 0,
        links: [LinkStats::EMPTY; MAX_LINKS],
        faults: 0,
        frames_lost: 0,
        full_services: 0,
        full_events: 0,
        publish_failures: 0,
        replies_lost: 0,
        events_dropped: 0,
        link_io: [LinkIo::EMPTY; MAX_LINKS],
        nodes_cleaned: 0,
        blackbox_lost: 0,
        paths_dropped: 0,
        setpoints_dropped: 0,
    };

    /// The valid link entries.
    pub fn links(&self) -> &[LinkStats] {
        &self.links[..(self.link_count as usize).min(MAX_LINKS)]
    }

    /// The I/O stamps of the valid links.
    pub fn link_io(&self) -> &[LinkIo] {
        &self.link_io[..(self.link_count as usize).min(MAX_LINKS)]
    }
}

impl Default for ServerStats {
    fn default() -> Self {
        Self::EMPTY
    }
}
