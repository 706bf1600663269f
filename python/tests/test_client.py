"""The client against a live motiond on the simulated robot: describe, move and arrive,
refusals with the server's reasons, signals, parameters, the CLI."""

from __future__ import annotations

import math
import subprocess
import sys
import time

import pytest

import motiond
from motiond import CommandKind, Reason, ipc

from conftest import Server

# config/sim.toml, in config order.
AXES = [
    "wheel_left",
    "wheel_right",
    "lift",
    "turret",
    "x",
    "y",
    "z",
    "a",
    "b",
    "c",
    "gripper",
    "conveyor",
    "camera_pan",
    "camera_tilt",
    "focus",
    "pump_a",
    "pump_b",
    "feeder",
]
SIGNALS = ["lift_bottom", "feeder_jam", "x_ref", "supply", "lamp"]


def test_no_server_is_a_clear_error() -> None:
    with pytest.raises(motiond.NoServer, match='no motiond server named "nobody-here"'):
        motiond.Client("nobody-here", timeout=0.2)


def test_lists_axes_devices_and_signals(client: motiond.Client, server: Server) -> None:
    assert [axis.name for axis in client.axes] == AXES
    assert [signal.name for signal in client.signals] == SIGNALS
    info = client.info
    assert info.text("name") == server.name
    assert info.schema_version == ipc.SCHEMA_VERSION
    assert client.tick_hz == 1000
    assert client.command_timeout == pytest.approx(0.25)
    x = client.axis("x")
    assert (x.index, x.unit, x.device) == (4, "mm", "pack_xyz")
    assert (x.info.min, x.info.max, x.info.max_velocity, x.info.max_accel) == (0, 400, 50, 250)
    assert x.supports(CommandKind.RAMP_POSITION)
    assert not client.axis("pump_a").supports(CommandKind.POSITION)
    devices = [info.devices[i].text("name") for i in range(info.device_count)]
    assert devices == ["drive", "pack_xyz", "pack_aux", "focus_drv", "pumps", "feeder_qsb"]
    assert ipc.DeviceModel(info.devices[1].model) is ipc.DeviceModel.TMCPACK
    assert info.devices[1].model_name() == "tmcpack"
    lamp = client.signal("lamp")
    assert lamp.kind is ipc.SignalKind.DIGITAL_OUT
    assert client.signal("supply").unit == "V"
    with pytest.raises(motiond.NoSuchAxis, match='no axis named "w"'):
        client.axis("w")
    with pytest.raises(motiond.NoSuchSignal):
        client.signal("siren")


def test_state_of_an_axis(client: motiond.Client) -> None:
    state = client.axis("x").state()
    assert state.index == 4
    assert state.device_state is ipc.DeviceState.ONLINE
    assert isinstance(state.mode, ipc.AxisMode)
    assert not state.faulted and not state.stale
    assert math.isfinite(state.position)


def test_ramp_to_and_arrive(client: motiond.Client) -> None:
    x = client.axis("x")
    goal = 30.0 if abs(x.state().position - 30.0) > 5.0 else 10.0
    accepted = x.ramp_to(goal, 40.0, 200.0)
    assert accepted.tick > 0
    frame = x.wait_until_arrived(timeout=15.0)
    assert frame.tick >= accepted.tick
    state = x.state(frame)
    assert state.arrived and not state.moving
    assert state.position == pytest.approx(goal, abs=0.01)
    del frame


def test_move_to_and_arrive(client: motiond.Client) -> None:
    turret = client.axis("turret")
    goal = 20.0 if abs(turret.state().position - 20.0) > 5.0 else -20.0
    turret.position(goal)
    frame = turret.wait_until_arrived(timeout=15.0)
    assert turret.state(frame).position == pytest.approx(goal, abs=1.0)
    del frame


def test_a_replaced_goal_aborts_the_wait(client: motiond.Client) -> None:
    x = client.axis("x")
    here = x.state().position
    x.ramp_to(here + 50.0 if here < 200.0 else here - 50.0, 10.0, 100.0)
    x.stop()
    with pytest.raises(motiond.WaitAborted, match="axis x will not arrive"):
        x.wait_until_arrived(timeout=10.0)


