"""``python -m motiond.bench``: what a Python client of a running motiond sees, in ns.

Two parts, each ``--duration`` seconds, through this package's public client (the code a
user's script runs, no fast path of its own):

1. **Frame delivery**: ``for frame in client.frames()`` — the blocking iterator this
   package's README shows, which sleeps on the server's tick event (no busy polling) —
   and for every frame ``time.monotonic_ns()`` as soon as the iterator hands it over minus
   the frame's ``publish_ns`` (stamped by the server just before the send). Also counted:
   frames received and ticks lost (gaps in ``tick``).
2. **Command round trip**: the probe of the Rust latency bench (``crates/motion-bench``):
   ``Client.command(axis_count, CommandKind.STOP)`` — Stop on the first axis index past the
   last, answered ``UnknownAxis`` (raised as :class:`motiond.UnknownAxis`), which moves
   nothing — one at a time, each after a pseudo-random wait within one tick period so that
   requests land at every phase of the tick, timed from just before the call to the moment
   it returned or raised.

Prints one JSON document on stdout (format ``motiond.bench/1``); each distribution carries
its raw samples, or, past :data:`RAW_LIMIT` samples, a histogram of values rounded to four
significant digits, so the output stays below about 1 MB whatever the duration. Exits 3
with a one-line reason on stderr when no server answers, 1 on any other failure.

``cargo bench --bench latency`` and ``motionctl bench`` run this module as their "Python
client" phase (docs/PERFORMANCE.md).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import platform
import random
import sys
import time
from collections import Counter
from typing import Any, Dict, List, Optional, Sequence

from .client import Client
from .errors import ConnectError, MotiondError, NoReply, Refused
from .ipc import CommandKind, Reason

__all__ = ["FORMAT", "RAW_LIMIT", "distribution", "measure_frames", "measure_commands", "main"]

#: The ``format`` field of the document (the Rust bench checks it).
FORMAT = "motiond.bench/1"
#: A distribution with more samples than this is printed as a histogram.
RAW_LIMIT = 20_000
#: The only clock behind ``time.monotonic_ns()`` this bench accepts (see :func:`check_clock`).
MONOTONIC = "clock_gettime(CLOCK_MONOTONIC)"
# How long the frame iterator waits for one frame before the server counts as silent, s.
_FRAME_TIMEOUT = 1.0


def check_clock() -> str:
    """Returns the implementation of ``time.monotonic_ns()``; raises when it is not
    CLOCK_MONOTONIC, the clock of ``MotionFrame.publish_ns``.

    The Python documentation of ``time.monotonic()`` (which ``monotonic_ns()`` is "similar
    to, but return time as nanoseconds") lists its clock per platform: "On Windows, call
    ``QueryPerformanceCounter()`` …; On macOS, call ``mach_absolute_time()`` …; On HP-UX,
    call ``gethrtime()``; Call ``clock_gettime(CLOCK_HIGHRES)`` if available; Otherwise,
    call ``clock_gettime(CLOCK_MONOTONIC)``." CLOCK_HIGHRES exists on Solaris/illumos only,
    so on Linux it is ``clock_gettime(CLOCK_MONOTONIC)`` — the clock motiond stamps
    ``publish_ns`` with (``crates/motiond/src/tick.rs``). ``time.get_clock_info()`` names
    the implementation at run time; it is checked here rather than trusted.
    """
    implementation = str(time.get_clock_info("monotonic").implementation)
    if implementation != MONOTONIC:
        raise MotiondError(
            f"time.monotonic_ns() is {implementation} here, not {MONOTONIC}: its readings "
            "cannot be compared with the frames' publish_ns"
        )
    return implementation


def _round4(value: int) -> int:
    """``value`` rounded to four significant digits (exact below 10 000)."""
    if value < 10_000:
        return value
    scale = 10 ** (len(str(value)) - 4)
    return (value + scale // 2) // scale * scale


def _percentile(ordered: Sequence[int], quantile: float) -> int:
    """Nearest-rank percentile of sorted, non-empty ``ordered``."""
    rank = max(1, math.ceil(quantile * len(ordered)))
    return int(ordered[min(rank, len(ordered)) - 1])


def distribution(samples: List[int]) -> Dict[str, Any]:
    """One distribution of non-negative ns samples for the JSON document: its count and
    summary (nearest-rank percentiles of the exact samples), and either ``samples`` (at
    most :data:`RAW_LIMIT`) or ``histogram``: ``[value, count]`` pairs, values rounded to
    four significant digits, ascending."""
    ordered = sorted(samples)
    document: Dict[str, Any] = {"count": len(ordered)}
    if ordered:
        document.update(
            min=ordered[0],
            p50=_percentile(ordered, 0.5),
            p99=_percentile(ordered, 0.99),
            p999=_percentile(ordered, 0.999),
            max=ordered[-1],
        )
    if len(ordered) <= RAW_LIMIT:
        document["samples"] = list(samples)
    else:
        buckets = Counter(_round4(value) for value in ordered)
        document["histogram"] = [[value, buckets[value]] for value in sorted(buckets)]
    return document


def measure_frames(client: Client, duration: float) -> Dict[str, Any]:
    """Part 1: every frame ``client.frames()`` yields for ``duration`` s."""
    # The history sample and anything already queued are old: taken, not measured.
    old = client.latest()
    del old
    latency: List[int] = []
    negative = 0
    lost = 0
    last_tick: Optional[int] = None
    end = time.monotonic_ns() + int(duration * 1e9)
    for frame in client.frames(timeout=_FRAME_TIMEOUT):
        received = time.monotonic_ns()
        delta = received - frame.publish_ns
        tick = frame.tick
        del frame  # one borrowed sample at a time
        if delta < 0:
            negative += 1  # impossible on one clock; counted, never recorded
        else:
            latency.append(delta)
        if last_tick is not None and tick > last_tick:
            lost += tick - last_tick - 1
        last_tick = tick
        if received >= end:
            break
    return {
        "waiting": "for frame in client.frames(): the blocking iterator, sleeping on the "
        "tick event",
        "received": len(latency) + negative,
        "lost": lost,
        "negative": negative,
        "latency_ns": distribution(latency),
    }


def measure_commands(client: Client, duration: float, seed: int) -> Dict[str, Any]:
    """Part 2: the unknown-axis probe, one request at a time for ``duration`` s."""
    axis_index = len(client.axes)  # one past the last axis
    period = 1.0 / max(1, client.tick_hz)
    pace = random.Random(seed)
    rtt: List[int] = []
    replies: Counter[str] = Counter()
    no_reply = 0
    sent_count = 0
    end = time.monotonic_ns() + int(duration * 1e9)
    while time.monotonic_ns() < end:
        time.sleep(pace.random() * period)
        sent_count += 1
        sent = time.monotonic_ns()
        try:
            client.command(axis_index, CommandKind.STOP)
            reason: Any = Reason.ACCEPTED
        except Refused as refusal:
            reason = refusal.reason
        except NoReply:
            no_reply += 1
            continue
        rtt.append(time.monotonic_ns() - sent)
        replies[reason.name if isinstance(reason, Reason) else f"reason {int(reason)}"] += 1
    expected = Reason.UNKNOWN_AXIS.name
    return {
        "probe": f"Client.command({axis_index}, CommandKind.STOP): Stop on axis {axis_index}, "
        "one past the last, answered UNKNOWN_AXIS",
        "axis_index": axis_index,
        "sent": sent_count,
        "replies": dict(sorted(replies.items())),
        "wrong_reason": sum(n for name, n in replies.items() if name != expected),
        "no_reply": no_reply,
        "rtt_ns": distribution(rtt),
    }


def run(client: Client, duration: float, seed: int) -> Dict[str, Any]:
    """Both parts against ``client``'s server; the whole JSON document."""
    clock = check_clock()
    info = client.info
    frames = measure_frames(client, duration)
    commands = measure_commands(client, duration, seed)
    return {
        "format": FORMAT,
        "server": client.name,
        "tick_hz": int(info.tick_hz),
        "axis_count": int(info.axis_count),
        "duration_s": duration,
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "iceoryx2": importlib.metadata.version("iceoryx2"),
        "motiond_package": importlib.metadata.version("motiond"),
        "clock": clock,
        "frames": frames,
        "commands": commands,
    }


def _seconds(text: str) -> float:
    value = float(text)
    if not math.isfinite(value) or value <= 0.0 or value > 86_400.0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be more than 0 and at most a day")
    return value


def _fail(error: BaseException) -> None:
    line = " ".join(str(error).split()) or type(error).__name__
    print(f"motiond.bench: {line}", file=sys.stderr)


def exit_status(error: BaseException) -> int:
    """Says on stderr why a bench stopped and returns its exit status: 3 when the server
    could not be reached, 1 for another error of this package, 130 when interrupted."""
    if isinstance(error, KeyboardInterrupt):
        _fail(KeyboardInterrupt("interrupted"))
        return 130
    _fail(error)
    return 3 if isinstance(error, ConnectError) else 1


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m motiond.bench",
        description="Frame delivery and command round trip of this Python client against "
        "a running motiond, as one JSON document on stdout.",
    )
    parser.add_argument("--server", default="demo", help="instance name (default: demo)")
    parser.add_argument(
        "--duration",
        type=_seconds,
        default=10.0,
        help="seconds for each of the two parts (default: 10)",
    )
    parser.add_argument(
        "--connect-timeout",
        type=_seconds,
        default=2.0,
        help="how long to wait for the server's services, s (default: 2)",
    )
    parser.add_argument("--seed", type=int, default=None, help="seed of the request pacing")
    args = parser.parse_args(argv)
    seed = args.seed if args.seed is not None else time.monotonic_ns()
    try:
        with Client(args.server, timeout=args.connect_timeout, node_name="motiond-py-bench") as c:
            document = run(c, args.duration, seed)
    except (MotiondError, KeyboardInterrupt) as error:
        return exit_status(error)
    json.dump(document, sys.stdout, separators=(",", ":"))
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
