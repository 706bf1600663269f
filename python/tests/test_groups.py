"""Groups against a live motiond on the simulated robot (``config/sim.toml``: ``arm``,
``gantry``, ``base``): description, lines and trajectories, refusals naming the point and
the axis, hold/resume/feed/cancel/stop, claims between two clients, setpoint streams and
the closed-loop example.

No assertion here is on timing: waits are generous, and the moves are slow on purpose.
On the real-time simulation the gantry's boards lag the path by more than its
``path_tolerance`` (1 mm) at higher speeds (x on the SIXpack from about 20 % of its
``max_velocity``, lift on the QuadQuad2Drv from about 50 %), so the lines here run at 10 %
and move x by half a millimetre."""

from __future__ import annotations

import math
import subprocess
import sys
import time
from typing import Callable, List, Tuple

import iceoryx2 as iox2
import pytest

import motiond
from motiond import GroupAbort, GroupMotion, StreamMode, StreamState, ipc
from motiond.groupstate import aborted_error

from conftest import REPO, Server

GANTRY = ["x", "feeder", "lift"]


def positions(client: motiond.Client, group: motiond.Group) -> List[float]:
    frame = client.latest()
    return [frame.axis(index).position for index in group.axis_indices]


#: Ticks the axes must stay at rest before a test starts a motion or a stream: a wheel's
#: board PID still settling after a stop moves again for a moment (its measured speed above
#: the QuadQuad2Drv's standstill step), and the server rightly refuses with ``GroupBusy``.
SETTLED_TICKS = 100


def at_rest(client: motiond.Client, group: motiond.Group) -> List[float]:
    """Waits until the group's axes are at rest and stay so for :data:`SETTLED_TICKS`;
    their positions."""
    group.wait_stopped(timeout=20.0)
    indices = group.axis_indices
    since = [client.latest().tick]

    def settled(frame: motiond.Frame) -> bool:
        if any(frame.axis(i).flags & motiond.AxisFlags.MOVING for i in indices):
            since[0] = frame.tick
        return frame.tick - since[0] >= SETTLED_TICKS

    client.wait_frames("stay at rest", 20.0, settled, subject=f"the axes of group {group.name}")
    return positions(client, group)


def within(value: float, low: float, high: float) -> float:
    return min(max(value, low), high)


def nearby_goal(client: motiond.Client, gantry: motiond.Group) -> List[float]:
    """A goal a little away from where the gantry is, inside every axis's travel."""
    x, feeder, lift = at_rest(client, gantry)
    infos = [client.axis(name).info for name in GANTRY]
    steps = [0.5, 15.0, 4.0]
    goal = []
    for value, step, info in zip((x, feeder, lift), steps, infos):
        target = value + step if value + step <= info.max - 1.0 else value - step
        goal.append(within(target, info.min + 1.0, info.max - 1.0))
    return goal


def slow_trajectory(
    client: motiond.Client, gantry: motiond.Group, seconds: float = 5.0
) -> Tuple[List[float], List[List[float]]]:
    """1024 points starting 0.5 s ahead: feeder and lift on a half cosine, x still."""
    x, feeder, lift = at_rest(client, gantry)
    direction = 1.0 if feeder < 500.0 else -1.0
    up = 1.0 if lift < 150.0 else -1.0
    times, rows = [], []
    for point in range(ipc.MAX_PATH_POINTS):
        phase = (1.0 - math.cos(math.pi * point / (ipc.MAX_PATH_POINTS - 1))) / 2.0
        times.append(0.5 + seconds * point / (ipc.MAX_PATH_POINTS - 1))
        rows.append([x, feeder + direction * 20.0 * phase, lift + up * 4.0 * phase])
    return times, rows


# --- description -------------------------------------------------------------------------


