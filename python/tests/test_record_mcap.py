"""``motionctl record --out run.mcap --out run.csv`` against the session's live motiond
(config/sim.toml) while x ramps: the MCAP file is read with the ``mcap`` and
``mcap-ros2-support`` packages (the readers Foxglove's and ROS 2's tooling use), every
``sensor_msgs/msg/JointState`` decodes, and it holds exactly the ticks, names, positions and
velocities of the CSV written from the same frames in the same run (the CSV prints each f64
in its shortest round-trip form, so equality is exact).

Environment: ``MOTIONCTL_BIN``, the motionctl binary (default ``target/debug/motionctl``;
``scripts/test`` builds it)."""

from __future__ import annotations

import csv
import os
import subprocess
import time
from pathlib import Path
from typing import Dict, List

import pytest

# Both are in python[test] (python/pyproject.toml), which ./scripts/test installs.
from mcap import reader as mcap_reader
from mcap_ros2 import decoder as mcap_ros2_decoder

import motiond

from conftest import REPO, Server


def motionctl_binary() -> Path:
    """The motionctl binary the test runs."""
    path = Path(os.environ.get("MOTIONCTL_BIN", REPO / "target" / "debug" / "motionctl"))
    if not path.is_file():
        pytest.fail(
            f"no motionctl binary at {path}: run ./scripts/test, or `cargo build -p "
            "motionctl`, or point MOTIONCTL_BIN at one"
        )
    return path


def read_csv(path: Path) -> List[Dict[str, str]]:
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def test_mcap_joint_states_equal_the_csv_of_the_same_run(
    server: Server, client: motiond.Client, tmp_path: Path
) -> None:
    mcap_path, csv_path = tmp_path / "run.mcap", tmp_path / "run.csv"
    recorder = subprocess.Popen(
        [
            str(motionctl_binary()),
            "--server",
            server.name,
            "record",
            "--duration",
            "2s",
            "--out",
            str(mcap_path),
            "--out",
            str(csv_path),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    # Motion during the recording, so positions and velocities change from tick to tick.
    x = client.axis("x")
    time.sleep(0.3)
    goal = 30.0 if abs(x.state().position - 30.0) > 5.0 else 10.0
    x.ramp_to(goal, 20.0, 100.0)
    try:
        _, stderr = recorder.communicate(timeout=60)
    finally:
        if recorder.poll() is None:
            recorder.kill()
    assert recorder.returncode == 0, stderr

    rows = read_csv(csv_path)
    assert rows, "the CSV has no rows"
    names = [column.split(".position[")[0] for column in rows[0] if ".position[" in column]
    assert "x" in names and len(names) == 18, names
    position_columns = [next(c for c in rows[0] if c.startswith(f"{n}.position[")) for n in names]
    velocity_columns = [next(c for c in rows[0] if c.startswith(f"{n}.velocity[")) for n in names]

    topic = f"/motiond/{server.name}/joint_states"
    decoded = []
    with open(mcap_path, "rb") as file:
        reader = mcap_reader.make_reader(
            file, validate_crcs=True, decoder_factories=[mcap_ros2_decoder.DecoderFactory()]
        )
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes, "chunked, with a summary"
        channel = next(c for c in summary.channels.values() if c.topic == topic)
        schema = summary.schemas[channel.schema_id]
        assert (schema.name, schema.encoding, channel.message_encoding) == (
            "sensor_msgs/msg/JointState",
            "ros2msg",
            "cdr",
        )
        metadata = {record.name: record.metadata for record in reader.iter_metadata()}
        for _, _, message, joint_state in reader.iter_decoded_messages(topics=[topic]):
            decoded.append((message, joint_state))
    assert set(metadata) == {
        "motiond.description",
        "motiond.config",
        "motiond.versions",
        "motiond.recording",
    }, metadata.keys()
    assert metadata["motiond.versions"]["motion_ipc_schema_version"].isdigit()

    # One message per CSV row: the same ticks (sequence = tick), names, positions, velocities.
    assert len(decoded) == len(rows)
    moved = set()
    first_stamp_ns = None
    for (message, joint_state), row in zip(decoded, rows):
        assert message.sequence == int(row["tick"]) % 2**32
        assert list(joint_state.name) == names
        positions = [float(row[c]) for c in position_columns]
        velocities = [float(row[c]) for c in velocity_columns]
        assert list(joint_state.position) == positions, row["tick"]
        assert list(joint_state.velocity) == velocities, row["tick"]
        assert list(joint_state.effort) == []
        moved.add(positions[names.index("x")])
        stamp_ns = joint_state.header.stamp.sec * 10**9 + joint_state.header.stamp.nanosec
        assert message.log_time == stamp_ns
        # Stamps advance as the ticks' deadlines do (the CSV's time_s, printed from an f64
        # of seconds: exact to well under a microsecond).
        deadline_ns = int(row["time_s"].replace(".", ""))
        if first_stamp_ns is None:
            first_stamp_ns, first_deadline_ns = stamp_ns, deadline_ns
        assert abs((stamp_ns - first_stamp_ns) - (deadline_ns - first_deadline_ns)) <= 1000
    # The simulated pack refreshes x every few ticks: a handful of distinct positions.
    assert len(moved) > 3, f"x did not move during the recording: {sorted(moved)}"
    # Wall-clock-like: within a minute of now.
    assert abs(first_stamp_ns / 1e9 - time.time()) < 60.0
