"""E-stop and reset from Python: latched, every axis stopped, goals refused, outputs in
their safe state, cleared by reset; and the e-stop event service."""

from __future__ import annotations

import motiond
from motiond import AxisFlags, AxisMode, Reason


def test_estop_stops_refuses_and_reset_clears(client: motiond.Client) -> None:
    conveyor = client.axis("conveyor")
    x = client.axis("x")
    lamp = client.signal("lamp")
    lamp.set(True)
    lamp.wait_for(True, timeout=5.0)
    jog = conveyor.jog(30.0)
    try:
        client.wait_frames(
            "move", 5.0, lambda f: bool(f.axis(conveyor.index).flags & AxisFlags.MOVING)
        )
        accepted = client.estop()
        stopped = client.wait_frames(
            "stop every axis",
            10.0,
            lambda f: f.estop_latched and not any(a.flags & AxisFlags.MOVING for a in f.axes),
            since=accepted.tick,
        )
        state = conveyor.state(stopped)
        del stopped
        assert AxisFlags.ESTOPPED in state.flags
        assert state.velocity == 0.0

        # Goals are refused with the server's reason while it is latched...
        try:
            x.position(10.0)
        except motiond.EstopLatched as refusal:
            assert refusal.reason is Reason.ESTOP_LATCHED
            assert str(refusal) == "position on axis x refused: e-stop is latched: send reset first"
        else:
            raise AssertionError("a goal was accepted during an e-stop")
        # ...the jog's renewals too: it stops renewing and says why.
        client.wait_frames("renew the jog", 2.0, lambda f: jog.refused is not None)
        assert jog.refused is Reason.ESTOP_LATCHED
        # The lamp (safe = false) went off and says it is in its safe state.
        status = lamp.wait_for(lambda s: s.safe_state and not s.on, timeout=5.0)
        assert status.value == 0.0
        # Stop is still taken.
        conveyor.stop()
    finally:
        jog.stop()

    client.reset()
    frame = client.wait_frames("clear the e-stop", 5.0, lambda f: not f.estop_latched)
    assert AxisFlags.ESTOPPED not in conveyor.state(frame).flags
    del frame
    here = x.state().position
    x.ramp_to(here + 1.0 if here < 300.0 else here - 1.0)
    x.wait_until_arrived(timeout=10.0)
    lamp.set(True)
    assert lamp.wait_for(True, timeout=5.0).on
    lamp.set(False)


def test_estop_event_latches_like_the_command(client: motiond.Client) -> None:
    client.notify_estop()
    frame = client.wait_frames("latch the e-stop", 5.0, lambda f: f.estop_latched)
    assert all(axis.mode in (AxisMode.HOLD, AxisMode.STOPPING, AxisMode.OFF) for axis in frame.axes)
    del frame
    try:
        client.axis("focus").ramp_to(10.0)
    except motiond.EstopLatched:
        pass
    else:
        raise AssertionError("a goal was accepted during an e-stop")
    client.reset()
    client.wait_frames("clear the e-stop", 5.0, lambda f: not f.estop_latched)
    client.axis("focus").ramp_to(10.0)


def test_estop_returns_once_a_frame_shows_the_latch(client: motiond.Client) -> None:
    accepted = client.estop()
    try:
        # estop() returned only after a frame of the accepting tick or later showed the
        # latch: the newest frame shows it too, with no wait.
        frame = client.latest()
        assert frame.estop_latched
        assert frame.tick >= accepted.tick
        del frame
    finally:
        client.reset()
        client.wait_frames("clear the e-stop", 5.0, lambda f: not f.estop_latched)


def test_an_estop_not_seen_is_a_timeout_that_says_what_was_accepted() -> None:
    error = motiond.EstopNotSeen(12, 0.5, None)
    assert isinstance(error, TimeoutError)
    assert isinstance(error, motiond.MotiondError)
    assert str(error) == (
        "the server accepted the e-stop in tick 12, but no frame showed it latched within "
        "0.500 s (no frame came); check the machine"
    )
    assert "newest frame: tick 40" in str(motiond.EstopNotSeen(12, 0.5, 40))
