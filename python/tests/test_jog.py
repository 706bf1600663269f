"""Jogs: the deadman renewal while the program reads, the stop when the block ends, and
the server's own deadman when the program stops calling into the client."""

from __future__ import annotations

import time

import pytest

import motiond
from motiond import AxisMode

# The conveyor: ±100000 mm of travel, 200 mm/s, so a jog never meets a limit.
AXIS = "conveyor"
SPEED = 20.0


def read_for(client: motiond.Client, seconds: float) -> motiond.AxisStatus:
    """Reads every frame for ``seconds``; returns the conveyor's state in the last one."""
    conveyor = client.axis(AXIS)
    deadline = time.monotonic() + seconds
    for frame in client.frames():
        if time.monotonic() >= deadline:
            state = conveyor.state(frame)
            del frame
            return state
    raise AssertionError("frames ended")  # pragma: no cover


def test_jog_is_renewed_while_reading_and_stops_on_exit(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    deadman = client.command_timeout
    assert deadman > 0
    with conveyor.jog(SPEED) as jog:
        # Four deadman periods: without renewals the server would have stopped it.
        state = read_for(client, 4 * deadman)
        assert state.mode is AxisMode.RAMP_VELOCITY
        assert state.moving and not state.deadman_expired
        assert state.velocity == pytest.approx(SPEED, rel=0.05)
        assert jog.refused is None
        assert jog.renewals >= 4  # every third of the deadman: about 12 in 4 periods
    stopped = conveyor.wait_until_stopped(timeout=5.0)
    state = conveyor.state(stopped)
    del stopped
    assert state.mode is AxisMode.HOLD
    assert state.velocity == 0.0
    assert not state.deadman_expired  # stopped by the jog's own stop, not the deadman
    assert not jog.active


def test_jog_stops_when_the_block_raises(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    with pytest.raises(KeyError):
        with conveyor.jog(-SPEED):
            read_for(client, 0.3)
            raise KeyError("something went wrong in the program")
    state = conveyor.state(conveyor.wait_until_stopped(timeout=5.0))
    assert state.mode is AxisMode.HOLD and not state.moving


def test_keep_alive_renews_without_reading(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    with conveyor.jog(SPEED) as jog:
        deadline = time.monotonic() + 3 * client.command_timeout
        while time.monotonic() < deadline:
            client.keep_alive()
            time.sleep(0.01)
        state = conveyor.state()
        assert state.moving and not state.deadman_expired
        assert jog.renewals >= 3


def test_server_deadman_stops_a_jog_that_is_not_renewed(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    jog = conveyor.jog(SPEED)
    try:
        # The program "hangs": no call into the client for three deadman periods.
        time.sleep(3 * client.command_timeout)
        state = conveyor.state()
        assert state.deadman_expired, state
        assert jog.expired  # and the jog does not set the axis moving again
        assert conveyor.state(conveyor.wait_until_stopped(timeout=5.0)).velocity == 0.0
        state = read_for(client, 2 * client.command_timeout)
        assert not state.moving and state.deadman_expired
        jog.set(SPEED)  # an explicit new goal starts it again
        assert not jog.expired
        assert read_for(client, 0.5).moving
    finally:
        jog.stop()


def test_set_changes_a_running_jog(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    with conveyor.jog(SPEED) as jog:
        jog.set(2 * SPEED)
        state = read_for(client, 1.0)
        assert state.velocity == pytest.approx(2 * SPEED, rel=0.05)


def test_refused_jog_raises_and_never_runs(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    conveyor.stop()
    conveyor.wait_until_stopped(timeout=5.0)
    with pytest.raises(motiond.VelocityLimit):
        conveyor.jog(1e6)
    state = read_for(client, 0.2)
    assert not state.moving and state.mode is AxisMode.HOLD


def test_a_dropped_jog_stops_its_axis(client: motiond.Client) -> None:
    conveyor = client.axis(AXIS)
    jog = conveyor.jog(SPEED)
    read_for(client, 0.2)
    del jog  # garbage collected at once: its finaliser stops the axis
    state = conveyor.state(conveyor.wait_until_stopped(timeout=5.0))
    assert not state.deadman_expired and state.mode is AxisMode.HOLD


def test_closing_the_client_stops_its_jogs(server) -> None:
    other = motiond.Client(server.name, timeout=5.0)
    jog = other.axis(AXIS).jog(SPEED)
    read_for(other, 0.2)
    other.close()
    assert not jog.active
    with motiond.Client(server.name, timeout=5.0) as watcher:
        state = watcher.axis(AXIS).state(watcher.axis(AXIS).wait_until_stopped(timeout=5.0))
        assert not state.deadman_expired
