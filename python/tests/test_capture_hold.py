"""Hold and resume of an axis's own move, and capture and trigger signals with their
events, against live motiond servers on the simulated robot (issue 29 items 4 and 5).

The session's server holds ``x`` (a Trinamic pack: the server stops the ramp at its
acceleration and sends it again) and ``feeder`` (the QSB-M pauses its own move with
COMMAND 6 and resumes it with COMMAND 7). A second server runs the robot with the
feeder's io0 as a camera trigger at its index and at 25 mm, which also captures the count
at every index (MDR1 B4 "Trigger/Capture on Index": every 20 mm of its encoder)."""

from __future__ import annotations

import os
from typing import Iterator

import pytest

import motiond

from conftest import Server, start_server

CAMERA_SIGNALS = """[[signal]]
name = "probe"
device = "feeder_qsb"
pin = "capture"
kind = "capture"

[[signal]]
name = "camera"
device = "feeder_qsb"
pin = "trigger"
kind = "trigger"

"""


def with_a_camera(text: str) -> str:
    """config/sim.toml with the feeder's jam sensor (io0) replaced by a camera trigger."""
    start = text.index('[[signal]]\nname = "feeder_jam"')
    end = text.index("\n[[", start + 1) + 1
    text = text[:start] + CAMERA_SIGNALS + text[end:]
    device = 'name = "feeder_qsb"\n'
    assert device in text
    return text.replace(
        device, device + 'trigger_on = ["match", "index"]\ncompare_position = 25.0\n', 1
    )


@pytest.fixture(scope="module")
def camera_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("camera")
    instance = start_server(tmp, f"pytest-camera-{os.getpid()}", with_a_camera)
    yield instance
    status = instance.stop()
    assert status == 0, f"motiond exited with {status}:\n{instance.log_text()}"


@pytest.mark.parametrize("name", ["x", "feeder"])
def test_a_move_is_held_on_its_way_and_resumed_to_its_target(
    client: motiond.Client, name: str
) -> None:
    axis = client.axis(name)
    assert axis.supports(motiond.CommandKind.HOLD)
    with pytest.raises(motiond.NotMoving, match="no position move to hold"):
        axis.hold()
    start = axis.state().position
    info = axis.info
    goal = start + 40.0 if start + 40.0 <= info.max else start - 40.0
    axis.ramp_to(goal, 20.0, 0.0)
    client.wait_frames("move", 5.0, lambda frame: abs(axis.state(frame).position - start) > 5.0)
    axis.hold()
    frame = client.wait_frames(
        "come to rest, held",
        5.0,
        lambda frame: axis.state(frame).held and axis.state(frame).mode == motiond.AxisMode.HOLD,
    )
    held_at = axis.state(frame).position
    del frame
    assert abs(held_at - goal) > 1.0, "held short of its target"
    axis.resume()
    assert not axis.state().held
    frame = axis.wait_until_arrived(timeout=15.0)
    assert axis.state(frame).position == pytest.approx(goal, abs=0.05)
    del frame
    with pytest.raises(motiond.NotMoving):
        axis.resume()


def test_captures_and_trigger_pulses_are_events_with_their_tick(camera_server: Server) -> None:
    with motiond.Client(camera_server.name, timeout=5.0) as client:
        client.wait_ready(timeout=10.0)
        probe, camera = client.signal("probe"), client.signal("camera")
        assert (probe.kind, camera.kind) == (motiond.SignalKind.CAPTURE, motiond.SignalKind.TRIGGER)
        assert probe.unit == "mm"
        assert camera.value() == pytest.approx(25.0), "the compare position, in mm"
        seen, pulses = probe.sequence(), camera.sequence()
        feeder = client.axis("feeder")
        accepted = feeder.ramp_to(50.0)
        first = probe.wait_event(seen, timeout=10.0)
        assert first.value == pytest.approx(20.0, abs=0.05), first
        assert first.tick > accepted.tick and first.missed == 0
        second = probe.wait_event(first.sequence, timeout=10.0)
        assert second.value == pytest.approx(40.0, abs=0.05), second
        feeder.wait_until_arrived(timeout=10.0)
        # The index at 20 mm, the match at 25 mm, the index at 40 mm.
        status = camera.wait_for(lambda s: s.events_since(pulses) == 3, timeout=5.0)
        assert status.event_tick > accepted.tick
        camera.set_value(30.0)
        camera.wait_for(30.0, timeout=5.0)
        with pytest.raises(motiond.NotAnOutput):
            probe.set_value(1.0)
        with pytest.raises(motiond.WaitTimeout):
            probe.wait_event(probe.sequence(), timeout=0.2)
        feeder.ramp_to(0.0)
        feeder.wait_until_arrived(timeout=10.0)
