"""Fixtures: the repository, the Rust contract description, and a live motiond on the
simulated robot of ``config/sim.toml`` under a name of its own.

Environment:

- ``MOTIOND_BIN``: the motiond binary (default ``target/release/motiond``; ``scripts/test``
  builds it).
- ``MOTIOND_LAYOUT_JSON``: the contract as printed by ``cargo run -p motion-ipc --example
  layout`` (default: run that command).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import time
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional

import pytest

import motiond

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository root."""
    return REPO


@pytest.fixture(scope="session")
def contract() -> Dict[str, Any]:
    """The shared-memory contract as the Rust crate describes it."""
    path = os.environ.get("MOTIOND_LAYOUT_JSON")
    if path:
        return json.loads(Path(path).read_text())
    result = subprocess.run(
        ["cargo", "run", "-q", "-j", "1", "-p", "motion-ipc", "--example", "layout"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    if result.returncode != 0:
        pytest.fail(f"cargo run -p motion-ipc --example layout failed:\n{result.stderr}")
    return json.loads(result.stdout)


def motiond_binary() -> Path:
    """The motiond binary the tests run."""
    path = Path(os.environ.get("MOTIOND_BIN", REPO / "target" / "release" / "motiond"))
    if not path.is_file():
        pytest.fail(
            f"no motiond binary at {path}: run ./scripts/test, or `cargo build --release -p "
            "motiond`, or point MOTIOND_BIN at one"
        )
    return path


class Process:
    """A child process whose output goes to a log file; stopped with SIGTERM."""

    def __init__(self, argv: List[str], log: Path, env: Optional[Dict[str, str]] = None) -> None:
        self.log = log
        self._log_file = open(log, "wb")
        self.process = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=self._log_file,
            stderr=subprocess.STDOUT,
            env=env,
        )

    def log_text(self) -> str:
        """What the process logged so far."""
        self._log_file.flush()
        return self.log.read_text(errors="replace")

    def stop(self) -> int:
        """SIGTERM, then waits (kills after 15 s); returns the exit status."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log_file.close()
        return int(self.process.returncode)


class Server(Process):
    """A motiond process on a copy of config/sim.toml named ``name``."""

    def __init__(self, name: str, config: Path, log: Path) -> None:
        self.name = name
        self.config = config
        # Its state directory and black box in the test's temporary directory, as systemd's
        # StateDirectory= would give it, not the machine's /var/lib/motiond.
        env = dict(os.environ)
        env.setdefault("STATE_DIRECTORY", str(config.parent / "state"))
        super().__init__([str(motiond_binary()), "--config", str(config)], log, env)


def sim_config(repo: Path, name: str) -> str:
    """config/sim.toml with ``[server] name`` set to ``name``."""
    text = (repo / "config" / "sim.toml").read_text()
    text, count = re.subn(r'(?m)^name = "demo"', f'name = "{name}"', text, count=1)
    assert count == 1, 'config/sim.toml has no `name = "demo"` line in [server]'
    return text


def start_server(tmp: Path, name: str, edit: Callable[[str], str] = lambda text: text) -> Server:
    """Starts motiond on the simulated robot (its config changed by ``edit``) and waits
    until every device is online."""
    config = tmp / f"{name}.toml"
    config.write_text(edit(sim_config(REPO, name)))
    server = Server(name, config, tmp / f"{name}.log")
    deadline = time.monotonic() + 30.0
    while True:
        if server.process.poll() is not None:
            pytest.fail(f"motiond exited with {server.process.returncode}:\n{server.log_text()}")
        try:
            with motiond.Client(name, timeout=1.0) as client:
                client.wait_ready(timeout=max(1.0, deadline - time.monotonic()))
            return server
        except motiond.MotiondError:
            if time.monotonic() >= deadline:
                server.stop()
                pytest.fail(f"motiond did not come up within 30 s:\n{server.log_text()}")
            time.sleep(0.1)


@pytest.fixture(scope="session")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """One live motiond for the session, on the simulated robot."""
    tmp = tmp_path_factory.mktemp("motiond")
    instance = start_server(tmp, f"pytest-{os.getpid()}")
    yield instance
    status = instance.stop()
    assert status == 0, f"motiond exited with {status}:\n{instance.log_text()}"


@pytest.fixture
def client(server: Server) -> Iterator[motiond.Client]:
    """A client of the session's server; leaves no e-stop latched and no axis moving."""
    with motiond.Client(server.name, timeout=5.0) as connection:
        connection.wait_ready(timeout=10.0)
        yield connection
        if connection.latest().estop_latched:
            connection.reset()
        connection.stop_all()
        # The next test starts with every axis at rest.
        connection.wait_frames(
            "bring every axis to rest",
            15.0,
            lambda frame: not any(axis.flags & motiond.AxisFlags.MOVING for axis in frame.axes),
        )