def test_groups_and_their_description(client: motiond.Client) -> None:
    assert [group.name for group in client.groups] == ["arm", "gantry", "base", "aim"]
    arm, gantry, base = client.group("arm"), client.group("gantry"), client.group("base")
    assert arm.axes == ["x", "y", "z", "a", "b", "c"]
    assert gantry.axes == GANTRY
    assert gantry.axis_indices == [client.axis(name).index for name in GANTRY]
    assert base.axes == ["wheel_left", "wheel_right"]
    assert gantry.path_tolerance == {"x": 5.0, "feeder": 1.0, "lift": 2.0}
    assert gantry.goal_tolerance == {"x": 0.01, "feeder": 0.1, "lift": 0.02}
    assert arm.goal_time_tolerance == pytest.approx(1.0)
    assert (base.stream_limit, base.stream_timeout, base.stream_buffer) == ("clamp", 50, 3)
    assert gantry.info.text("name") == "gantry"
    with pytest.raises(motiond.NoSuchGroup, match=r'no group named "legs".*arm, gantry, base, aim'):
        client.group("legs")

    frame = client.latest()
    assert frame.group_count == 4
    state = base.state(frame)
    assert state.tick == frame.tick and state.name == "base"
    assert isinstance(state.motion, GroupMotion) and isinstance(state.stream, StreamState)
    assert state.abort_axis is None or state.abort_axis in base.axes
    del frame


# --- lines and trajectories --------------------------------------------------------------


def test_a_line_ends_done_with_every_axis_within_its_goal_tolerance(
    client: motiond.Client,
) -> None:
    gantry = client.group("gantry")
    goal = nearby_goal(client, gantry)
    started = gantry.move_to(dict(zip(GANTRY, goal)), velocity_scale=0.1)
    assert started.path_id > 0
    frame = gantry.wait_done(timeout=60.0)
    state = gantry.state(frame)
    assert state.motion is GroupMotion.DONE and state.abort is GroupAbort.NONE
    assert state.path_id == started.path_id and state.owner == int(client.id)
    assert state.kind is ipc.PathKind.LINE and state.duration > 0.0
    tolerance = gantry.goal_tolerance
    for name, index, target in zip(GANTRY, gantry.axis_indices, goal):
        error = abs(frame.axis(index).position - target)
        assert error <= tolerance[name] + 1e-9, f"{name} ended {error} from {target}"
    del frame


def test_malformed_paths_are_refused_by_the_client(client: motiond.Client) -> None:
    gantry = client.group("gantry")
    here = positions(client, gantry)
    with pytest.raises(motiond.BadPath, match="3 axes"):
        gantry.move_to(here[:2])
    with pytest.raises(motiond.BadPath, match="missing"):
        gantry.move_to({"x": 1.0, "lift": 2.0})
    with pytest.raises(motiond.BadPath, match=r"velocity_scale 1.5 outside \(0, 1\]"):
        gantry.move_to(here, velocity_scale=1.5)
    with pytest.raises(motiond.BadPath, match="2 rows; the path has 3 points"):
        gantry.follow([0.5, 1.0, 1.5], [here, here])
    with pytest.raises(motiond.BadPath, match=r"positions\[1\] has 2 values"):
        gantry.follow([0.5, 1.0], [here, here[:2]])
    with pytest.raises(motiond.BadPath, match="1..1024 points"):
        gantry.follow([0.5 + i for i in range(1025)], [here] * 1025)
    with pytest.raises(motiond.BadPath, match="accelerations need velocities"):
        gantry.follow([0.5], [here], accelerations=[[0.0] * 3])
    with pytest.raises(motiond.BadPath):
        gantry.follow([0.5], "abc")
    numpy = pytest.importorskip("numpy")
    with pytest.raises(motiond.BadPath, match=r"shape \(2, 2\)"):
        gantry.follow([0.5, 1.0], numpy.zeros((2, 2)))


