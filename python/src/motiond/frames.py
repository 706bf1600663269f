"""Samples read straight from shared memory: :class:`Frame` and the newest-sample cache."""

from __future__ import annotations

import ctypes
from typing import TYPE_CHECKING, Any, Dict, Generic, List, Optional, Type, TypeVar

import iceoryx2 as iox2

from .errors import FramesHeld, IpcError
from .ipc import (
    AxisState,
    DeviceState,
    FrameFlags,
    GroupState,
    MotionFrame,
    Payload,
    SignalState,
    MAX_AXES,
    MAX_DEVICES,
    MAX_GROUPS,
    MAX_SIGNALS,
    to_enum,
)

if TYPE_CHECKING:  # pragma: no cover
    import numpy

__all__ = ["Received", "Frame", "LatestCache"]

T = TypeVar("T", bound=Payload)
R = TypeVar("R", bound="Received[Any]")

_AXES_OFFSET = MotionFrame.axes.offset
_SIGNALS_OFFSET = MotionFrame.signals.offset

_NUMPY_TYPES = {
    ctypes.c_double: "float64",
    ctypes.c_int64: "int64",
    ctypes.c_uint64: "uint64",
    ctypes.c_uint32: "uint32",
    ctypes.c_uint16: "uint16",
    ctypes.c_uint8: "uint8",
}


class Received(Generic[T]):
    """A payload received from the server, still in shared memory (nothing was copied).

    ``payload`` is a read-only :mod:`ctypes` view of it. While this object (or any view
    taken from it) lives, the server cannot reuse the memory chunk; iceoryx2 lets a client
    hold only two samples of one service at once, so keep copies
    (:meth:`Payload.copy`) of what you want to keep for long. :meth:`release` gives the
    sample back at once (views taken from it must not be used afterwards).
    """

    __slots__ = ("_sample", "_payload")

    def __init__(self, sample: Any, payload_type: Type[T]) -> None:
        self._sample = sample
        payload = payload_type.from_address(sample.payload_ptr)
        # Every view derived from `payload` keeps it (and so the sample) alive.
        payload._iox2_sample = sample  # type: ignore[attr-defined]
        self._payload: Optional[T] = payload

    @property
    def payload(self) -> T:
        """The payload, a read-only view into shared memory."""
        if self._payload is None:
            raise ValueError("the sample was released")
        return self._payload

    def copy(self) -> T:
        """A private, writable copy of the payload."""
        return self.payload.copy()

    @property
    def released(self) -> bool:
        """Whether :meth:`release` gave the sample back."""
        return self._payload is None

    def release(self) -> None:
        """Gives the sample back to the server now. Views taken from it are invalid
        afterwards."""
        if self._payload is not None:
            self._payload = None
            self._sample.delete()

    def __enter__(self: R) -> R:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


