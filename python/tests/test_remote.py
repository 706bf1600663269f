"""The remote client: the same API through a real ``motion-bridge`` over zenoh (TCP on
loopback), against the session's live motiond.

Environment: ``MOTION_BRIDGE_BIN``, the bridge binary (default ``target/debug/motion-bridge``,
which ``cargo test --workspace`` builds; ``scripts/test`` passes it).
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Iterator

import pytest

import motiond
from motiond import AxisMode, CommandKind
from motiond.remote import RemoteClient

from conftest import REPO, Process, Server

pytest.importorskip("zenoh", reason="the remote client needs eclipse-zenoh (motiond[test])")

BRIDGE_CONFIG = """
# The panel may do everything; any other identity only stop and e-stop.
[[remote]]
identity = "panel"
allow = ["all"]

[[remote]]
identity = "*"
allow = ["stop", "estop"]
"""


def bridge_binary() -> Path:
    path = Path(os.environ.get("MOTION_BRIDGE_BIN", REPO / "target" / "debug" / "motion-bridge"))
    if not path.is_file():
        pytest.fail(
            f"no motion-bridge binary at {path}: run ./scripts/test, or `cargo build -p "
            "motion-bridge`, or point MOTION_BRIDGE_BIN at one"
        )
    return path


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Bridge(Process):
    """A motion-bridge process in front of the session's server."""

    def __init__(self, server: Server, tmp: Path) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        config = tmp / "bridge.toml"
        config.write_text(BRIDGE_CONFIG)
        argv = [str(bridge_binary()), "--server", server.name, "--listen", self.endpoint]
        # The panel's rule is wide and zenoh authenticates nobody here: loopback only.
        super().__init__(argv + ["--config", str(config), "--insecure"], tmp / "bridge.log")


@pytest.fixture(scope="module")
def bridge(server: Server, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Bridge]:
    instance = Bridge(server, tmp_path_factory.mktemp("bridge"))
    # Up when a remote client gets the server's description through it.
    try:
        RemoteClient(server.name, timeout=30.0, remote=instance.endpoint).close()
    except motiond.MotiondError as error:
        instance.stop()
        pytest.fail(f"the bridge did not come up: {error}\n{instance.log_text()}")
    yield instance
    status = instance.stop()
    assert status == 0, f"motion-bridge exited with {status}:\n{instance.log_text()}"


@pytest.fixture
def panel(server: Server, bridge: Bridge) -> Iterator[RemoteClient]:
    with motiond.Client(server.name, 5.0, remote=bridge.endpoint, identity="panel") as remote:
        assert isinstance(remote, RemoteClient)
        yield remote


def test_remote_client_sees_the_same_server(
    client: motiond.Client, panel: RemoteClient
) -> None:
    assert panel.tick_hz == client.tick_hz
    assert [a.name for a in panel.axes] == [a.name for a in client.axes]
    assert [s.name for s in panel.signals] == [s.name for s in client.signals]
    assert panel.info.server_pid == client.info.server_pid
    assert panel.command_timeout == client.command_timeout
    # Frames arrive in order, decimated by the bridge (every 10th tick at 1 kHz), and are
    # private copies: holding many is fine (over shared memory iceoryx2 allows two).
    held = []
    for frame in panel.frames(timeout=2.0):
        held.append(frame)
        if len(held) == 12:
            break
    ticks = [f.tick for f in held]
    assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
    gaps = {b - a for a, b in zip(ticks, ticks[1:])}
    assert min(gaps) >= 5, f"frames every {sorted(gaps)} ticks: not decimated"
    assert held[-1].axis_count == client.latest().axis_count
    # Parameters and statistics through the bridge.
    remote_params = [(p.owner_name, p.key, p.value) for p in panel.params()]
    assert remote_params == [(p.owner_name, p.key, p.value) for p in client.params()]
    deadline = time.monotonic() + 5.0
    while panel.stats() is None:
        assert time.monotonic() < deadline, "no statistics through the bridge within 5 s"
        panel.next_frame(1.0)


def test_remote_move_arrives_and_refusals_carry_the_servers_reason(
    client: motiond.Client, panel: RemoteClient
) -> None:
    client.wait_ready(timeout=10.0)
    x = panel.axis("x")
    start = x.state().position
    goal = 12.0 if abs(start - 12.0) > 1.0 else 4.0
    accepted = x.ramp_to(goal)
    assert accepted.tick > 0
    frame = x.wait_until_arrived(timeout=20.0)
    assert x.state(frame).position == pytest.approx(goal, abs=0.05)
    # The local client sees the same arrival.
    assert client.axis("x").state().position == pytest.approx(goal, abs=0.05)
    # A refusal of the server's comes back typed, as over shared memory.
    with pytest.raises(motiond.OutOfRange) as refusal:
        x.position(1e9)
    assert refusal.value.reason is motiond.Reason.OUT_OF_RANGE


def test_the_bridge_refuses_what_an_identity_may_not_do(
    client: motiond.Client, server: Server, bridge: Bridge
) -> None:
    with motiond.Client(server.name, 5.0, remote=bridge.endpoint) as anonymous:
        assert anonymous.identity == "anonymous"
        x = anonymous.axis("x")
        target_before = client.axis("x").state().target
        with pytest.raises(motiond.BridgeRefused) as refused:
            x.ramp_to(target_before + 3.0)
        assert refused.value.code == "not-allowed"
        assert "anonymous" in str(refused.value)
        # The server never saw it: the axis holds its target.
        time.sleep(0.05)
        assert client.axis("x").state().target == target_before
        # Stop is allowed for everyone.
        assert x.stop().tick > 0


