"""Frames from Python: every tick in order at the tick rate, zero-copy views and NumPy
arrays, the borrow limit, and the example that reads 1000 consecutive frames."""

from __future__ import annotations

import ctypes
import subprocess
import sys
import time
from pathlib import Path

import numpy
import pytest

import motiond
from motiond import ipc
from motiond.frames import Frame, LatestCache

from conftest import Server


def wait_stats(client: motiond.Client, at_tick: int) -> ipc.ServerStats:
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline:
        stats = client.stats()
        if stats is not None and stats.tick >= at_tick:
            return stats
        client.next_frame()
    raise AssertionError(f"no server stats at or after tick {at_tick}")


def test_every_frame_in_order_at_the_tick_rate(client: motiond.Client) -> None:
    period_ns = 1_000_000_000 // client.tick_hz
    before = wait_stats(client, 0)
    frames = []
    for frame in client.frames():
        frames.append((frame.tick, frame.time_ns, frame.publish_ns))
        if len(frames) == 500:
            break
    del frame
    after = wait_stats(client, frames[-1][0] + 1)
    gaps = 0
    for (tick, time_ns, publish_ns), (next_tick, next_time, _) in zip(frames, frames[1:]):
        assert next_tick > tick, "ticks only go forward"
        # The frame's time is its tick's deadline: exactly one period per tick.
        assert next_time - time_ns == (next_tick - tick) * period_ns
        assert publish_ns >= time_ns
        gaps += next_tick != tick + 1
    # A missing tick is one the server skipped (it overran) or could not send; none was
    # published and lost on the way to this client.
    assert gaps <= (after.overruns - before.overruns) + (after.frames_lost - before.frames_lost)


def test_views_and_numpy_arrays_share_the_sample(client: motiond.Client) -> None:
    frame = client.latest()
    base = ctypes.addressof(frame.payload)
    positions = frame.positions()
    velocities = frame.velocities()
    assert positions.shape == (frame.axis_count,) == (18,)
    axes_at = base + ipc.MotionFrame.axes.offset
    assert positions.ctypes.data == axes_at + ipc.AxisState.position.offset
    assert velocities.ctypes.data == axes_at + ipc.AxisState.velocity.offset
    assert positions.strides == (ctypes.sizeof(ipc.AxisState),)
    for index, axis in enumerate(frame.axes):
        assert ctypes.addressof(axis) == axes_at + index * ctypes.sizeof(ipc.AxisState)
        assert positions[index] == axis.position and velocities[index] == axis.velocity
    assert not positions.flags.writeable
    with pytest.raises(ValueError):
        positions[0] = 1.0
    raw = frame.axis_array("raw_counts")
    assert raw.dtype == numpy.int64 and raw[4] == frame.axis(4).raw_counts
    assert frame.signal_array("value")[3] == frame.signal(3).value
    with pytest.raises(ValueError, match="no numeric field"):
        frame.axis_array("claimed_by")
    # The array alone keeps its sample borrowed once the frame object is gone: with it
    # and one more frame held, a third cannot be borrowed (iceoryx2 allows two)...
    del frame, axis
    held = client.next_frame()
    with pytest.raises(motiond.FramesHeld):
        client.next_frame()
    # ...and dropping the array gives the sample back.
    del positions, velocities, raw
    assert client.next_frame().tick > held.tick
    del held


def test_copies_are_detached_and_release_gives_back(client: motiond.Client) -> None:
    with client.latest() as frame:
        copy = frame.copy()
        assert copy.tick == frame.tick
        assert bytes(copy) == bytes(frame.payload)
    with pytest.raises(ValueError, match="released"):
        frame.payload
    copy.tick = 0  # a copy is private and writable
    assert copy.tick == 0


def test_holding_too_many_frames_is_a_clear_error(client: motiond.Client) -> None:
    first = client.next_frame()
    second = client.next_frame()
    with pytest.raises(motiond.FramesHeld, match="frame.copy"):
        client.next_frame()
    del first
    third = client.next_frame()
    assert third.tick > second.tick
    del second, third


def test_the_example_moves_an_axis_and_reads_1000_consecutive_frames(
    server: Server, repo: Path
) -> None:
    example = repo / "python" / "examples" / "move_and_read.py"
    result = subprocess.run(
        [sys.executable, str(example), "--server", server.name, "--axis", "x"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "read 1000 frames" in result.stdout
    assert "every published frame was read, in order" in result.stdout


class _FakeSample:
    """What a LatestCache needs of an iceoryx2 sample: its payload's address, delete()."""

    def __init__(self, tick: int) -> None:
        frame = motiond.ipc.MotionFrame()
        frame.tick = tick
        self._buffer = ctypes.create_string_buffer(bytes(frame), ctypes.sizeof(frame))
        self.payload_ptr = ctypes.addressof(self._buffer)
        self.deleted = False

    def delete(self) -> None:
        self.deleted = True


class _FakeSubscriber:
    def __init__(self, samples: list) -> None:
        self.samples = samples

    def has_samples(self) -> bool:
        return bool(self.samples)

    def receive(self) -> _FakeSample:
        return self.samples.pop(0)


def test_a_released_newest_frame_is_not_handed_out_again() -> None:
    # Regression: `with client.latest() as f: ...` then `client.latest()` within the same
    # tick returned the released frame (ValueError on its payload) instead of waiting.
    sample = _FakeSample(7)
    cache = LatestCache(_FakeSubscriber([sample]), motiond.ipc.MotionFrame, "test", wrap=Frame)
    newest = cache.refresh()
    assert newest is not None and newest.tick == 7
    newest.release()
    assert sample.deleted
    assert cache.refresh() is None
    later = _FakeSample(8)
    cache._subscriber.samples.append(later)
    assert cache.refresh().tick == 8
