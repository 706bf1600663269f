//! The robot's black box: its journal replayed from the start and, from the snapshots of
//! the engine's state in it, from the middle of a ring that wrapped.

use motion_blackbox::ReplayError;
use motion_blackbox::record::Kind;

use super::*;

/// Offset of the first byte after the stamp of the first `LinkRx` record in `records`
/// with at least `min` bytes of data, and its data length.
fn first_rx(records: &[u8], min: usize) -> Option<(usize, usize)> {
    first_where(records, |kind, len| {
        kind == Kind::LinkRx as u8 && len >= 8 + min
    })
    .map(|(at, len)| (at + 8, len - 8))
}

/// Offset of the payload of the first record in `records` whose kind byte and payload
/// length pass `wanted`, and its length.
fn first_where(records: &[u8], wanted: impl Fn(u8, usize) -> bool) -> Option<(usize, usize)> {
    let mut at = 0;
    while at + 6 <= records.len() {
        let len = u32::from_le_bytes(records[at + 2..at + 6].try_into().ok()?) as usize;
        if wanted(records[at], len) {
            return Some((at + 6, len));
        }
        at += 6 + len;
    }
    None
}

/// The black box (docs/ARCHITECTURE.md "The black box"): the scripted robot's journal —
/// four boards, moves, jogs, a home, an e-stop and a reset — replayed through drivers and
/// an engine built anew from the same config gives every frame, every byte sent and every
/// reply again; one byte changed in what a board said is found at the tick it was said.
#[test]
fn the_robots_journal_replays_frame_for_frame_and_one_changed_byte_is_found() {
    let mut robot = Robot::new();
    run(&mut robot, 0, 6000, |_| {});
    let recording = Recording::of(&robot.ring.ticks());
    assert_eq!(recording.ticks.len(), 6000);
    let replayed = replay(&robot.config, &recording).expect("the same frames");
    assert_eq!((replayed.first, replayed.ticks), (0, 6000));

    // Journal tick k is the engine's tick k - 1 (the first two steps are both tick 0).
    let changed_at = 3000;
    let mut changed = recording.clone();
    let (at, len) = first_rx(&changed.ticks[changed_at], 4).expect("a reply at tick 3000");
    changed.ticks[changed_at][at + len / 2] ^= 0x5a;
    match replay(&robot.config, &changed) {
        Err(ReplayError::Diverged { tick, what }) => {
            assert!(
                (changed_at as u64 - 1..changed_at as u64 + 200).contains(&tick),
                "diverged at tick {tick} ({what}), the byte was changed at {}",
                changed_at - 1
            );
        }
        other => panic!("a changed reply byte must diverge: {other:?}"),
    }

    // A ring that wrapped: the first 1500 ticks gone, the replay starts from the snapshot
    // journaled at tick 2000 and gives every later frame, byte and reply again.
    let wrapped = dropped(&recording, 1500);
    let replayed = replay(&robot.config, &wrapped).expect("the same frames from the snapshot");
    assert_eq!((replayed.first, replayed.ticks), (2000, 4000));
    // ... and finds a changed byte after it.
    let mut changed = dropped(&recording, 1500);
    let (at, len) = first_rx(&changed.ticks[3000 - 1500], 4).expect("a reply at tick 3000");
    changed.ticks[3000 - 1500][at + len / 2] ^= 0x5a;
    assert!(
        matches!(
            replay(&robot.config, &changed),
            Err(ReplayError::Diverged { tick, .. }) if (2999..3200).contains(&tick)
        ),
        "a changed reply byte after the snapshot must diverge"
    );

    // A wrapped ring with no snapshot left (its last one was at tick 5000) is refused, not
    // misread.
    let late = dropped(&recording, 5001);
    assert!(matches!(
        replay(&robot.config, &late),
        Err(ReplayError::NotFromStart { first: 5001 })
    ));

    // A snapshot that does not decode is said to be one.
    let mut damaged = dropped(&recording, 1500);
    let snapshot_at = 2000 - 1500;
    let (at, _) = first_of(&damaged.ticks[snapshot_at], Kind::Snapshot).expect("a snapshot");
    damaged.ticks[snapshot_at].truncate(at + 8);
    let len = damaged.ticks[snapshot_at].len();
    let header = at - 6;
    damaged.ticks[snapshot_at][header + 2..header + 6]
        .copy_from_slice(&u32::try_from(len - at).unwrap().to_le_bytes());
    assert!(matches!(
        replay(&robot.config, &damaged),
        Err(ReplayError::Snapshot { tick: 2000, .. })
    ));
}

/// `recording` with its first `ticks` ticks gone, as a ring that wrapped saves it.
pub(super) fn dropped(recording: &Recording, ticks: usize) -> Recording {
    let mut late = recording.clone();
    late.ticks.drain(..ticks);
    late.metadata
        .insert("dropped_ticks".into(), ticks.to_string());
    late
}

/// Offset of the payload of the first record of `kind` in `records`, and its length.
fn first_of(records: &[u8], kind: Kind) -> Option<(usize, usize)> {
    first_where(records, |byte, _| byte == kind as u8)
}

/// The journal's snapshots: one every 1000 ticks, each the state the replay reaches
/// there (checked by the replay from the start above), small enough for the journal's
/// queue many times over.
#[test]
fn the_journal_holds_a_snapshot_every_thousand_ticks() {
    let mut robot = Robot::new();
    run(&mut robot, 0, 3500, |_| {});
    let recording = Recording::of(&robot.ring.ticks());
    let with_snapshot: Vec<usize> = recording
        .ticks
        .iter()
        .enumerate()
        .filter_map(|(i, ticks)| first_of(ticks, Kind::Snapshot).map(|(_, len)| (i, len)))
        .map(|(i, len)| {
            assert!(
                len > 1000 && len < (1 << 20) / 4,
                "a snapshot of {len} bytes"
            );
            i
        })
        .collect();
    assert_eq!(with_snapshot, [1000, 2000, 3000]);
}
