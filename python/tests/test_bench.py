"""``python -m motiond.bench`` against the session's live server: one JSON document with
frames, latencies on one clock and the unknown-axis probe's replies; a clear one-line
refusal without a server. No timing is asserted: only that the figures are measurements."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
from typing import Any, Dict, List

import pytest

import motiond
from motiond import bench

from conftest import Server

# A latency above this is not a delivery but two clocks compared (or a broken stamp).
_PLAUSIBLE_NS = 10_000_000_000


def run_bench(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    """Runs ``python -m motiond.bench`` with this interpreter."""
    return subprocess.run(
        [sys.executable, "-m", "motiond.bench", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        check=False,
    )


def values(dist: Dict[str, Any]) -> List[int]:
    """Every sample of a distribution, expanded from its histogram if it has one."""
    if "samples" in dist:
        return list(dist["samples"])
    return [value for value, count in dist["histogram"] for _ in range(count)]


def test_one_second_prints_one_document_of_measurements(server: Server) -> None:
    result = run_bench("--server", server.name, "--duration", "1")
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("\n") == 1, "one JSON document on one line"
    document = json.loads(result.stdout)
    assert document["format"] == bench.FORMAT
    assert document["server"] == server.name
    assert document["clock"] == "clock_gettime(CLOCK_MONOTONIC)"
    assert document["python"].split()[1] == ".".join(map(str, sys.version_info[:3]))
    assert document["iceoryx2"].startswith("0.10.")

    frames = document["frames"]
    latency = values(frames["latency_ns"])
    assert frames["received"] > 0
    assert frames["negative"] == 0, "a frame stamped after it was received: two clocks"
    assert len(latency) == frames["latency_ns"]["count"] == frames["received"]
    assert all(isinstance(v, int) and 0 <= v < _PLAUSIBLE_NS for v in latency)
    assert frames["lost"] >= 0
    summary = frames["latency_ns"]
    assert summary["min"] <= summary["p50"] <= summary["p99"] <= summary["max"]

    commands = document["commands"]
    rtt = values(commands["rtt_ns"])
    assert commands["axis_index"] == document["axis_count"] == 18
    assert commands["sent"] > 0
    assert commands["wrong_reason"] == 0, commands["replies"]
    assert commands["replies"] == {"UNKNOWN_AXIS": len(rtt)}
    assert commands["sent"] == len(rtt) + commands["no_reply"]
    assert all(0 < v < _PLAUSIBLE_NS for v in rtt)


def test_without_a_server_it_exits_non_zero_with_one_line() -> None:
    result = run_bench(
        "--server", f"no-such-server-{os.getpid()}", "--duration", "1", "--connect-timeout", "0.5"
    )
    assert result.returncode == 3, result
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("motiond.bench: no motiond server named"), lines[0]


def test_bad_arguments_are_refused() -> None:
    for args in (["--duration", "0"], ["--duration", "soon"], ["--duration", "nan"]):
        result = run_bench(*args)
        assert result.returncode == 2, (args, result)
        assert "--duration" in result.stderr


def test_a_long_run_prints_a_histogram_not_every_sample() -> None:
    small = bench.distribution([5, 1, 3])
    assert small["samples"] == [5, 1, 3]
    assert (small["count"], small["min"], small["p50"], small["max"]) == (3, 1, 3, 5)
    samples = [1_000 + (i % 5_000) * 997 for i in range(bench.RAW_LIMIT + 1)]
    big = bench.distribution(samples)
    assert "samples" not in big
    assert sum(count for _, count in big["histogram"]) == big["count"] == len(samples)
    assert [v for v, _ in big["histogram"]] == sorted({v for v, _ in big["histogram"]})
    # Four significant digits: every sample is within 0.05 % of its bucket.
    assert len(big["histogram"]) <= 5_000
    for value in (samples[0], samples[4_999], 4_985_003):
        bucket = min((v for v, _ in big["histogram"]), key=lambda v: abs(v - value))
        assert abs(bucket - value) <= value * 0.0005
    assert len(json.dumps(big)) < len(json.dumps(samples))
    assert bench.distribution([]) == {"count": 0, "samples": []}


def test_the_clock_is_checked_not_assumed(monkeypatch: pytest.MonkeyPatch) -> None:
    assert bench.check_clock() == "clock_gettime(CLOCK_MONOTONIC)"
    realtime = types.SimpleNamespace(implementation="clock_gettime(CLOCK_REALTIME)")
    monkeypatch.setattr(bench.time, "get_clock_info", lambda name: realtime)
    with pytest.raises(motiond.MotiondError, match="CLOCK_REALTIME"):
        bench.check_clock()


def test_the_closed_loop_streams_to_base_and_prints_one_document(server: Server) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "motiond.bench_stream", "--server", server.name]
        + ["--group", "base", "--duration", "1"],
        capture_output=True,
        text=True,
        timeout=60.0,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        check=False,
    )
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["format"] == "motiond.bench_stream/2"
    stream = document["stream"]
    assert stream["lead"] == motiond.DEFAULT_LEAD
    assert 0 <= stream["stream_delay"] <= 3  # base's stream_buffer
    assert stream["sent"] > 0
    assert 0 < stream["before_deadline"] <= stream["sent"] <= stream["ticks"]
    assert stream["counters"]["refused"] == 0
    # Frame published → setpoint received by the server: on one clock, after the send.
    received = values(stream["received_ns"])
    assert received and all(0 < v < _PLAUSIBLE_NS for v in received)
    assert stream["applied_in_tick"] + stream["applied_later"] == len(received)


def test_the_closed_loop_takes_a_lead(server: Server) -> None:
    argv = [sys.executable, "-m", "motiond.bench_stream", "--server", server.name]
    result = subprocess.run(
        argv + ["--group", "base", "--duration", "0.3", "--lead", "1"],
        capture_output=True,
        text=True,
        timeout=60.0,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["stream"]["lead"] == 1
    # base's stream_buffer is 3: a lead of 5 is refused before anything is sent.
    result = subprocess.run(
        argv + ["--group", "base", "--duration", "0.3", "--lead", "5"],
        capture_output=True,
        text=True,
        timeout=60.0,
        check=False,
    )
    assert result.returncode != 0
    assert "outside 1..=4" in result.stderr, result.stderr
