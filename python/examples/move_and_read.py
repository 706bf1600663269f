"""Moves an axis and reads 1000 consecutive frames while it moves.

    python examples/move_and_read.py [--server demo] [--axis x] [--frames 1000]

Every frame the server publishes is read in order, straight from shared memory, and the
axis's position is taken from a NumPy view of the frame when NumPy is installed. At the
end the program checks that it saw every tick: a tick missing between two frames is only
acceptable when the server itself skipped it (a tick that overran its deadline is not
published: ``ServerStats.overruns`` counts those, ``frames_lost`` the frames it could not
send). Exit status 0 when no frame was lost on the client's side, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import List, Optional, Sequence

import motiond


def wait_stats(client: motiond.Client, at_tick: int, timeout: float) -> motiond.ipc.ServerStats:
    """The first server statistics taken at or after ``at_tick``."""
    deadline = time.monotonic() + timeout
    while True:
        stats = client.stats()
        if stats is not None and stats.tick >= at_tick:
            return stats
        if time.monotonic() >= deadline:
            raise motiond.WaitTimeout("the stats service", f"report tick {at_tick}", timeout)
        client.next_frame()


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server", default="demo")
    parser.add_argument("--axis", default="x")
    parser.add_argument("--frames", type=int, default=1000)
    args = parser.parse_args(argv)

    try:
        import numpy  # noqa: F401

        have_numpy = True
    except ImportError:
        have_numpy = False

    with motiond.Client(args.server, timeout=5.0) as client:
        client.wait_ready(timeout=20.0)
        axis = client.axis(args.axis)
        name, unit, info = axis.name, axis.unit, axis.info
        start = axis.state().position
        # Head for the far half of the travel, so that the move lasts the whole reading.
        middle = (info.min + info.max) / 2.0
        goal = (
            info.max - (info.max - middle) * 0.2
            if start < middle
            else info.min + (middle - info.min) * 0.2
        )
        before = wait_stats(client, 0, timeout=3.0)

        accepted = axis.ramp_to(goal)
        print(f"{name}: {start:.3f} -> {goal:.3f} {unit} (goal at tick {accepted.tick})")

        ticks: List[int] = []
        positions: List[float] = []
        for frame in client.frames(timeout=1.0):
            ticks.append(frame.tick)
            if have_numpy:
                positions.append(float(frame.positions()[axis.index]))
            else:
                positions.append(frame.axis(axis.index).position)
            if len(ticks) == args.frames:
                break
        del frame
        after = wait_stats(client, ticks[-1] + 1, timeout=3.0)
        axis.stop()

    gaps = [(a, b) for a, b in zip(ticks, ticks[1:]) if b != a + 1]
    skipped = sum(b - a - 1 for a, b in gaps)
    overruns = after.overruns - before.overruns
    not_sent = after.frames_lost - before.frames_lost
    print(
        f"read {len(ticks)} frames, ticks {ticks[0]}..{ticks[-1]}; "
        f"{name} moved {positions[0]:.3f} -> {positions[-1]:.3f} {unit}"
    )
    print(
        f"{len(gaps)} gaps ({skipped} ticks) in the ticks read; meanwhile the server "
        f"overran {overruns} times and could not send {not_sent} frames"
    )
    if any(b <= a for a, b in gaps):
        print("error: ticks went backwards or repeated", file=sys.stderr)
        return 1
    if len(gaps) > overruns + not_sent:
        print(
            "error: frames were published but not read (the client fell more than the "
            "frame service's buffer behind)",
            file=sys.stderr,
        )
        return 1
    if positions[-1] == positions[0]:
        print(f"error: {name} did not move", file=sys.stderr)
        return 1
    print("every published frame was read, in order")
    return 0


if __name__ == "__main__":
    sys.exit(main())
