"""Setpoints streamed to a group tick by tick: :class:`SetpointStream`.

:meth:`Group.stream <motiond.group.Group.stream>` claims the group, sends ``Stream`` and
returns the stream; each :meth:`~SetpointStream.send` publishes one
:class:`~motiond.ipc.Setpoint` on the server's ``setpoints`` service, addressed to a tick
(``for_tick``: a frame's tick + 1 is the next tick). The server applies each setpoint on
its own time, once and in order: the one for tick ``k`` in tick ``k + stream_delay``, where
the stream's delay grows to the lateness of a setpoint that arrived after its tick (at most
``stream_buffer``; one later still is dropped, ``late``) and never shrinks while the stream
runs; velocities and accelerations are judged over the setpoints' own ticks. One for a
tick more than ``stream_buffer`` ahead is dropped (``early``); when none arrives for
``stream_timeout`` ticks the server stops the group (stream ``stale``).

:meth:`~SetpointStream.run_each_tick` answers frame ``k`` with the setpoint for
``k + lead`` (:data:`DEFAULT_LEAD` unless set): a lead above the client's scheduling jitter
keeps the delay at 0. Leaving the ``with`` block cancels the stream and releases the
claim::

    with client.group("base").stream("velocity") as stream:
        stream.run_each_tick(lambda frame: [10.0, -10.0], duration=2.0)
        print(stream.wait_applied())     # the group's counters: applied, late, early …
"""

from __future__ import annotations

import ctypes
import time
from array import array
from typing import Any, Callable, Dict, Optional, Sequence, Union

from .errors import (
    BadPath,
    MotiondError,
    NoFrame,
    NotClaimed,
    NotMoving,
    StreamClosed,
    WaitAborted,
    WaitTimeout,
)
from .frames import Frame
from .groupstate import GroupStatus, aborted_error
from .ipc import (
    SCHEMA_VERSION,
    CommandKind,
    GroupMotion,
    GroupState,
    Setpoint,
    SetpointFlags,
    StreamMode,
    StreamState,
    Target,
    to_enum,
)
from .session import Accepted, Session

__all__ = ["DEFAULT_LEAD", "SetpointStream"]

#: Ticks ahead of the frame read that :meth:`SetpointStream.run_each_tick` sends for unless
#: told otherwise (the same as the Rust client's ``DEFAULT_STREAM_LEAD``).
#: ``motionctl bench``'s stream phase measures the share of ticks a Python client meets with
#: lead 1 and with this lead, beside ``--busy-loops N`` spinning processes
#: (docs/PERFORMANCE.md "Coordinated motion and streams").
DEFAULT_LEAD = 2

_DOUBLE = ctypes.sizeof(ctypes.c_double)
_SIZE = ctypes.sizeof(Setpoint)
_VALUES = Setpoint.values.offset
_VELOCITIES = Setpoint.velocities.offset
_MODES = {
    "position": StreamMode.POSITION,
    "velocity": StreamMode.VELOCITY,
    "power": StreamMode.POWER,
}


def stream_mode(mode: Union[str, StreamMode, int]) -> StreamMode:
    """``mode`` as a :class:`~motiond.ipc.StreamMode` (``"position"``, ``"velocity"``,
    ``"power"``)."""
    if isinstance(mode, str):
        if mode in _MODES:
            return _MODES[mode]
    elif int(mode) in (int(m) for m in _MODES.values()):
        return StreamMode(int(mode))
    raise BadPath(f"stream mode {mode!r}: one of {', '.join(_MODES)}")