class Frame(Received[MotionFrame]):
    """One :class:`~motiond.ipc.MotionFrame` in shared memory: the state of every axis,
    board and signal at one tick.

    ``frame.axes[i]`` and ``frame.signals[i]`` are views (no copy);
    :meth:`positions` and :meth:`velocities` are NumPy arrays over the same memory (no
    copy, read-only) when NumPy is installed.
    """

    __slots__ = ()

    def __init__(self, sample: Any) -> None:
        super().__init__(sample, MotionFrame)

    @property
    def tick(self) -> int:
        """Tick number, 0 at server start."""
        return int(self.payload.tick)

    @property
    def time_ns(self) -> int:
        """The tick's deadline, CLOCK_MONOTONIC ns."""
        return int(self.payload.time_ns)

    @property
    def publish_ns(self) -> int:
        """CLOCK_MONOTONIC ns just before the frame was sent."""
        return int(self.payload.publish_ns)

    @property
    def flags(self) -> FrameFlags:
        """Server-wide flags (e-stop latched, shutting down)."""
        return FrameFlags(self.payload.flags)

    @property
    def estop_latched(self) -> bool:
        """Whether the e-stop is latched."""
        return bool(self.payload.flags & FrameFlags.ESTOP_LATCHED)

    @property
    def axis_count(self) -> int:
        """Valid entries of :attr:`axes`."""
        return min(int(self.payload.axis_count), MAX_AXES)

    @property
    def signal_count(self) -> int:
        """Valid entries of :attr:`signals`."""
        return min(int(self.payload.signal_count), MAX_SIGNALS)

    @property
    def group_count(self) -> int:
        """Valid entries of :attr:`groups`."""
        return min(int(self.payload.group_count), MAX_GROUPS)

    @property
    def groups(self) -> List[GroupState]:
        """The valid groups, in config order: read-only views."""
        raw = self.payload.groups
        return [raw[i] for i in range(self.group_count)]

    def group(self, index: int) -> GroupState:
        """Group ``index`` (config order), a read-only view."""
        if not 0 <= index < self.group_count:
            raise IndexError(f"group index {index} out of range 0..{self.group_count}")
        return self.payload.groups[index]

    @property
    def axes(self) -> List[AxisState]:
        """The valid axes, in config order: read-only views."""
        raw = self.payload.axes
        return [raw[i] for i in range(self.axis_count)]

    @property
    def signals(self) -> List[SignalState]:
        """The valid signals, in config order: read-only views."""
        raw = self.payload.signals
        return [raw[i] for i in range(self.signal_count)]

    def axis(self, index: int) -> AxisState:
        """Axis ``index`` (config order), a read-only view."""
        if not 0 <= index < self.axis_count:
            raise IndexError(f"axis index {index} out of range 0..{self.axis_count}")
        return self.payload.axes[index]

    def signal(self, index: int) -> SignalState:
        """Signal ``index`` (config order), a read-only view."""
        if not 0 <= index < self.signal_count:
            raise IndexError(f"signal index {index} out of range 0..{self.signal_count}")
        return self.payload.signals[index]

    def device_states(self) -> List[Any]:
        """:class:`~motiond.ipc.DeviceState` per device, config order."""
        count = min(int(self.payload.device_count), MAX_DEVICES)
        raw = self.payload.devices
        return [to_enum(DeviceState, raw[i]) for i in range(count)]

    def axis_array(self, field: str) -> "numpy.ndarray":
        """A read-only NumPy array of one :class:`~motiond.ipc.AxisState` field over the
        valid axes, viewing the shared memory (no copy). Needs NumPy
        (``pip install motiond[numpy]``)."""
        return self._strided(AxisState, _AXES_OFFSET, self.axis_count, field)

    def signal_array(self, field: str) -> "numpy.ndarray":
        """Like :meth:`axis_array`, for a :class:`~motiond.ipc.SignalState` field."""
        return self._strided(SignalState, _SIGNALS_OFFSET, self.signal_count, field)

    def positions(self) -> "numpy.ndarray":
        """Measured positions of the valid axes (units), a NumPy view without copy."""
        return self.axis_array("position")

    def velocities(self) -> "numpy.ndarray":
        """Measured velocities of the valid axes (units/s), a NumPy view without copy."""
        return self.axis_array("velocity")

    def targets(self) -> "numpy.ndarray":
        """Targets of the valid axes, a NumPy view without copy."""
        return self.axis_array("target")

    def _strided(self, record: Type[Payload], base: int, count: int, field: str) -> "numpy.ndarray":
        try:
            import numpy
        except ImportError as error:  # pragma: no cover - depends on the environment
            raise ImportError("Frame arrays need NumPy: pip install 'motiond[numpy]'") from error
        descriptor = getattr(record, field, None)
        kinds: Dict[str, Any] = {entry[0]: entry[1] for entry in record._fields_}
        kind = kinds.get(field)
        if descriptor is None or kind not in _NUMPY_TYPES:
            numeric = [name for name, k in kinds.items() if k in _NUMPY_TYPES]
            raise ValueError(
                f"{record.__name__} has no numeric field {field!r} (numeric fields: {numeric})"
            )
        payload = self.payload
        buffer = (ctypes.c_uint8 * ctypes.sizeof(MotionFrame)).from_address(
            ctypes.addressof(payload)
        )
        buffer._iox2_owner = payload  # type: ignore[attr-defined]
        array = numpy.ndarray(
            shape=(count,),
            dtype=numpy.dtype(_NUMPY_TYPES[kind]),
            buffer=memoryview(buffer),
            offset=base + descriptor.offset,
            strides=(ctypes.sizeof(record),),
        )
        array.flags.writeable = False
        return array


class LatestCache(Generic[T]):
    """One subscriber and the newest sample taken from it."""

    def __init__(
        self, subscriber: Any, payload_type: Type[T], service: str, wrap: Any = None
    ) -> None:
        self._subscriber = subscriber
        self._type = payload_type
        self._service = service
        self._wrap = wrap if wrap is not None else (lambda s: Received(s, payload_type))
        self._newest: Optional[Any] = None

    @property
    def current(self) -> Optional[Any]:
        """The newest sample taken so far, without looking for new ones."""
        return self._newest

    def refresh(self) -> Optional[Any]:
        """Takes every waiting sample and keeps the newest; returns it (or the one kept
        before)."""
        while self.take_next() is not None:
            pass
        if self._newest is not None and self._newest.released:
            # The program gave it back: it is no newest sample any more.
            self._newest = None
        return self._newest

    def take_next(self) -> Optional[Any]:
        """Takes the oldest waiting sample (the next in publication order), keeps it as
        the newest and returns it; ``None`` when nothing is waiting."""
        try:
            if not self._subscriber.has_samples():
                return None
            # Give our own hold on the previous sample back first; a caller that still
            # holds it keeps it alive.
            self._newest = None
            sample = self._subscriber.receive()
        except iox2.ReceiveError as error:
            if "ExceedsMaxBorrows" in repr(error):
                raise FramesHeld(self._service, repr(error)) from error
            raise IpcError(f"receive from {self._service}", error) from error
        except iox2.ConnectionFailure as error:
            raise IpcError(f"check {self._service} for samples", error) from error
        if sample is None:
            return None
        received = self._wrap(sample)
        self._newest = received
        return received

    def close(self) -> None:
        """Drops the cached sample and the subscriber (samples still held elsewhere stay
        valid until they are dropped)."""
        self._newest = None
        self._subscriber = None