def test_a_remote_jog_stops_when_its_process_dies(
    client: motiond.Client, server: Server, bridge: Bridge
) -> None:
    program = textwrap.dedent(
        f"""
        import sys, time, motiond
        with motiond.Client({server.name!r}, 10.0, remote={bridge.endpoint!r},
                            identity="panel") as remote:
            jog = remote.axis("conveyor").jog(20.0)
            print("jogging", flush=True)
            while True:
                remote.keep_alive()
                time.sleep(0.01)
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", program], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    try:
        assert child.stdout is not None
        line = child.stdout.readline()
        assert line.strip() == b"jogging", child.stderr.read().decode() if child.stderr else ""
        conveyor = client.axis("conveyor")
        moving = client.wait_frames("start moving", 5.0, lambda f: conveyor.state(f).moving)
        assert conveyor.state(moving).mode is AxisMode.RAMP_VELOCITY
        del moving
        # Renewed through the bridge for longer than the deadman.
        time.sleep(2 * client.command_timeout)
        assert conveyor.state().moving, "the remote jog was not renewed through the bridge"
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    # No renewals any more: the server's deadman (or the bridge, seeing the client's
    # liveliness end) stops the axis.
    stopped = client.axis("conveyor").wait_until_stopped(timeout=5.0)
    assert not client.axis("conveyor").state(stopped).moving


def test_estop_through_the_bridge_latches(client: motiond.Client, server: Server, bridge: Bridge) -> None:
    # Any identity may e-stop.
    with motiond.Client(server.name, 5.0, remote=bridge.endpoint, identity="visitor") as visitor:
        visitor.notify_estop()
        assert visitor.wait_frames("latch the e-stop", 5.0, lambda f: f.estop_latched)
        with pytest.raises(motiond.BridgeRefused):
            visitor.reset()  # not on the visitor's list
    assert client.latest().estop_latched
    client.reset()


def test_no_bridge_is_a_clear_error() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    started = time.monotonic()
    with pytest.raises(motiond.NoBridge) as error:
        motiond.Client("demo", 0.5, remote=endpoint)
    assert endpoint in str(error.value)
    assert time.monotonic() - started < 10.0


def test_bad_names_and_local_only_options_are_refused() -> None:
    with pytest.raises(motiond.ConnectError, match="cannot be a remote identity"):
        motiond.Client("demo", 0.5, remote="tcp/127.0.0.1:1", identity="a/b")
    with pytest.raises(motiond.ConnectError, match="cannot be a server name"):
        motiond.Client("de*mo", 0.5, remote="tcp/127.0.0.1:1")
    with pytest.raises(motiond.ConnectError, match="remote client only"):
        motiond.Client("demo", 0.5, identity="panel")


def test_cli_lists_through_the_bridge(server: Server, bridge: Bridge) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "motiond",
            "list",
            "--server",
            server.name,
            "--remote",
            bridge.endpoint,
            "--timeout",
            "10",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert "conveyor" in result.stdout and "x" in result.stdout


def test_remote_sends_the_kind_it_was_given(panel: RemoteClient) -> None:
    # A stop of every axis, as a raw request: accepted with the server's tick.
    reply = panel.send(motiond.ipc.ALL_AXES, CommandKind.STOP)
    assert reply.reason == motiond.Reason.ACCEPTED
    assert reply.tick_applied > 0


def test_groups_say_they_need_shared_memory(panel: RemoteClient) -> None:
    with pytest.raises(motiond.MotiondError, match="groups work over shared memory only"):
        panel.group("base")
    with pytest.raises(motiond.MotiondError, match="groups work over shared memory only"):
        panel.groups
    # The frames a remote client reads carry the groups' states all the same.
    frame = panel.latest()
    assert frame.group_count == len(panel.info.groups[: panel.info.group_count])


def test_request_meta_is_the_documented_mac() -> None:
    # The same bytes motion-wire's keys::tests pins (GOLDEN_MAC): HMAC-SHA3-256 keyed by the
    # session's secret, the first 16 bytes.
    from motiond.remote import request_meta

    meta = request_meta(bytes([7] * 16), "panel", bytes(range(64)), 0x0102, 5, 1000)
    assert len(meta) == 49 and meta[0] == 3
    assert meta[1:3] == b"\x02\x01" and meta[17:25] == (5).to_bytes(8, "little")
    assert meta[33:].hex() == "e761b1d15721ac41efb5c765052e2456"
    # The secret itself is nowhere in it.
    assert bytes([7] * 16) not in meta
    assert request_meta(None, "panel", bytes(64), 0, 0, 9)[33:] == bytes(16)


def test_session_secret_is_agreed_not_sent() -> None:
    # motion-wire's keys::tests (GOLDEN_SECRET): the client's key of bytes 1..32, the bridge's
    # of 33..64, session 0x0102.
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import x25519

    from motiond.remote import session_secret

    def public(private: bytes) -> bytes:
        key = x25519.X25519PrivateKey.from_private_bytes(private)
        return key.public_key().public_bytes(
            serialization.Encoding.Raw, serialization.PublicFormat.Raw
        )

    client, bridge = bytes(range(1, 33)), bytes(range(33, 65))
    secret = session_secret(client, public(client), public(bridge), 0x0102)
    assert secret.hex() == "8b426f0d029361820a9f12a653f823b0"
    assert session_secret(bridge, public(client), public(bridge), 0x0102) == secret
    with pytest.raises(ValueError):
        session_secret(bridge, bytes(32), public(bridge), 0x0102)
