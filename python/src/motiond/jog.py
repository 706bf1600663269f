"""A velocity or power goal that lives as long as a block of your program: :class:`Jog`.

The server stops velocity and power goals that are not renewed within its deadman
(``command_timeout_ms`` of the server config, :attr:`Client.command_timeout`). A running
jog renews its goal every third of that time whenever the program calls into the client:
any read or wait (:meth:`Client.latest`, :meth:`Client.frames`, :meth:`Axis.state`, the
waits) or :meth:`Client.keep_alive`. There is no background thread on purpose: a program
that hangs, or stops calling into the client, lets the server's deadman stop the axis, and
the jog then stays stopped (:attr:`Jog.expired`) until :meth:`Jog.set` starts it again.

Leaving the ``with`` block (normally, by an exception or by Ctrl-C) stops the axis at
once::

    with x.jog(-2.0):
        for frame in client.frames():
            if frame.axis(x.index).position < 5.0:
                break
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Optional, Sequence, Tuple, Union

from . import errors
from .ipc import CommandKind, Reason

if TYPE_CHECKING:  # pragma: no cover
    from .session import Accepted, Session

__all__ = ["Jog"]


class Jog:
    """A running jog (velocity or power goal) that stops its axis when it ends.

    Made by :meth:`Axis.jog` and :meth:`Axis.jog_power`, which send the first goal at once
    (raising the server's refusal if it is refused). Use it as a context manager, or call
    :meth:`stop`; a jog that is garbage collected stops its axis too.
    """

    def __init__(
        self,
        client: "Session",
        axis: int,
        kind: CommandKind,
        values: Sequence[float],
    ) -> None:
        self._client = client
        self._axis = axis
        self._kind = kind
        self._values: Tuple[float, float, float] = (
            float(values[0]),
            float(values[1]),
            float(values[2]),
        )
        self.active = False
        #: The reason the server gave when it last refused a renewal; once refused, the
        #: jog stops renewing (the server has stopped the axis).
        self.refused: Optional[Union[Reason, int]] = None
        #: ``time.monotonic()`` of the last goal sent.
        self.last_sent = time.monotonic()
        #: Renewals sent so far (the first goal not counted).
        self.renewals = 0
        #: ``True`` once the jog went a whole deadman without renewal: the server has
        #: stopped the axis, and the jog does not restart it (:meth:`set` does).
        self.expired = False
        client.command(axis, kind, self._values)
        self.last_sent = time.monotonic()
        self.active = True
        self._key = client._jogs.register(self)

    @property
    def axis(self) -> int:
        """The axis index."""
        return self._axis

    def _send(self) -> "Accepted":
        try:
            accepted = self._client.command(self._axis, self._kind, self._values)
        except errors.Refused as refusal:
            self.refused = refusal.reason
            raise
        finally:
            self.last_sent = time.monotonic()
        self.refused = None
        return accepted

    def _renew(self) -> None:
        """Sends the goal again (called by the client's reads and waits)."""
        try:
            self._send()
            self.renewals += 1
        except errors.MotiondError:
            # Refused (e-stop, claim, limit) or no answer: the server's deadman stops the
            # axis; `refused` tells why.
            pass

    def set(self, value: float) -> "Accepted":
        """Changes the jog's velocity (or power) and sends it now."""
        if not self.active:
            raise errors.MotiondError("the jog has ended")
        self._values = (float(value), self._values[1], self._values[2])
        accepted = self._send()
        self.expired = False
        return accepted

    def stop(self) -> None:
        """Ends the jog: stops the axis (decelerate and hold) and stops renewing."""
        if not self.active:
            return
        self.active = False
        self._client._jogs.forget(self._key)
        self._client.command(self._axis, CommandKind.STOP)

    def __enter__(self) -> "Jog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def __del__(self) -> None:
        # Best effort: a jog nobody holds any more stops its axis (if that fails, the
        # server's deadman does it).
        try:
            if self.active:
                self.stop()
        except BaseException:  # noqa: BLE001 - nothing may escape a finaliser
            pass

    def __repr__(self) -> str:
        state = "active" if self.active else "ended"
        return f"Jog(axis={self._axis}, kind={self._kind.name}, values={self._values}, {state})"
