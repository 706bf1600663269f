"""Commissioning a device: a change of the board's own settings — its bus address, its line
rate, a reset to its factory settings — that the server's driver sends before it finds the
board again where it now answers (``CommandKind.COMMISSION``, ``motionctl commission``).

The server takes it only from a client holding the claim of every axis and signal of the
device (:meth:`Client.claim_device`), while none of its axes moves::

    with client.claim_device("pack_aux"):
        accepted = client.commission("pack_aux", address=5)
        found = client.wait_commissioned("pack_aux", accepted)
    print(f"put address = {found.address} in [[device]] pack_aux")

The config still names the old setting afterwards: tell whoever keeps it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, List, Optional

from .errors import NoSuchDevice, NotClaimed, NotRecommissioned
from .ipc import CommandKind, CommissionWhat, DeviceState, Target
from .session import Accepted

#: The client these functions work through (a :class:`~motiond.Client`; not imported here:
#: the client imports this module).
Client = Any


@dataclass(frozen=True)
class Commissioned:
    """A device found again after a commission."""

    #: The device's name.
    device: str
    #: Its bus address as the server now talks to it.
    address: int
    #: Its firmware as it reported it when found.
    firmware: str
    #: Seconds from the accepting tick to the first frame showing it online.
    took: float


class DeviceClaim:
    """The claims of every axis and signal of a device, released when the ``with`` block
    ends (or by :meth:`release`). Made by :meth:`Client.claim_device`, which takes them at
    once (a claim another client holds raises :class:`~motiond.errors.ClaimedByOther`, and
    the ones taken are given back)."""

    def __init__(self, client: Client, device: str) -> None:
        self._client = client
        self.device = device
        index = device_index(client, device)
        info = client.info
        self._held: List[tuple] = []
        targets = [
            (Target.AXIS, a)
            for a in range(int(info.axis_count))
            if int(info.axes[a].device_index) == index
        ] + [
            (Target.SIGNAL, s)
            for s in range(int(info.signal_count))
            if int(info.signals[s].device_index) == index
        ]
        try:
            for target, entry in targets:
                client.command(entry, CommandKind.CLAIM, target=target)
                self._held.append((target, entry))
        except BaseException:
            self.release()
            raise
        self.active = True

    def release(self) -> None:
        """Gives the claims back (a claim the server no longer has is not an error)."""
        held, self._held = self._held, []
        self.active = False
        for target, entry in held:
            try:
                self._client.command(entry, CommandKind.RELEASE, target=target)
            except NotClaimed:
                pass

    def __enter__(self) -> "DeviceClaim":
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __repr__(self) -> str:
        state = "held" if self.active else "released"
        return f"DeviceClaim({self.device!r}, {state})"


def device_index(client: Client, name: str) -> int:
    """The index (config order) of device ``name``."""
    info = client.info
    for index in range(int(info.device_count)):
        if info.devices[index].text("name") == name:
            return index
    raise NoSuchDevice(name)


def commission(
    client: Client,
    device: str,
    *,
    address: Optional[int] = None,
    baud: Optional[int] = None,
    factory_reset: bool = False,
) -> Accepted:
    """Sends the commission of ``device`` (exactly one of ``address``, ``baud``,
    ``factory_reset``)."""
    given = [address is not None, baud is not None, bool(factory_reset)]
    if sum(given) != 1:
        raise ValueError("give exactly one of address=, baud=, factory_reset=True")
    if address is not None:
        what, value = CommissionWhat.ADDRESS, int(address)
    elif baud is not None:
        what, value = CommissionWhat.BAUD, int(baud)
    else:
        what, value = CommissionWhat.FACTORY_RESET, 0
    if not 0 <= value <= 0xFFFF_FFFF:
        raise ValueError(f"{value} is not a value a device takes")
    index = device_index(client, device)
    return client.command(
        index,
        CommandKind.COMMISSION,
        (float(what), float(value), 0.0),
        target=Target.DEVICE,
        label=f"device {device}",
    )


def wait_commissioned(
    client: Client, device: str, accepted: Accepted, timeout: float = 5.0
) -> Commissioned:
    """Waits until ``device`` is online again after the commission ``accepted``; raises
    :class:`~motiond.errors.NotRecommissioned` when it is not by ``timeout``."""
    index = device_index(client, device)
    deadline = time.monotonic() + timeout
    state = DeviceState.STARTING
    found_tick = None
    frame = client.latest()
    while True:
        if frame.tick >= accepted.tick:
            states = frame.device_states()
            state = states[index] if index < len(states) else DeviceState.OFFLINE
            if state == DeviceState.ONLINE:
                found_tick = frame.tick
                break
        now = time.monotonic()
        if now >= deadline:
            break
        del frame
        try:
            frame = client.next_frame(deadline - now)
        except Exception:  # NoFrame: judged below
            break
    if found_tick is None:
        raise NotRecommissioned(device, state, timeout)
    settle = time.monotonic() + 0.3
    while True:
        entry = client.info.devices[index]
        if int(entry.state) == int(DeviceState.ONLINE) or time.monotonic() >= settle:
            break
        time.sleep(0.01)
    return Commissioned(
        device=device,
        address=int(entry.address),
        firmware=entry.text("firmware"),
        took=(found_tick - accepted.tick) / max(1, client.tick_hz),
    )
