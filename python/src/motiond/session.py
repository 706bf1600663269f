"""What a client shares with its handles and transports, below all of them.

- :class:`Accepted` and :class:`Param`, what the server answers;
- the default timeouts;
- :class:`JogRegistry`, the client's running jogs, renewed on every read and wait;
- :class:`Session`, the calls :class:`~motiond.axis.Axis`, :class:`~motiond.signal.Signal`,
  :class:`~motiond.jog.Jog`, :class:`~motiond.group.Group` and
  :class:`~motiond.stream.SetpointStream` make on the client that made them;
- :class:`EntryHandle`, what an axis and a signal handle have in common.

None of them imports :mod:`motiond.client`: the package's imports run one way (``ipc`` ←
``errors`` ← ``frames`` ← ``session`` ← ``answers``, ``jog``, ``axis``, ``signal``,
``groupstate`` ← ``stream`` ← ``group`` ← ``client`` ← ``remote``).
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterator, Optional, Protocol, Union

from .ipc import ParamOwner, Reason

if TYPE_CHECKING:  # pragma: no cover
    from .frames import Frame
    from .ipc import ServerInfo

__all__ = [
    "Accepted",
    "Param",
    "JogRegistry",
    "Session",
    "EntryHandle",
    "DEFAULT_CONNECT_TIMEOUT",
    "DEFAULT_REPLY_TIMEOUT",
]

#: How long :class:`~motiond.Client` retries by default before saying no server runs, s.
DEFAULT_CONNECT_TIMEOUT = 2.0
#: How long a command waits for its reply by default, s.
DEFAULT_REPLY_TIMEOUT = 1.0
# Shortest jog renewal period, whatever the deadman.
_MIN_REFRESH = 0.005


@dataclass(frozen=True)
class Accepted:
    """A command the server accepted."""

    #: The sequence number the client gave the request.
    sequence: int
    #: The tick in which the command took effect.
    tick: int


@dataclass(frozen=True)
class Param:
    """One machine parameter in effect (``motiond/<name>/params``)."""

    #: ``ParamOwner.DEVICE`` or ``ParamOwner.AXIS``.
    owner: Union[ParamOwner, int]
    #: Device or axis index, config order.
    owner_index: int
    #: Device or axis name.
    owner_name: str
    #: The config key, dotted for tables (``current.standstill``).
    key: str
    #: The value in effect, with its unit (``50 %``).
    value: str
    #: ``True`` when the config file set it, ``False`` for the default.
    from_config: bool


class RenewedGoal(Protocol):
    """What :class:`JogRegistry` needs of a running jog (:class:`~motiond.jog.Jog`)."""

    active: bool
    refused: Optional[Union[Reason, int]]
    expired: bool
    last_sent: float

    def _renew(self) -> None: ...

    def stop(self) -> None: ...


def refresh_period(command_timeout_ms: int) -> Optional[float]:
    """How often a jog is renewed under a deadman of ``command_timeout_ms`` (a third of it,
    at least :data:`_MIN_REFRESH`); ``None`` when the server has no deadman."""
    if command_timeout_ms <= 0:
        return None
    return max(command_timeout_ms / 3000.0, _MIN_REFRESH)


class JogRegistry:
    """The running jogs of one client, held weakly: a jog nobody holds any more is
    garbage collected (and stops its axis)."""

    def __init__(self) -> None:
        self._jogs: "weakref.WeakValueDictionary[int, RenewedGoal]" = (
            weakref.WeakValueDictionary()
        )
        self._next = 0

    def register(self, jog: RenewedGoal) -> int:
        """Adds ``jog``; its key for :meth:`forget`."""
        self._next += 1
        self._jogs[self._next] = jog
        return self._next

    def forget(self, key: int) -> None:
        """Removes the jog of ``key`` (it ended)."""
        self._jogs.pop(key, None)

    def __bool__(self) -> bool:
        return bool(self._jogs)

    def __iter__(self) -> Iterator[RenewedGoal]:
        return iter(list(self._jogs.values()))

    def wait_cap(self, remaining: float, period: Optional[float]) -> float:
        """``remaining``, shortened so that a sleeping client wakes in time to renew."""
        if period is None:
            return remaining
        now = time.monotonic()
        for jog in self:
            if jog.active and jog.refused is None and not jog.expired:
                remaining = min(remaining, max(0.0, jog.last_sent + period - now))
        return remaining

    def renew_due(self, period: Optional[float], deadman: float) -> None:
        """Renews every running jog whose renewal is due. A jog not renewed for a whole
        ``deadman`` has been stopped by the server: it is marked expired and not renewed
        any more, so that a program that hung does not set the axis moving again when it
        wakes up."""
        if period is None or not self._jogs:
            return
        now = time.monotonic()
        for jog in self:
            if not jog.active or jog.refused is not None or jog.expired:
                continue
            if now - jog.last_sent >= deadman:
                jog.expired = True
            elif now >= jog.last_sent + period:
                jog._renew()


class Session(Protocol):
    """The calls a client's handles make on it: :class:`~motiond.Client` and
    :class:`~motiond.RemoteClient` both answer them, with the signatures of
    :meth:`Client.command <motiond.Client.command>`, :meth:`~motiond.Client.wait_frames`,
    :meth:`~motiond.Client.wait_ready`, :meth:`~motiond.Client.latest` and
    :meth:`~motiond.Client.goal_tick`."""

    _jogs: JogRegistry
    latest: Callable[[], "Frame"]
    command: Callable[..., Accepted]
    wait_frames: Callable[..., "Frame"]
    wait_ready: Callable[..., "Frame"]
    goal_tick: Callable[[int], int]
    # What the groups use (:class:`~motiond.group.Group`, :class:`~motiond.stream.SetpointStream`).
    _wait_tick: Callable[[float], None]
    _paths_port: Callable[[], Any]
    _setpoints_port: Callable[[], Any]
    _next_path_id: Callable[[], int]

    @property
    def info(self) -> "ServerInfo": ...

    @property
    def id(self) -> Any: ...


class EntryHandle:
    """A handle on one entry of the server's description, an axis or a signal: the client
    that made it and the entry's index. A subclass names its table (``_table``: ``"axes"``
    or ``"signals"`` of :class:`~motiond.ipc.ServerInfo`)."""

    __slots__ = ("_client", "_index")
    _table: str = ""

    def __init__(self, client: Session, index: int) -> None:
        self._client = client
        self._index = index

    def _entry(self) -> Any:
        """The entry in the client's description (shared, not a copy): an
        :class:`~motiond.ipc.AxisInfo` or a :class:`~motiond.ipc.SignalInfo`."""
        return getattr(self._client.info, self._table)[self._index]

    @property
    def index(self) -> int:
        """The index (config order), as used in frames and requests."""
        return self._index

    @property
    def name(self) -> str:
        """The name in the config."""
        return self._entry().text("name")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, index={self._index})"
