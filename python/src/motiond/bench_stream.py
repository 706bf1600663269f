"""``python -m motiond.bench_stream``: a Python closed-loop client streaming to a group of
a running motiond, timed, as one JSON document.

The loop is this package's public one (the code a user's script runs, as
``examples/closed_loop.py``): ``client.group(name).stream("velocity")`` and
:meth:`~motiond.stream.SetpointStream.run_each_tick`, answering every new frame ``k`` with
the setpoint for ``k + lead`` (``--lead``, default :data:`motiond.DEFAULT_LEAD`; a velocity
sine of ±20 units/s, period 1.5 s, every second axis the opposite). Measured:

- ``before_deadline``: the setpoints sent (``time.monotonic_ns()`` right after the send)
  before the deadline of the tick they were for (the frame's ``time_ns`` + ``lead``
  periods: the server takes that tick's setpoints then), of the stream's ``ticks`` (first
  setpoint's tick to the last's): the share of ticks the client met;
- ``sent_ns``: frame ``publish_ns`` → that send;
- ``received_ns``: frame ``publish_ns`` → the server took the setpoint from the service
  (``GroupStatus.last_received_ns`` of the frames that show it applied);
- ``applied_in_tick`` / ``applied_later``: setpoints seen applied in the tick they were for,
  or later; and the server's counters and the stream's delay at the end.

``cargo bench --bench latency`` and ``motionctl bench`` run it on the group ``base`` of the
simulated robot their coordinated-motion phase starts (docs/PERFORMANCE.md). Exits 3 when
no server answers, 1 on any other failure.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import platform
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .bench import _seconds, check_clock, distribution, exit_status
from .client import Client
from .errors import MotiondError
from .frames import Frame
from .stream import DEFAULT_LEAD

__all__ = ["FORMAT", "measure_stream", "main"]

#: The ``format`` field of the document (the Rust bench checks it).
FORMAT = "motiond.bench_stream/2"
# The sine: amplitude (units/s) and period (s), as the Rust bench client's.
_SPEED = 20.0
_PERIOD = 1.5


def measure_stream(
    client: Client, group_name: str, duration: float, lead: int = DEFAULT_LEAD
) -> Dict[str, Any]:
    """Streams to ``group_name`` for ``duration`` s, ``lead`` ticks ahead; the document's
    figures."""
    group = client.group(group_name)
    index = group.index
    count = len(group.axes)
    period_ns = 1_000_000_000 // max(1, client.tick_hz)
    signs = [1.0 if slot % 2 == 0 else -1.0 for slot in range(count)]
    # Per sequence (index = sequence − 1): (for_tick, frame publish_ns, frame time_ns).
    answered: List[Tuple[int, int, int]] = []
    sent_ns: List[int] = []
    received_ns: List[int] = []
    before_deadline = 0
    applied = [0, 0]  # in their tick, later
    seen = [0]  # the last sequence seen applied
    lost = [0]
    last_tick: List[int] = []

    def observe(frame: Frame) -> None:
        state = frame.group(index)
        sequence = int(state.last_sequence)
        if int(state.last_applied_tick) != frame.tick or sequence <= seen[0]:
            return
        seen[0] = sequence
        if not 0 < sequence <= len(answered):
            return
        for_tick, publish_ns, _ = answered[sequence - 1]
        received = int(state.last_received_ns)
        if received >= publish_ns:
            received_ns.append(received - publish_ns)
        applied[0 if for_tick == frame.tick else 1] += 1

    def control(frame: Frame) -> List[float]:
        observe(frame)
        if last_tick and frame.tick > last_tick[0] + 1:
            lost[0] += frame.tick - last_tick[0] - 1
        last_tick[:] = [frame.tick]
        answered.append((frame.tick + lead, frame.publish_ns, frame.time_ns))
        t = len(answered) * period_ns / 1e9
        speed = _SPEED * math.sin(2.0 * math.pi * t / _PERIOD)
        return [sign * speed for sign in signs]

    group.wait_stopped(timeout=10.0)
    with group.stream("velocity", lead=lead) as stream:
        send = stream.send

        def timed_send(
            for_tick: int,
            values: Sequence[float],
            velocities: Optional[Sequence[float]] = None,
        ) -> int:
            sequence = send(for_tick, values, velocities)
            now = time.monotonic_ns()
            _, publish_ns, time_ns = answered[-1]
            sent_ns.append(now - publish_ns)
            if now < time_ns + lead * period_ns:
                nonlocal before_deadline
                before_deadline += 1
            return sequence

        stream.send = timed_send  # type: ignore[method-assign]
        stream.run_each_tick(control, duration=duration)
        # The last setpoints' ticks pass: their outcome shows in the frames to come.
        final = stream.wait_applied(timeout=2.0)
        for _ in range(5):
            frame = client.latest()
            observe(frame)
            del frame
            time.sleep(period_ns / 1e9)
    ticks = answered[-1][0] - answered[0][0] + 1 if answered else 0
    return {
        "group": group_name,
        "lead": lead,
        "stream_delay": final.stream_delay,
        "sent": len(sent_ns),
        "ticks": ticks,
        "before_deadline": before_deadline,
        "lost_frames": lost[0],
        "applied_in_tick": applied[0],
        "applied_later": applied[1],
        "counters": {
            "applied": final.applied,
            "late": final.late,
            "early": final.early,
            "clamped": final.clamped,
            "refused": final.refused,
        },
        "sent_ns": distribution(sent_ns),
        "received_ns": distribution(received_ns),
    }


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m motiond.bench_stream",
        description="A Python closed-loop client streaming velocity setpoints to a group of "
        "a running motiond, timed, as one JSON document on stdout.",
    )
    parser.add_argument("--server", default="demo", help="instance name (default: demo)")
    parser.add_argument("--group", default="base", help="the group (default: base)")
    parser.add_argument("--duration", type=_seconds, default=5.0, help="seconds (default: 5)")
    parser.add_argument(
        "--lead",
        type=int,
        default=DEFAULT_LEAD,
        help=f"ticks ahead of the frame read (default: {DEFAULT_LEAD})",
    )
    parser.add_argument(
        "--connect-timeout",
        type=_seconds,
        default=2.0,
        help="how long to wait for the server's services, s (default: 2)",
    )
    args = parser.parse_args(argv)
    try:
        clock = check_clock()
        with Client(
            args.server, timeout=args.connect_timeout, node_name="motiond-py-bench-stream"
        ) as client:
            figures = measure_stream(client, args.group, args.duration, args.lead)
            tick_hz = int(client.tick_hz)
    except (MotiondError, KeyboardInterrupt) as error:
        return exit_status(error)
    document = {
        "format": FORMAT,
        "server": args.server,
        "tick_hz": tick_hz,
        "duration_s": args.duration,
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "iceoryx2": importlib.metadata.version("iceoryx2"),
        "clock": clock,
        "stream": figures,
    }
    json.dump(document, sys.stdout, separators=(",", ":"))
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