def test_a_refused_trajectory_names_the_point_and_the_axis(client: motiond.Client) -> None:
    gantry = client.group("gantry")
    x, feeder, lift = at_rest(client, gantry)
    times = [0.5 + 0.2 * point for point in range(6)]
    rows = [[x, feeder, lift] for _ in times]
    rows[3] = [x, 2000.0, lift]  # the feeder's travel ends at 1000 mm
    with pytest.raises(motiond.OutOfRange) as refused:
        gantry.follow(times, rows)
    error = refused.value
    assert (error.point, error.axis) == (3, "feeder")
    assert (error.value, error.limit, error.unit) == (2000.0, 1000.0, "mm")
    assert "point 3, axis feeder, 2000 mm against the limit 1000 mm" in str(error)
    assert str(error).startswith("run on group gantry refused: position outside")

    with pytest.raises(motiond.PathTimes) as refused_times:
        gantry.follow([0.5, 0.4], [[x, feeder, lift]] * 2)
    assert refused_times.value.point == 1

    with pytest.raises(motiond.PathStart) as refused_start:
        gantry.follow([0.0], [[x, feeder, within(lift + 10.0, 1.0, 299.0)]])
    assert (refused_start.value.point, refused_start.value.axis) == (0, "lift")
    assert refused_start.value.value == pytest.approx(10.0, abs=0.1)
    # Nothing of it started.
    assert not gantry.state().active


def test_hold_resume_feed_and_done(client: motiond.Client) -> None:
    numpy = pytest.importorskip("numpy")
    gantry = client.group("gantry")
    times, rows = slow_trajectory(client, gantry)
    started = gantry.follow(numpy.array(times), numpy.array(rows))
    client.wait_frames(
        "run its path", 10.0, lambda f: gantry.state(f).time > 1.0, since=started.tick
    )
    gantry.set_feed(0.5)
    assert gantry.state().feed_set == 0.5
    gantry.hold()
    frame = gantry.wait_held(timeout=20.0)
    held = gantry.state(frame)
    del frame
    assert held.motion is GroupMotion.HELD and held.feed == 0.0
    assert 0.0 < held.time < held.duration
    for _ in range(20):
        client.next_frame()
    assert gantry.state().time == held.time  # path time stands still while held
    gantry.resume()
    gantry.set_feed(1.0)
    frame = gantry.wait_done(timeout=60.0)
    done = gantry.state(frame)
    del frame
    assert done.path_id == started.path_id and done.kind is ipc.PathKind.TRAJECTORY
    assert done.point == ipc.MAX_PATH_POINTS - 1 or done.time >= done.duration
    with pytest.raises(motiond.NotMoving, match="hold on group gantry refused"):
        gantry.hold()


def test_cancel_and_stop_abort_the_wait_with_their_reason(client: motiond.Client) -> None:
    gantry = client.group("gantry")
    for end, reason in ((gantry.cancel, GroupAbort.CANCELLED), (gantry.stop, GroupAbort.STOPPED)):
        times, rows = slow_trajectory(client, gantry)
        started = gantry.follow(times, rows)
        client.wait_frames(
            "run its path", 10.0, lambda f: gantry.state(f).time > 0.6, since=started.tick
        )
        end()
        with pytest.raises(motiond.GroupAborted) as aborted:
            gantry.wait_done(timeout=20.0)
        assert aborted.value.abort is reason and aborted.value.axis is None
        assert aborted.value.path_id == started.path_id
        assert f"aborted ({reason.text})" in str(aborted.value)
        assert gantry.state().abort is reason


def test_an_aborted_group_names_the_axis_and_the_figures(client: motiond.Client) -> None:
    # The error of a path-tolerance abort, from a GroupState as the server writes it.
    state = ipc.GroupState(
        motion=int(GroupMotion.ABORTED),
        abort=int(GroupAbort.PATH_TOLERANCE),
        abort_axis=client.axis("lift").index,
        abort_value=1.25,
        abort_limit=1.0,
        path_id=7,
    )
    error = aborted_error(client.info, "gantry", "finish its path", state, 1234)
    assert isinstance(error, motiond.WaitAborted)
    assert (error.abort, error.axis, error.value, error.limit) == (
        GroupAbort.PATH_TOLERANCE,
        "lift",
        1.25,
        1.0,
    )
    assert str(error) == (
        "group gantry will not finish its path: aborted (path-tolerance) on axis lift: "
        "1.25 mm against the limit 1 mm in tick 1234"
    )