@pytest.mark.parametrize(
    "send, refusal, reason",
    [
        (lambda c: c.axis("x").position(1e9), motiond.OutOfRange, Reason.OUT_OF_RANGE),
        (
            lambda c: c.axis("x").ramp_to(10.0, 1e6, 0.0),
            motiond.VelocityLimit,
            Reason.VELOCITY_LIMIT,
        ),
        (lambda c: c.axis("x").ramp_to(10.0, 10.0, 1e9), motiond.AccelLimit, Reason.ACCEL_LIMIT),
        (lambda c: c.axis("x").position(float("nan")), motiond.NotFinite, Reason.NOT_FINITE),
        (lambda c: c.axis("pump_a").position(1.0), motiond.Unsupported, Reason.UNSUPPORTED),
        (lambda c: c.axis("pump_a").power(1.5), motiond.PowerLimit, Reason.POWER_LIMIT),
        (lambda c: c.axis("x").release(), motiond.NotClaimed, Reason.NOT_CLAIMED),
        (lambda c: c.command(999, CommandKind.STOP), motiond.UnknownAxis, Reason.UNKNOWN_AXIS),
        (
            lambda c: c.command(99, CommandKind.SET_OUTPUT, (1.0,), ipc.Target.SIGNAL),
            motiond.UnknownSignal,
            Reason.UNKNOWN_SIGNAL,
        ),
        (lambda c: c.command(4, 99), motiond.UnknownKind, Reason.UNKNOWN_KIND),
        (
            lambda c: c.command(4, CommandKind.STOP, target=7),
            motiond.UnknownTarget,
            Reason.UNKNOWN_TARGET,
        ),
        (lambda c: c.signal("x_ref").set(True), motiond.NotAnOutput, Reason.NOT_AN_OUTPUT),
    ],
    ids=[
        "out-of-range",
        "velocity-limit",
        "accel-limit",
        "not-finite",
        "unsupported",
        "power-limit",
        "not-claimed",
        "unknown-axis",
        "unknown-signal",
        "unknown-kind",
        "unknown-target",
        "not-an-output",
    ],
)
def test_refusals_carry_the_servers_reason(client, send, refusal, reason) -> None:
    with pytest.raises(refusal) as caught:
        send(client)
    error = caught.value
    assert isinstance(error, motiond.Refused)
    assert error.reason is reason
    assert reason.message in str(error)
    assert error.tick > 0


def test_send_returns_the_raw_reply(client: motiond.Client) -> None:
    reply = client.send(4, CommandKind.STOP)
    assert reply.reason == Reason.ACCEPTED and reply.kind == CommandKind.STOP
    assert reply.axis == 4 and reply.schema_version == ipc.SCHEMA_VERSION
    refused = client.send(4, 99)
    assert refused.reason == Reason.UNKNOWN_KIND and refused.kind == 99


def test_claims_keep_other_clients_out(client: motiond.Client, server: Server) -> None:
    focus = client.axis("focus")
    focus.claim()
    try:
        state = focus.state()
        assert state.claimed and state.claimed_by == int(client.id)
        with motiond.Client(server.name, timeout=5.0) as other:
            with pytest.raises(motiond.ClaimedByOther, match="focus refused: the axis is claimed"):
                other.axis("focus").ramp_to(100.0)
            with pytest.raises(motiond.NotClaimed):
                other.axis("focus").release()
    finally:
        focus.release()
    assert not focus.state().claimed


def test_output_signal_set_and_wait(client: motiond.Client) -> None:
    lamp = client.signal("lamp")
    lamp.set(True)
    status = lamp.wait_for(True, timeout=5.0)
    assert status.on and status.raw == 1.0 and not status.pending
    assert lamp.is_on()
    lamp.set(False)
    assert lamp.wait_for(lambda s: s.value == 0.0, timeout=5.0).value == 0.0


def test_input_signals(client: motiond.Client) -> None:
    supply = client.signal("supply")
    status = supply.wait_for(lambda s: s.raw > 0, timeout=5.0)
    assert status.kind is ipc.SignalKind.ANALOG_IN
    # value = raw × scale + offset, as configured (scale 0.0454545 V per count)
    assert status.value == pytest.approx(status.raw * supply.info.scale + supply.info.offset)
    jam = client.signal("feeder_jam")
    assert jam.inverted
    state = jam.state()
    assert state.value == pytest.approx(1.0 - state.raw)


def test_machine_params(client: motiond.Client) -> None:
    params = client.params()
    assert params, "the server publishes its parameters"
    owners = {(p.owner, p.owner_name) for p in params}
    assert (ipc.ParamOwner.DEVICE, "pack_xyz") in owners
    x_params = {p.key: p for p in params if p.owner == ipc.ParamOwner.AXIS and p.owner_name == "x"}
    assert x_params, "axis x has parameters"
    assert any(p.from_config for p in x_params.values())


