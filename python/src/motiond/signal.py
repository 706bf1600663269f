"""Board I/O as named signals: :class:`Signal` and :class:`SignalStatus`, and the events
of capture and trigger signals (:class:`SignalEvent`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Optional, Union

from .frames import Frame
from .ipc import (
    CommandKind,
    SignalFlags,
    SignalInfo,
    SignalInfoFlags,
    SignalKind,
    Target,
    to_enum,
)

from .session import EntryHandle

if TYPE_CHECKING:  # pragma: no cover
    from .session import Accepted

__all__ = ["Signal", "SignalEvent", "SignalStatus"]


@dataclass(frozen=True)
class SignalStatus:
    """One signal's state in one frame (a copy; see :class:`~motiond.ipc.SignalState`)."""

    #: Signal index, config order.
    index: int
    #: The frame's tick.
    tick: int
    #: Logical value: digital 0.0/1.0 after ``invert``; analogue raw × scale + offset.
    value: float
    #: As the board reports it: electrical level 0/1, or ADC counts.
    raw: float
    #: Tick at which the board last reported it (outputs: acknowledged it).
    last_refresh_tick: int
    #: State flags.
    flags: SignalFlags
    #: What the signal is.
    kind: Union[SignalKind, int]
    #: Node id of the client holding a claim on an output, 0 when unclaimed.
    claimed_by: int
    #: A capture's or a trigger's events since the server started (wrapping at 2**32);
    #: 0 for the other kinds.
    sequence: int = 0
    #: The tick that took the newest event in; 0 before the first.
    event_tick: int = 0

    def events_since(self, seen: int) -> int:
        """Events between a status with sequence ``seen`` and this one (1: the next one;
        more: some were missed), through the wrap at 2**32."""
        return (self.sequence - seen) % (1 << 32)

    @property
    def on(self) -> bool:
        """A digital signal's logical value (``value >= 0.5``)."""
        return self.value >= 0.5

    @property
    def stale(self) -> bool:
        """Older than its board's refresh budget (or never read)."""
        return SignalFlags.STALE in self.flags

    @property
    def pending(self) -> bool:
        """An output value was commanded and the board has not acknowledged it yet."""
        return SignalFlags.PENDING in self.flags

    @property
    def safe_state(self) -> bool:
        """The e-stop put the output into its configured safe state."""
        return SignalFlags.SAFE_STATE in self.flags


@dataclass(frozen=True)
class SignalEvent:
    """A capture or a trigger pulse, as :meth:`Signal.wait_event` found it in a frame."""

    #: The signal's sequence: events since the server started.
    sequence: int
    #: The tick that took the event in.
    tick: int
    #: The signal's value then: a capture's position, a trigger's compare position.
    value: float
    #: Its raw value (counter counts).
    raw: float
    #: Events between the sequence waited after and this one that no frame showed apart
    #: (two taken in by one tick, or frames not read): 0 when this is the next one.
    missed: int


class Signal(EntryHandle):
    """One named signal (board input or output), found with :meth:`Client.signal`."""

    __slots__ = ()
    _table = "signals"

    @property
    def info(self) -> SignalInfo:
        """The signal's static description (a copy)."""
        return self._entry().copy()

    @property
    def kind(self) -> Union[SignalKind, int]:
        """Digital input, digital output or analogue input."""
        return to_enum(SignalKind, self._entry().kind)

    @property
    def unit(self) -> str:
        """The unit of an analogue value ("" for digital)."""
        return self._entry().text("unit")

    @property
    def inverted(self) -> bool:
        """Digital: the logical value is the inverse of the electrical level."""
        return SignalInfoFlags.INVERT in SignalInfoFlags(self._entry().flags)

    def state(self, frame: Optional[Frame] = None) -> SignalStatus:
        """The signal's state in ``frame`` (default: the newest frame), a copy."""
        if frame is None:
            frame = self._client.latest()
        raw = frame.signal(self._index)
        return SignalStatus(
            index=self._index,
            tick=frame.tick,
            value=float(raw.value),
            raw=float(raw.raw),
            last_refresh_tick=int(raw.last_refresh_tick),
            flags=SignalFlags(raw.flags),
            kind=to_enum(SignalKind, raw.kind),
            claimed_by=int(raw.claimed_by),
            sequence=int(raw.sequence),
            event_tick=int(raw.event_tick),
        )

    def value(self) -> float:
        """The logical value in the newest frame."""
        return self.state().value

    def is_on(self) -> bool:
        """A digital signal's logical value in the newest frame."""
        return self.state().on

    def _command(self, kind: CommandKind, value: float = 0.0) -> "Accepted":
        return self._client.command(
            self._index, kind, (value, 0.0, 0.0), Target.SIGNAL, label=f"signal {self.name}"
        )

    def set(self, on: bool) -> "Accepted":
        """Sets a digital output to its logical value ``on`` (``SetOutput``)."""
        return self._command(CommandKind.SET_OUTPUT, 1.0 if on else 0.0)

    def set_value(self, value: float) -> "Accepted":
        """Sets a trigger's compare position (``SetOutput`` on a ``trigger`` signal), in
        the signal's unit (by default the axis's): the board pulses its output when the
        count matches it. Raises :class:`~motiond.errors.NotAnOutput` for other kinds,
        :class:`~motiond.errors.OutOfRange` for a position the counter cannot hold."""
        return self._command(CommandKind.SET_OUTPUT, float(value))

    def sequence(self) -> int:
        """The sequence in the newest frame: captures or trigger pulses since the server
        started (0 for other kinds). Pass it to :meth:`wait_event`."""
        return self.state().sequence

    def wait_event(self, after: int, timeout: float = 2.0) -> SignalEvent:
        """Waits for the next capture or trigger pulse after sequence ``after``: the first
        frame whose sequence differs. :attr:`SignalEvent.missed` counts the events in
        between that no frame showed apart. Raises :class:`~motiond.errors.WaitTimeout`."""

        def done(frame: Frame) -> bool:
            status = self.state(frame)
            return not status.stale and status.sequence != after

        frame = self._client.wait_frames(
            f"an event after sequence {after}", timeout, done, subject=f"signal {self.name}"
        )
        status = self.state(frame)
        return SignalEvent(
            sequence=status.sequence,
            tick=status.event_tick,
            value=status.value,
            raw=status.raw,
            missed=max(status.events_since(after) - 1, 0),
        )

    def claim(self) -> "Accepted":
        """Takes an exclusive claim on the output."""
        return self._command(CommandKind.CLAIM)

    def release(self) -> "Accepted":
        """Gives a claim back."""
        return self._command(CommandKind.RELEASE)

    def wait_for(
        self,
        expected: Union[bool, float, Callable[[SignalStatus], bool]],
        timeout: float = 2.0,
    ) -> SignalStatus:
        """Waits until the signal has the logical value ``expected`` (a ``bool`` for a
        digital signal; a number is compared exactly) or, given a function, until it
        returns true for the signal's :class:`SignalStatus`. A value the server has not
        yet confirmed (``pending``, or ``stale``) does not count. Returns the status that
        matched."""
        if callable(expected):
            test = expected
        elif isinstance(expected, bool):

            def test(status: SignalStatus) -> bool:
                return status.on == expected

        else:
            wanted = float(expected)

            def test(status: SignalStatus) -> bool:
                return status.value == wanted

        def done(frame: Frame) -> bool:
            status = self.state(frame)
            return not status.pending and not status.stale and bool(test(status))

        frame = self._client.wait_frames(
            f"reach {expected!r}", timeout, done, subject=f"signal {self.name}"
        )
        return self.state(frame)
