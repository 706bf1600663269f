"""``python -m motiond list|status|params``: a look at a running server.

``list`` prints what the server drives (axes with units, limits and commands; devices;
signals), ``status`` the newest frame (every axis and signal), ``params`` the machine
parameters in effect. ``--server NAME`` picks the instance (default ``demo``);
``--remote tcp/HOST:7447`` reaches it on another host through its ``motion-bridge``.
"""

from __future__ import annotations

import argparse
import enum
import sys
from typing import List, Optional, Sequence, TextIO

from .client import Client
from .errors import MotiondError
from .ipc import (
    AxisFlags,
    AxisMode,
    CommandKind,
    DeviceState,
    FaultCode,
    FrameFlags,
    SignalFlags,
    SignalKind,
    to_enum,
)


def _name(value: object) -> str:
    text = getattr(value, "text", None)
    return str(text) if text is not None else str(value)


def _flags(flags: enum.IntFlag) -> str:
    names = [str(member.name).lower() for member in type(flags) if member in flags]
    return ",".join(names) if names else "-"


def _table(rows: List[List[str]], out: TextIO) -> None:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        out.write("  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip())
        out.write("\n")


def list_server(client: Client, out: TextIO) -> None:
    """Prints the server's description."""
    info = client.info
    out.write(
        f"motiond {info.text('name')!r}: {info.tick_hz} Hz, deadman "
        f"{info.command_timeout_ms} ms, pid {info.server_pid}, schema {info.schema_version}\n"
    )
    rows = [["axis", "device", "unit", "min", "max", "max_velocity", "max_accel", "commands"]]
    for axis in client.axes:
        a = axis.info
        commands = [kind.text for kind in CommandKind if a.supports(kind)]
        rows.append(
            [
                a.text("name"),
                a.text("device"),
                a.text("unit"),
                f"{a.min:g}",
                f"{a.max:g}",
                f"{a.max_velocity:g}",
                f"{a.max_accel:g}",
                " ".join(commands),
            ]
        )
    out.write("\n")
    _table(rows, out)
    rows = [["device", "model", "link", "address", "axes", "firmware"]]
    for index in range(info.device_count):
        d = info.devices[index]
        rows.append(
            [
                d.text("name"),
                d.model_name(),
                d.text("link"),
                f"{d.address:#x}" if d.address else "-",
                str(d.axis_count),
                d.text("firmware") or "-",
            ]
        )
    out.write("\n")
    _table(rows, out)
    if info.signal_count:
        rows = [["signal", "kind", "device", "pin", "unit"]]
        for signal in client.signals:
            s = signal.info
            rows.append(
                [
                    s.text("name"),
                    _name(to_enum(SignalKind, s.kind)),
                    s.text("device"),
                    s.text("pin"),
                    s.text("unit") or "-",
                ]
            )
        out.write("\n")
        _table(rows, out)


def status(client: Client, out: TextIO) -> None:
    """Prints the newest frame."""
    frame = client.latest()
    flags = FrameFlags(frame.payload.flags)
    devices = ", ".join(
        f"{client.info.devices[i].text('name')} {_name(state)}"
        for i, state in enumerate(frame.device_states())
    )
    out.write(f"tick {frame.tick}  flags {_flags(flags)}\ndevices: {devices}\n\n")
    rows = [["axis", "position", "velocity", "unit", "mode", "flags", "fault", "device"]]
    for axis in client.axes:
        s = axis.state(frame)
        mode = s.mode.name.lower() if isinstance(s.mode, AxisMode) else str(s.mode)
        fault = "-" if s.fault == FaultCode.NONE else _name(s.fault)
        rows.append(
            [
                axis.name,
                f"{s.position:.4f}",
                f"{s.velocity:.4f}",
                axis.unit,
                mode,
                _flags(AxisFlags(s.flags)),
                fault,
                _name(to_enum(DeviceState, s.device_state)),
            ]
        )
    _table(rows, out)
    if frame.signal_count:
        rows = [["signal", "value", "raw", "unit", "flags"]]
        for signal in client.signals:
            status = signal.state(frame)
            rows.append(
                [
                    signal.name,
                    f"{status.value:g}",
                    f"{status.raw:g}",
                    signal.unit or "-",
                    _flags(SignalFlags(status.flags)),
                ]
            )
        out.write("\n")
        _table(rows, out)


def params(client: Client, out: TextIO) -> None:
    """Prints the machine parameters in effect."""
    rows = [["owner", "key", "value", "from"]]
    for param in client.params():
        rows.append(
            [
                f"{_name(param.owner)} {param.owner_name}",
                param.key,
                param.value,
                "config" if param.from_config else "default",
            ]
        )
    _table(rows, out)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m motiond", description="Look at a running motiond server."
    )
    parser.add_argument("command", choices=["list", "status", "params"])
    parser.add_argument("--server", default="demo", help="instance name ([server] name)")
    parser.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for the server")
    parser.add_argument(
        "--remote",
        metavar="ENDPOINT",
        help="reach the server through its motion-bridge (zenoh), e.g. tcp/host-a:7447",
    )
    parser.add_argument("--identity", help="the identity to use with --remote (default anonymous)")
    parser.add_argument(
        "--zenoh-config", metavar="FILE", help="zenoh's JSON5 config for --remote (TLS, credentials)"
    )
    args = parser.parse_args(argv)
    remote = {}
    if args.remote is not None:
        remote = {"remote": args.remote, "identity": args.identity or "anonymous"}
        if args.zenoh_config is not None:
            remote["zenoh_config"] = args.zenoh_config
    elif args.identity is not None or args.zenoh_config is not None:
        parser.error("--identity and --zenoh-config need --remote")
    try:
        with Client(args.server, timeout=args.timeout, **remote) as client:
            {"list": list_server, "status": status, "params": params}[args.command](
                client, sys.stdout
            )
    except MotiondError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