class SetpointStream:
    """A running setpoint stream to one group, holding the group's claim.

    Sequence numbers are given by :meth:`send` (1, 2, … per stream). The stream keeps
    what it sent and what the frames it read showed applied:

    - :attr:`sent`: setpoints published;
    - :attr:`observed`: of those, seen applied in a frame (a frame shows the last one
      applied: one the client read no frame for is not observed);
    - :attr:`applied_before_tick`: observed applied in a tick before their ``for_tick``
      (the server never should);
    - :attr:`applied_after_tick`: observed applied in a later tick than their
      ``for_tick`` (they reached the server late, the tick had passed) and
      :attr:`max_delay`, the most ticks after;
    - :attr:`skipped`: frames :meth:`run_each_tick` did not answer because the previous
      setpoint was overdue and not applied yet (see its ``one_in_flight``).

    The server's own counters are in :meth:`state` (``applied``, ``late``, ``early``,
    ``clamped``, ``refused``).
    """

    def __init__(
        self,
        client: Session,
        index: int,
        name: str,
        axis_count: int,
        mode: Union[str, StreamMode, int],
        *,
        lead: Optional[int] = None,
    ) -> None:
        self._client = client
        self._index = index
        self._name = name
        self._count = axis_count
        self._mode = stream_mode(mode)
        self._active = False
        self._claimed = False
        # Before the claim: a client that cannot publish (remote) fails with nothing taken.
        self._publisher = client._setpoints_port()
        timeout = int(client.info.groups[index].stream_timeout)
        self._buffer = int(client.info.groups[index].stream_buffer)
        self._lead = DEFAULT_LEAD
        if lead is not None:
            self.lead = lead
        #: Ticks :meth:`run_each_tick` waits for the previous setpoint past its tick.
        self.patience = max(2, timeout // 4)
        #: Setpoints published.
        self.sent = 0
        #: The sequence number of the last setpoint published (0: none yet).
        self.sequence = 0
        #: The ``for_tick`` of the last setpoint published.
        self.last_for_tick = 0
        self.observed = 0
        self.applied_before_tick = 0
        self.applied_after_tick = 0
        self.max_delay = 0
        self.skipped = 0
        self._for_ticks: Dict[int, int] = {}
        self._seen_sequence = 0
        self._command(CommandKind.CLAIM)
        self._claimed = True
        try:
            accepted = self._command(CommandKind.STREAM, float(int(self._mode)))
        except BaseException:
            self._release()
            raise
        #: The server's answer to ``Stream`` (its tick: the stream's first).
        self.started: Accepted = accepted
        self._active = True

    # --- description -----------------------------------------------------------------------

    @property
    def group(self) -> str:
        """The group's name."""
        return self._name

    @property
    def mode(self) -> StreamMode:
        """What the values are: positions, velocities or powers."""
        return self._mode

    @property
    def lead(self) -> int:
        """Ticks ahead of the frame it read that :meth:`run_each_tick` sends for: after
        frame ``k`` the setpoint for ``k + lead``. 1 is the least latency and suits a
        client that always answers within the tick; a larger lead absorbs that much
        scheduling jitter before a setpoint arrives late (which grows the stream's delay for
        the rest of the stream). 1 to the group's ``stream_buffer`` + 1."""
        return self._lead

    @lead.setter
    def lead(self, ticks: int) -> None:
        most = self._buffer + 1
        if isinstance(ticks, bool) or not isinstance(ticks, int) or not 1 <= ticks <= most:
            raise BadPath(
                f"group {self._name}: a lead of {ticks!r} ticks is outside 1..={most} "
                "(its stream_buffer + 1)"
            )
        self._lead = ticks

    @property
    def active(self) -> bool:
        """Whether the stream is open (not closed yet)."""
        return self._active

    def state(self, frame: Optional[Frame] = None) -> GroupStatus:
        """The group's state in ``frame`` (default: the newest frame), a copy."""
        if frame is None:
            frame = self._client.latest()
        return GroupStatus.of(
            self._client.info, self._index, frame.tick, frame.group(self._index)
        )

    # --- sending ---------------------------------------------------------------------------

    def _command(self, kind: CommandKind, *values: float) -> Accepted:
        return self._client.command(
            self._index, kind, values, Target.GROUP, label=f"group {self._name}"
        )

    def _row(self, values: Sequence[float], what: str) -> array:
        try:
            row = array("d", values)
        except TypeError:
            raise BadPath(f"{what} must be {self._count} numbers, not {values!r}") from None
        if len(row) != self._count:
            raise BadPath(
                f"{what}: {len(row)} values; group {self._name} has {self._count} axes"
            )
        return row

    def send(
        self,
        for_tick: int,
        values: Sequence[float],
        velocities: Optional[Sequence[float]] = None,
    ) -> int:
        """Publishes the setpoint for tick ``for_tick``: ``values`` per axis in the group's
        order (positions, velocities or powers, as the stream's mode), with a velocity
        feed-forward per axis when ``velocities`` is given. Returns its sequence number.
        The server counts what it does with it (:meth:`state`)."""
        if not self._active:
            raise StreamClosed(self._name)
        row = self._row(values, "values")
        feed = None if velocities is None else self._row(velocities, "velocities")
        try:
            sample = self._publisher.loan_uninit()
        except Exception as error:
            raise MotiondError(f"could not loan a setpoint sample: {error!r}") from error
        base = int(sample.payload_ptr)
        ctypes.memset(base, 0, _SIZE)
        setpoint = Setpoint.from_address(base)
        setpoint.schema_version = SCHEMA_VERSION
        setpoint.group = self._index
        setpoint.sequence = self.sequence + 1
        setpoint.for_tick = int(for_tick)
        setpoint.mode = int(self._mode)
        setpoint.flags = 0 if feed is None else int(SetpointFlags.FEED_FORWARD)
        del setpoint
        ctypes.memmove(base + _VALUES, row.buffer_info()[0], _DOUBLE * self._count)
        if feed is not None:
            ctypes.memmove(base + _VELOCITIES, feed.buffer_info()[0], _DOUBLE * self._count)
        try:
            sample.assume_init().send()
        except Exception as error:
            raise MotiondError(f"could not publish the setpoint: {error!r}") from error
        self.sequence += 1
        self.sent += 1
        self.last_for_tick = int(for_tick)
        self._for_ticks[self.sequence] = int(for_tick)
        return self.sequence

    # --- reading ---------------------------------------------------------------------------

    def _observe(self, state: GroupState, tick: int) -> None:
        """Notes what a frame at ``tick`` shows applied."""
        if tick < self.started.tick:
            return
        sequence = int(state.last_sequence)
        if sequence <= self._seen_sequence:
            return
        self._seen_sequence = sequence
        for_tick = self._for_ticks.get(sequence)
        if for_tick is not None:
            self.observed += 1
            delay = int(state.last_applied_tick) - for_tick
            if delay < 0:
                self.applied_before_tick += 1
            elif delay > 0:
                self.applied_after_tick += 1
                self.max_delay = max(self.max_delay, delay)
        for old in [s for s in self._for_ticks if s <= sequence]:
            del self._for_ticks[old]

    def _check_running(self, state: GroupState, tick: int, what: str) -> None:
        """Raises when a frame at ``tick`` shows the stream no longer running."""
        if tick < self.started.tick or state.stream == StreamState.STREAMING:
            return
        if state.motion == GroupMotion.ABORTED:
            raise aborted_error(self._client.info, self._name, what, state, tick)
        stream = to_enum(StreamState, state.stream)
        text = stream.text if isinstance(stream, StreamState) else str(stream)
        raise WaitAborted(f"group {self._name}", what, f"its stream is {text}")

    def _newest_after(self, tick: int, timeout: float) -> Frame:
        """The newest frame, once it is newer than ``tick`` (waits on the tick event)."""
        deadline = time.monotonic() + timeout
        while True:
            frame = self._client.latest()
            if frame.tick > tick:
                return frame
            del frame
            now = time.monotonic()
            if now >= deadline:
                raise NoFrame(timeout)
            self._client._wait_tick(deadline - now)

    def _pending(self, state: GroupState, tick: int) -> bool:
        """Whether the last setpoint sent is overdue (its tick plus the stream's delay has
        passed) and not applied yet, but may still be."""
        if self.sequence == 0 or int(state.last_sequence) >= self.sequence:
            return False
        due = self.last_for_tick + int(state.stream_delay)
        return due <= tick < due + self.patience

    def run_each_tick(
        self,
        fn: Callable[[Frame], Optional[Sequence[float]]],
        duration: Optional[float] = None,
        *,
        one_in_flight: bool = False,
        timeout: float = 1.0,
    ) -> int:
        """The control loop: waits for each new frame (on the tick event), calls
        ``fn(frame)`` with the newest one and sends the values it returns for
        ``frame.tick + lead`` (:attr:`lead`: the values ``fn`` computes are for that
        tick); for ``duration`` s, or until ``fn`` returns ``None``. Returns how many
        setpoints it sent.

        A client that fell behind does not answer the frames it missed: it reads the
        newest. Every setpoint sent is applied on its own time, late ones too (the stream's
        delay grows to match), so the default answers every new frame. With
        ``one_in_flight``, a frame that shows the previous setpoint overdue (its tick plus
        the stream's delay passed) and not applied is not answered (:attr:`skipped`), for
        up to :attr:`patience` ticks: the client waits for the server rather than queueing
        more behind a setpoint that is stuck.

        Raises :class:`~motiond.errors.GroupAborted` when the stream stops (stale,
        a limit under ``stream_limit = "abort"``, a stop, the e-stop),
        :class:`~motiond.errors.NoFrame` when no frame comes for ``timeout`` s."""
        if not self._active:
            raise StreamClosed(self._name)
        end = None if duration is None else time.monotonic() + duration
        last = -1
        sent = 0
        while end is None or time.monotonic() < end:
            frame = self._newest_after(last, timeout)
            last = frame.tick
            state = frame.group(self._index)
            self._observe(state, last)
            self._check_running(state, last, "keep streaming")
            if one_in_flight and self._pending(state, last):
                self.skipped += 1
                del state, frame
                continue
            del state
            values = fn(frame)
            del frame
            if values is None:
                break
            self.send(last + self._lead, values)
            sent += 1
        return sent

    def wait_applied(self, timeout: float = 1.0) -> GroupStatus:
        """Waits until a frame shows the last setpoint sent applied — or every setpoint
        sent accounted for by the server's counters (``applied + late + early``: the last
        ones reached it more than ``stream_buffer`` ticks after their tick and were
        dropped) — and returns the group's state in it (the counters); raises
        :class:`~motiond.errors.WaitTimeout` when none does within ``timeout`` s,
        :class:`~motiond.errors.GroupAborted` when the stream stopped."""
        what = f"apply setpoint {self.sequence}"
        deadline = time.monotonic() + timeout
        last = -1
        while True:
            try:
                frame = self._newest_after(last, max(0.0, deadline - time.monotonic()))
            except NoFrame:
                raise WaitTimeout(f"group {self._name}", what, timeout) from None
            last = frame.tick
            state = frame.group(self._index)
            self._observe(state, last)
            if last >= self.started.tick and (
                int(state.last_sequence) >= self.sequence
                or int(state.applied) + int(state.late) + int(state.early) >= self.sent
            ):
                return GroupStatus.of(self._client.info, self._index, last, state)
            self._check_running(state, last, what)
            del state, frame

    # --- end -------------------------------------------------------------------------------

    def _release(self) -> None:
        if not self._claimed:
            return
        self._claimed = False
        try:
            self._command(CommandKind.RELEASE)
        except NotClaimed:
            pass

    def close(self) -> None:
        """Ends the stream (``Cancel``: the group's axes stop and hold; a stream that
        stopped already is no error) and releases the group's claim."""
        if not self._active:
            return
        self._active = False
        try:
            self._command(CommandKind.CANCEL)
        except NotMoving:
            pass
        finally:
            self._release()

    def __enter__(self) -> "SetpointStream":
        return self

    def __exit__(self, kind: Any, error: Any, trace: Any) -> None:
        try:
            self.close()
        except MotiondError:
            if error is None:
                raise
            # The exception leaving the block says more than a failed cancel.

    def __del__(self) -> None:
        # Best effort: a stream nobody holds any more ends (otherwise the server's
        # staleness stops the group, and the claim stays until the client closes).
        try:
            if self._active:
                self.close()
        except BaseException:  # noqa: BLE001 - nothing may escape a finaliser
            pass

    def __repr__(self) -> str:
        state = "active" if self._active else "ended"
        return (
            f"SetpointStream({self._name!r}, {self._mode.text}, sent={self.sent}, {state})"
        )