def test_qsb_counter_mode_in_params(client: motiond.Client) -> None:
    """The QSB's counter mode (MDR0) as the driver writes it: sim.toml leaves the defaults."""
    qsb = {
        p.key: p
        for p in client.params()
        if p.owner == ipc.ParamOwner.DEVICE and p.owner_name == "feeder_qsb"
    }
    assert qsb["count_mode"].value == "x4"
    assert qsb["count_range"].value == "free-running"
    assert qsb["index_action"].value == "none"
    assert qsb["index_sync"].value == "synchronous"
    assert not qsb["count_mode"].from_config


def test_tmcpack_power_down_and_pi_position_mode(client: motiond.Client) -> None:
    """sim.toml's QUADpack has power_down = "restore": the key among its parameters, its state
    in the description (armed, nothing loaded on a fresh start); camera_pan runs position
    targets with the pack's PI controller ($24), which holds the target once there."""
    params = {(p.owner_name, p.key): p for p in client.params()}
    assert params[("pack_aux", "power_down")].value == "restore (save; loaded after a boot)"
    assert params[("pack_aux", "power_down")].from_config
    assert params[("pack_xyz", "power_down")].value == "off (no $45)"
    assert params[("camera_pan", "position_mode")].value == "pi ($24 PI controller)"
    assert params[("camera_tilt", "position_mode")].value == "ramp ($14, $26, $23)"
    deadline = time.monotonic() + 5.0
    firmware = ""
    while time.monotonic() < deadline:
        firmware = client.info.devices[2].text("firmware")
        if firmware.endswith("PD armed"):
            break
        client.next_frame()
    assert firmware == "QUADpack V1.4.9 #1001 PD armed"
    assert client.info.devices[1].text("firmware") == "SIXpack V1.4.9 s/n 1001"
    pan = client.axis("camera_pan")
    pan.position(15.0)
    status = pan.wait_until_arrived(timeout=10.0)
    state = pan.state(status)
    assert state.position == pytest.approx(15.0, abs=0.2)
    assert not state.moving


def test_stats(client: motiond.Client) -> None:
    deadline = time.monotonic() + 3.0
    stats = client.stats()
    while stats is None and time.monotonic() < deadline:
        client.next_frame()
        stats = client.stats()
    assert stats is not None
    assert stats.schema_version == ipc.SCHEMA_VERSION
    assert stats.link_count == 4
    assert stats.links[0].text("name") == "spi0"
    assert stats.commands >= stats.rejected


def test_cli_list_and_status(server: Server) -> None:
    listed = subprocess.run(
        [sys.executable, "-m", "motiond", "list", "--server", server.name],
        capture_output=True,
        text=True,
        check=True,
    )
    for name in AXES + SIGNALS + ["pack_xyz", "tmcpack"]:
        assert name in listed.stdout
    status = subprocess.run(
        [sys.executable, "-m", "motiond", "status", "--server", server.name],
        capture_output=True,
        text=True,
        check=True,
    )
    assert status.stdout.startswith("tick ")
    assert "feeder" in status.stdout and "online" in status.stdout
    missing = subprocess.run(
        [sys.executable, "-m", "motiond", "status", "--server", "nobody-here", "--timeout", "0.2"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert missing.returncode == 1
    assert 'no motiond server named "nobody-here"' in missing.stderr


def test_home_set_position_and_off(client: motiond.Client) -> None:
    z = client.axis("z")  # a reference switch at the top (0): the search runs positive
    accepted = z.home()
    frame = z.wait_until_homed(timeout=30.0)
    assert frame.tick >= accepted.tick
    state = z.state(frame)
    del frame
    assert state.homed and state.mode is not ipc.AxisMode.HOMING

    focus = client.axis("focus")
    focus.set_position(123.0)
    frame = client.wait_frames(
        "take the new position", 5.0, lambda f: f.axis(focus.index).position == 123.0
    )
    assert focus.state(frame).homed  # a set position is a valid reference
    del frame

    conveyor = client.axis("conveyor")
    conveyor.off()
    frame = client.wait_frames(
        "de-energise", 5.0, lambda f: f.axis(conveyor.index).mode == ipc.AxisMode.OFF
    )
    del frame
    here = conveyor.state().position
    conveyor.ramp_to(here + 5.0)  # the next goal drives again
    conveyor.wait_until_arrived(timeout=10.0)
