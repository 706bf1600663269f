"""A Python client streams as the README shows, under real timing (issue 39).

The client claims ``aim`` (the QuadQuad2Drv's turret and the SPI_motor's focus stepper: two
boards) and streams positions with :meth:`~motiond.stream.SetpointStream.run_each_tick`, a
0.5 Hz cosine from rest peaking at 44 % of each axis's ``max_velocity`` (and at most 44 % of
its ``max_accel``), with ``stream_limit = "abort"``, for 10 s while two busy loops keep both
cores of the machine loaded. A client not in SCHED_FIFO answers some frames late; the server
applies every setpoint on its own time (the stream's delay grows instead) and judges it by
the setpoints' own ticks, so nothing is clamped, nothing aborts and every setpoint sent is
applied or counted late.

``MOTIOND_STREAM_RUNS=N`` repeats the run N times (the issue's 10 of 10: by hand).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from typing import Iterator, List

import pytest

import motiond
from motiond import GroupMotion, StreamState

RUNS = int(os.environ.get("MOTIOND_STREAM_RUNS", "1"))
SHARE = 0.44
FREQUENCY = 0.5
DURATION = 10.0


@pytest.fixture()
def busy_loops() -> Iterator[None]:
    """Two processes spinning for as long as the test runs."""
    loops = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)
    ]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def _limits(client: motiond.Client, name: str) -> List[float]:
    info = client.axis(name).info
    return [float(info.max_velocity), float(info.max_accel)]


@pytest.mark.parametrize("run", range(RUNS))
def test_a_sine_at_44_percent_streams_whole_beside_two_busy_loops(
    client: motiond.Client, busy_loops: None, run: int
) -> None:
    aim = client.group("aim")
    assert aim.stream_limit == "abort"
    assert aim.axes == ["turret", "focus"]
    omega = 2.0 * math.pi * FREQUENCY
    amplitudes = []
    for name in aim.axes:
        max_velocity, max_accel = _limits(client, name)
        amplitudes.append(min(SHARE * max_velocity / omega, SHARE * max_accel / omega**2))
    aim.wait_stopped(timeout=10.0)
    tick_hz = client.tick_hz
    with aim.stream("position") as stream:
        frame = client.latest()
        start = [frame.axis(client.axis(name).index).position for name in aim.axes]
        first = frame.tick + 1
        del frame

        def cosine(frame: motiond.Frame) -> List[float]:
            # The values are for the setpoint's own tick: the path does not depend on when
            # this client got to run.
            t = (frame.tick + stream.lead - first) / tick_hz
            return [
                p0 + a * (1.0 - math.cos(omega * max(t, 0.0)))
                for p0, a in zip(start, amplitudes)
            ]

        stream.run_each_tick(cosine, duration=DURATION)
        final = stream.wait_applied(timeout=5.0)
        assert final.stream is StreamState.STREAMING, final
    assert final.motion is GroupMotion.MOVING, final
    assert final.clamped == 0, final
    assert final.applied + final.late == stream.sent, (final, stream.sent)
    assert final.refused == 0 and final.early == 0, final
    assert stream.sent > DURATION * tick_hz / 4, (stream.sent, final)
    assert final.stream_delay <= aim.stream_buffer, final
    print(
        f"run {run}: sent {stream.sent}, applied {final.applied}, late {final.late}, "
        f"delay {final.stream_delay} ticks, skipped frames {stream.skipped}"
    )