# --- claims ------------------------------------------------------------------------------


def test_claims_keep_a_second_client_out_of_the_group(
    client: motiond.Client, server: Server
) -> None:
    base = client.group("base")
    at_rest(client, base)
    with motiond.Client(server.name, timeout=5.0) as other:
        theirs = other.group("base")
        with base.claim() as claim:
            assert claim.active
            mine = int(client.id)
            client.wait_frames(
                "show the claim",
                5.0,
                lambda f: all(int(f.axis(i).claimed_by) == mine for i in base.axis_indices),
                since=claim.accepted.tick,
            )
            with pytest.raises(motiond.ClaimedByOther) as refused:
                theirs.claim()
            assert refused.value.axis == "wheel_left"
            assert refused.value.holder == int(client.id)
            with pytest.raises(motiond.ClaimedByOther, match="run on group base refused"):
                theirs.move_to([0.0, 0.0])
            with pytest.raises(motiond.ClaimedByOther):
                theirs.stream("velocity")
            with pytest.raises(motiond.NotClaimed):
                theirs.release()
        assert not claim.active
        client.wait_frames(
            "show the claim released",
            5.0,
            lambda f: all(int(f.axis(i).claimed_by) == 0 for i in base.axis_indices),
        )
        with theirs.claim():
            with pytest.raises(motiond.ClaimedByOther):
                base.stream("velocity")


# --- streams -----------------------------------------------------------------------------


def retry_stale(attempt: Callable[[], None], tries: int = 3) -> None:
    """Runs ``attempt``; again when the stream went stale (this client stalled for the
    whole ``stream_timeout`` on a loaded machine: no fault of the server's)."""
    for left in range(tries - 1, -1, -1):
        try:
            attempt()
            return
        except motiond.GroupAborted as error:
            if error.abort is not GroupAbort.STREAM_STALE or not left:
                raise


def test_a_velocity_stream_applies_every_setpoint_sent(client: motiond.Client) -> None:
    base = client.group("base")

    def attempt() -> None:
        at_rest(client, base)
        with base.stream("velocity") as stream:
            assert stream.mode is StreamMode.VELOCITY
            assert base.state().streaming
            t0: List[int] = []

            def sine(frame: motiond.Frame) -> List[float]:
                t0.append(frame.tick) if not t0 else None
                speed = 20.0 * math.sin(2.0 * math.pi * (frame.tick + 1 - t0[0]) / 1000.0)
                return [speed, -speed]

            sent = stream.run_each_tick(sine, duration=1.0)
            final = stream.wait_applied(timeout=5.0)
        assert sent == stream.sent > 0
        # Each applied on its own time; one that reached the server more than
        # stream_buffer ticks after its tick (this client descheduled that long) is late.
        assert final.applied + final.late == stream.sent, (final, stream.skipped)
        assert (final.early, final.refused, final.clamped) == (0, 0, 0)
        assert final.stream_delay <= base.stream_buffer
        assert final.last_sequence == stream.sequence
        assert stream.applied_before_tick == 0
        assert stream.observed > 0
        after = base.state()
        assert after.stream is StreamState.IDLE and after.motion is GroupMotion.DONE
        with pytest.raises(motiond.StreamClosed):
            stream.send(client.latest().tick + 1, [0.0, 0.0])

    retry_stale(attempt)


