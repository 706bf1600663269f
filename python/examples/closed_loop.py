"""Streams a velocity sine to a group tick by tick, reading every frame (a closed loop).

    python examples/closed_loop.py [--server demo] [--group base] [--seconds 3]
                                   [--amplitude 30] [--period 2]

The group (``base``: the two wheels of the simulated robot) is claimed and put into a
velocity stream; then, for each new frame the server publishes, the program reads it and
sends the setpoint for the tick the stream's lead ahead (``frame.tick + stream.lead``,
``--lead``, default :data:`motiond.DEFAULT_LEAD`): the left wheel follows
``amplitude · sin(2π t / period)`` °/s, the right wheel the opposite. At the end it prints
how many setpoints it sent, the group's counters (applied, late, early, clamped, refused)
and the stream's delay (ticks it runs behind: a setpoint that reached the server after its
tick makes the rest of the stream run that much behind), and how many of its setpoints it
saw applied in a later tick than the one they were for.

A client on a busy machine may miss ticks: it then answers the newest frame. Exit status 0
when the server applied every setpoint sent or dropped it as late (``applied + late ==
sent``: late only when it arrived more than ``stream_buffer`` ticks after its tick), dropped
none as early, clamped none and applied none before its tick; 1 otherwise (or when the
stream stopped).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from typing import List, Optional, Sequence

import motiond


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server", default=os.environ.get("MOTIOND_SERVER", "demo"))
    parser.add_argument("--group", default="base")
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--amplitude", type=float, default=30.0, help="units/s (deg/s)")
    parser.add_argument("--period", type=float, default=2.0, help="s")
    parser.add_argument(
        "--lead", type=int, default=motiond.DEFAULT_LEAD, help="ticks ahead of the frame read"
    )
    args = parser.parse_args(argv)

    with motiond.Client(args.server, timeout=5.0) as client:
        group = client.group(args.group)
        names = group.axes
        units = [client.axis(name).unit for name in names]
        client.wait_ready(timeout=20.0, axes=names)
        group.wait_stopped(timeout=10.0)
        hz = client.tick_hz
        signs = [1.0 if slot % 2 == 0 else -1.0 for slot in range(len(names))]
        first: List[int] = []
        lead = [args.lead]
        fastest = [0.0] * len(names)

        indices = group.axis_indices

        def control(frame: motiond.Frame) -> List[float]:
            # The measured velocities, read from this tick's frame.
            for slot, index in enumerate(indices):
                fastest[slot] = max(fastest[slot], abs(frame.axis(index).velocity))
            if not first:
                first.append(frame.tick)
            t = (frame.tick + lead[0] - first[0]) / hz
            speed = args.amplitude * math.sin(2.0 * math.pi * t / args.period)
            return [sign * speed for sign in signs]

        try:
            with group.stream("velocity", lead=args.lead) as stream:
                stream.run_each_tick(control, duration=args.seconds)
                final = stream.wait_applied(timeout=2.0)
        except motiond.GroupAborted as error:
            print(f"error: the stream stopped: {error}", file=sys.stderr)
            return 1

    measured = ", ".join(
        f"{name} {speed:.1f} {unit}/s" for name, unit, speed in zip(names, units, fastest)
    )
    print(
        f"{args.group}: {stream.sent} setpoints sent in {args.seconds:g} s "
        f"for frame.tick + {args.lead}"
    )
    print(
        f"server: applied {final.applied}, late {final.late}, early {final.early}, "
        f"clamped {final.clamped}, refused {final.refused}; the stream {final.stream_delay} "
        f"ticks behind; last applied tick {final.last_applied_tick} (sequence "
        f"{final.last_sequence})"
    )
    print(
        f"seen applied in frames: {stream.observed}, of which {stream.applied_after_tick} "
        f"after their tick (at most {stream.max_delay} ticks) and "
        f"{stream.applied_before_tick} before it; fastest measured: {measured}"
    )
    failures = []
    if final.applied + final.late != stream.sent:
        failures.append(
            f"the server applied {final.applied} and dropped {final.late} as late of "
            f"{stream.sent} setpoints"
        )
    if final.early or final.clamped:
        failures.append(f"setpoints {final.early} early, {final.clamped} clamped")
    if stream.applied_before_tick:
        failures.append(f"{stream.applied_before_tick} setpoints applied before their tick")
    if stream.sent == 0:
        failures.append("no setpoint was sent")
    for failure in failures:
        print(f"error: {failure}", file=sys.stderr)
    if not failures:
        how = "applied" if final.late == 0 else "applied or, after its tick was long gone, late"
        print(f"every setpoint sent was {how}; none before its tick, none clamped")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