def test_another_clients_setpoints_are_refused_and_do_not_disturb(
    client: motiond.Client, server: Server
) -> None:
    base = client.group("base")
    with motiond.Client(server.name, timeout=5.0) as other:
        # A plain iceoryx2 publisher on the other client's node: it holds no claim.
        service = (
            other.node.service_builder(
                iox2.ServiceName.new(ipc.service_name(server.name, "setpoints"))
            )
            .publish_subscribe(ipc.Setpoint)
            .open()
        )
        intruder = service.publisher_builder().create()

        def attempt() -> None:
            at_rest(client, base)
            fastest = [0.0]

            def steady(frame: motiond.Frame) -> List[float]:
                for index in base.axis_indices:
                    fastest[0] = max(fastest[0], abs(frame.axis(index).desired_velocity))
                return [3.0, 3.0]

            with base.stream("velocity") as stream:
                stream.run_each_tick(steady, duration=0.2)
                for sequence in range(20):
                    setpoint = ipc.Setpoint(
                        schema_version=ipc.SCHEMA_VERSION,
                        group=base.index,
                        sequence=stream.sequence + 1000 + sequence,
                        for_tick=other.latest().tick + 1,
                        mode=int(StreamMode.VELOCITY),
                    )
                    setpoint.values[0] = 90.0
                    setpoint.values[1] = -90.0
                    intruder.send_copy(setpoint)
                    stream.run_each_tick(steady, duration=0.01)
                stream.run_each_tick(steady, duration=0.2)
                final = stream.wait_applied(timeout=5.0)
            assert final.refused == 20
            assert final.applied + final.late == stream.sent, final
            assert fastest[0] == pytest.approx(3.0)

        try:
            retry_stale(attempt)
        finally:
            intruder.delete()


def test_a_setpoint_that_can_never_apply_does_not_keep_a_stream_alive(
    client: motiond.Client,
) -> None:
    """Issue 40: the claimant sends its last applied sequence again every tick; the stream
    goes stale after ``stream_timeout`` ticks and the wheels stop."""
    base = client.group("base")
    at_rest(client, base)
    with base.stream("velocity") as stream:
        tick = client.latest().tick
        stream.send(tick + 2, [5.0, -5.0])
        stream.wait_applied(timeout=5.0)
        setpoint = ipc.Setpoint(
            schema_version=ipc.SCHEMA_VERSION,
            group=base.index,
            sequence=stream.sequence,
            for_tick=tick + 2,
            mode=int(StreamMode.VELOCITY),
        )
        setpoint.values[0] = 5.0
        setpoint.values[1] = -5.0
        deadline = time.monotonic() + 2.0
        state = base.state()
        while time.monotonic() < deadline:
            setpoint.for_tick = client.latest().tick + 1
            stream._publisher.send_copy(setpoint)
            state = base.state()
            if state.stream is not StreamState.STREAMING:
                break
            time.sleep(0.001)
        assert state.stream is StreamState.STALE, state
        assert state.abort is GroupAbort.STREAM_STALE, state
        assert state.applied == 1, state


def test_wait_applied_returns_when_the_last_setpoint_was_dropped_late(
    client: motiond.Client,
) -> None:
    """A client descheduled for more than ``stream_buffer`` ticks sends its last setpoint
    after its tick: the server drops it (``late``). ``wait_applied`` returns with the
    counters (every setpoint sent accounted for) instead of waiting until the stream goes
    stale and the group stops."""
    base = client.group("base")
    at_rest(client, base)
    with base.stream("velocity") as stream:
        tick = client.latest().tick
        stream.send(tick + 2, [2.0, -2.0])
        stream.wait_applied(timeout=5.0)
        # Its tick passed more than stream_buffer (3) ticks ago.
        stream.send(client.latest().tick - 10, [2.0, -2.0])
        started = time.monotonic()
        final = stream.wait_applied(timeout=5.0)
        waited = time.monotonic() - started
        assert final.stream is StreamState.STREAMING, final
        assert (final.applied, final.late) == (1, 1), final
        assert final.last_sequence == 1 and stream.sequence == 2
        # Returned with the frame that showed it dropped, long before stream_timeout
        # (50 ticks) would have ended the stream.
        assert base.state().stream is StreamState.STREAMING, waited


def test_the_closed_loop_example_runs(server: Server) -> None:
    example = REPO / "python" / "examples" / "closed_loop.py"
    for attempt in range(3):
        result = subprocess.run(
            [sys.executable, str(example), "--server", server.name, "--seconds", "2"],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
        stale = "stream-stale" in result.stderr
        if result.returncode == 0 or not stale or attempt == 2:
            break
        time.sleep(0.5)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "none before its tick, none clamped" in result.stdout
    assert "early 0, clamped 0" in result.stdout
