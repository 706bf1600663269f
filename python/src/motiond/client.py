"""Connecting to a motiond instance: :class:`Client` (its answers named from the server's
description by :mod:`motiond.answers`)."""

from __future__ import annotations

import ctypes
import time
from typing import Any, Callable, ClassVar, Iterator, List, Optional, Sequence, Type, Union

import iceoryx2 as iox2

from . import answers, commission, errors
from .axis import Axis
from .errors import (
    EstopNotSeen,
    IncompatibleServer,
    IpcError,
    NoFrame,
    NoInfo,
    NoReply,
    NoServer,
    NoSuchAxis,
    NoSuchGroup,
    NoSuchSignal,
    ServerGone,
    WaitTimeout,
)
from .frames import Frame, LatestCache
from .group import Group
from .ipc import (
    ALL_AXES,
    SCHEMA_VERSION,
    ClientId,
    CommandKind,
    CommandReply,
    CommandRequest,
    DeviceState,
    FrameFlags,
    GroupPath,
    MachineParams,
    MotionFrame,
    Reason,
    ServerInfo,
    ServerStats,
    Setpoint,
    Target,
    service_name,
    to_enum,
)
from .session import (
    DEFAULT_CONNECT_TIMEOUT,
    DEFAULT_REPLY_TIMEOUT,
    Accepted,
    JogRegistry,
    Param,
    refresh_period,
)
from .signal import Signal

__all__ = ["Client", "Accepted", "Param", "DEFAULT_CONNECT_TIMEOUT", "DEFAULT_REPLY_TIMEOUT"]

# Longest single sleep of any wait: bounds a missed wake-up and how late Ctrl-C is seen.
_WAIT_CAP = 0.05
# Longest single sleep while waiting for a command reply.
_REPLY_POLL_CAP = 0.002


def _duration(seconds: float) -> Any:
    return iox2.Duration.from_secs_f64(max(0.0, seconds))


def _open_retrying(deadline: float, open_: Callable[[], Any]) -> Any:
    """Calls ``open_`` until it succeeds or ``deadline`` passes (then raises its error)."""
    while True:
        try:
            return open_()
        except Exception:
            if time.monotonic() >= deadline:
                raise
            time.sleep(0.01)


class Client:
    """A connection to one motiond instance: frames, server description, commands.

    ``Client("demo")`` connects to the instance whose config says ``[server] name =
    "demo"``, retrying for ``timeout`` seconds while its services do not exist yet.
    ``Client("demo", remote="tcp/host-a:7447", identity="panel")`` reaches it on another
    host through its ``motion-bridge`` instead (a :class:`~motiond.remote.RemoteClient`).
    A client is meant to be used from one thread. Close it with :meth:`close` (or use it
    as a context manager); its jogs stop then.

    Every read and wait (:meth:`latest`, :meth:`frames`, :meth:`Axis.state`,
    the waits, :meth:`keep_alive`) also renews the client's running jogs: see
    :class:`~motiond.jog.Jog`.
    """

    #: The class ``Client(name, remote=...)`` makes: the subclass declared with
    #: ``transport="remote"`` (:class:`~motiond.remote.RemoteClient`, which the package
    #: imports), so that this module never imports the one above it.
    _remote_class: ClassVar[Optional[Type["Client"]]] = None

    def __init_subclass__(cls, transport: Optional[str] = None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if transport == "remote":
            Client._remote_class = cls

    def __new__(cls, *args: Any, remote: Optional[str] = None, **kwargs: Any) -> "Client":
        # `Client(name, remote="tcp/host:7447")` is a RemoteClient (motion-bridge, zenoh).
        if remote is not None and cls is Client:
            if Client._remote_class is None:  # pragma: no cover - motiond imports remote
                raise errors.ConnectError("no remote client is loaded (import motiond.remote)")
            return super().__new__(Client._remote_class)
        return super().__new__(cls)

    def __init__(
        self,
        name: str = "demo",
        timeout: float = DEFAULT_CONNECT_TIMEOUT,
        *,
        remote: Optional[str] = None,
        identity: Optional[str] = None,
        zenoh_config: Optional[str] = None,
        reply_timeout: float = DEFAULT_REPLY_TIMEOUT,
        node_name: str = "motiond-python",
    ) -> None:
        if remote is not None or identity is not None or zenoh_config is not None:
            raise errors.ConnectError(
                "identity and zenoh_config apply to a remote client only: pass remote= "
                "(over shared memory the server knows a client by its iceoryx2 node)"
            )
        started = time.monotonic()
        deadline = started + timeout
        self._init_state(name, reply_timeout)
        self._stats: Optional[LatestCache[ServerStats]] = None
        try:
            self._node = (
                iox2.NodeBuilder.new()
                .name(iox2.NodeName.new(node_name))
                # Python handles SIGINT itself (KeyboardInterrupt); every wait here is
                # short enough for it to be seen at once.
                .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
                .create(iox2.ServiceType.Ipc)
            )
        except Exception as error:
            raise IpcError("create a node", error) from error

        frame_service = self._service("frame")
        try:
            frames = _open_retrying(
                deadline,
                lambda: self._node.service_builder(frame_service)
                .publish_subscribe(MotionFrame)
                .open(),
            )
        except iox2.PublishSubscribeOpenError as error:
            detail = error.args[0] if error.args else ""
            if detail == "IncompatibleTypes":
                raise IncompatibleServer(name, 0, SCHEMA_VERSION) from None
            if detail in ("DoesNotExist", "IsMarkedForDestruction", "HangsInCreation"):
                raise NoServer(name, str(frame_service), timeout) from None
            raise IpcError("open the frame service", error) from error
        self._frame_service = frames
        self._frames: LatestCache[MotionFrame] = LatestCache(
            self._create(lambda: frames.subscriber_builder().create(), "subscribe to frames"),
            MotionFrame,
            "the frame service",
            wrap=Frame,
        )
        tick = self._open(deadline, "tick", lambda s: self._node.service_builder(s).event().open())
        self._tick = self._create(lambda: tick.listener_builder().create(), "listen to ticks")
        command = self._open(
            deadline,
            "command",
            lambda s: self._node.service_builder(s)
            .request_response(CommandRequest, CommandReply)
            .open(),
        )
        self._commands = self._create(
            lambda: command.client_builder().create(), "create a command client"
        )
        self._reserve_setpoints_port()
        info = self._open(
            deadline,
            "info",
            lambda s: self._node.service_builder(s).publish_subscribe(ServerInfo).open(),
        )
        self._info: LatestCache[ServerInfo] = LatestCache(
            self._create(lambda: info.subscriber_builder().create(), "subscribe to info"),
            ServerInfo,
            "the info service",
        )
        # The server hands a late subscriber its history sample when it next looks at its
        # connections (every tick).
        info_timeout = max(timeout, 0.5)
        info_deadline = started + info_timeout
        while self._info.refresh() is None:
            if time.monotonic() >= info_deadline:
                raise NoInfo(name, str(self._service("info")), info_timeout)
            time.sleep(0.005)
        description = self.info
        if description.schema_version != SCHEMA_VERSION:
            raise IncompatibleServer(name, description.schema_version, SCHEMA_VERSION)
        self._id = ClientId.from_int(self._node.id.value)
        self._goal_ticks: List[int] = [0] * int(description.axis_count)
        self._open_stats()

    # --- plumbing --------------------------------------------------------------------------

    def _init_state(self, name: str, reply_timeout: float) -> None:
        """The state every client keeps, whatever its transport."""
        self._name = name
        self._reply_timeout = reply_timeout
        self._sequence = 0
        self._closed = False
        self._jogs = JogRegistry()
        self._estop_notifier: Any = None
        # The groups' publishers: paths' made by the first path, setpoints' at connect (or
        # by the first stream when no slot was free then).
        self._paths_publisher: Any = None
        self._setpoints_publisher: Any = None
        self._path_id = 0

    def _service(self, leaf: str) -> Any:
        try:
            return iox2.ServiceName.new(service_name(self._name, leaf))
        except iox2.SemanticStringError as error:
            raise errors.ConnectError(
                f'"{self._name}" is not a valid server name: {error!r}'
            ) from None

    def _open(self, deadline: float, leaf: str, open_: Callable[[Any], Any]) -> Any:
        name = self._service(leaf)
        try:
            return _open_retrying(deadline, lambda: open_(name))
        except Exception as error:
            raise IpcError(f"open the {leaf} service", error) from error

    @staticmethod
    def _create(create: Callable[[], Any], what: str) -> Any:
        try:
            return create()
        except Exception as error:
            raise IpcError(what, error) from error

    def _check_open(self) -> None:
        if self._closed:
            raise errors.MotiondError("the client is closed")

    def _wait_tick(self, timeout: float) -> None:
        """Sleeps until the next tick notification or ``timeout`` (capped, so that Ctrl-C
        is seen)."""
        try:
            self._tick.timed_wait(_duration(min(timeout, _WAIT_CAP)))
        except iox2.ListenerWaitError as error:
            if "Interrupt" not in repr(error):
                raise IpcError("wait for the tick event", error) from error

    # --- description -----------------------------------------------------------------------

    @property
    def name(self) -> str:
        """The instance name this client talks to."""
        return self._name

    @property
    def id(self) -> ClientId:
        """This client's id as the server sees it (its iceoryx2 node id)."""
        return self._id

    @property
    def node(self) -> Any:
        """The iceoryx2 node of this client (to build your own ports)."""
        return self._node

    @property
    def info(self) -> ServerInfo:
        """The server's description (axes, devices, signals, tick rate, deadman): a
        read-only view of the newest info sample."""
        self._check_open()
        received = self._info.refresh()
        if received is None:  # pragma: no cover - connect guarantees one
            raise IpcError("read the server description", RuntimeError("none received"))
        return received.payload

    @property
    def tick_hz(self) -> int:
        """The server's tick rate."""
        return int(self.info.tick_hz)

    @property
    def command_timeout(self) -> float:
        """The server's deadman for velocity and power goals, s (0: none)."""
        return self.info.command_timeout_ms / 1000.0

    @property
    def axes(self) -> List[Axis]:
        """Handles of every axis, in config order."""
        return [Axis(self, index) for index in range(len(self._goal_ticks))]

    def axis(self, name: str) -> Axis:
        """The handle of the axis called ``name``."""
        info = self.info
        for index in range(min(int(info.axis_count), len(info.axes))):
            if info.axes[index].text("name") == name:
                return Axis(self, index)
        raise NoSuchAxis(name)

    @property
    def signals(self) -> List[Signal]:
        """Handles of every signal, in config order."""
        return [Signal(self, index) for index in range(int(self.info.signal_count))]

    @property
    def groups(self) -> List[Group]:
        """Handles of every group (``[[group]]`` of the server's config), in config order."""
        return [Group(self, index) for index in range(self._group_count())]

    def group(self, name: str) -> Group:
        """The handle of the group called ``name``; :class:`~motiond.errors.NoSuchGroup`
        (listing the server's groups) when there is none."""
        info = self.info
        names = [info.groups[i].text("name") for i in range(self._group_count())]
        if name in names:
            return Group(self, names.index(name))
        raise NoSuchGroup(name, names)

    def _group_count(self) -> int:
        info = self.info
        return min(int(info.group_count), len(info.groups))

    def signal(self, name: str) -> Signal:
        """The handle of the signal called ``name``."""
        info = self.info
        for index in range(min(int(info.signal_count), len(info.signals))):
            if info.signals[index].text("name") == name:
                return Signal(self, index)
        raise NoSuchSignal(name)

    def stats(self) -> Optional[ServerStats]:
        """A copy of the newest :class:`~motiond.ipc.ServerStats` (published about once a
        second; a remote client has those the bridge passed on); ``None`` until the first."""
        self.service_jogs()
        self._open_stats()
        if self._stats is None:
            return None
        received = self._stats.refresh()
        return None if received is None else received.copy()

    def _open_stats(self) -> None:
        """Subscribes to the stats service if it is not yet (a server publishes it from
        its first second on; until then there is nothing to read)."""
        if self._stats is not None:
            return
        try:
            factory = (
                self._node.service_builder(self._service("stats"))
                .publish_subscribe(ServerStats)
                .open()
            )
            subscriber = factory.subscriber_builder().create()
        except Exception:
            return
        self._stats = LatestCache(subscriber, ServerStats, "the stats service")

    def params(self, timeout: float = 1.0) -> List[Param]:
        """The machine parameters in effect (devices' then axes', config order), each with
        the config key, the effective value with its unit and whether the config set it."""
        self.service_jogs()
        try:
            factory = (
                self._node.service_builder(self._service("params"))
                .publish_subscribe(MachineParams)
                .open()
            )
            subscriber = factory.subscriber_builder().create()
        except Exception as error:
            raise IpcError("open the params service", error) from error
        cache: LatestCache[MachineParams] = LatestCache(
            subscriber, MachineParams, "the params service"
        )
        deadline = time.monotonic() + timeout
        while True:
            received = cache.refresh()
            if received is not None:
                break
            if time.monotonic() >= deadline:
                raise WaitTimeout("the params service", "publish its parameters", timeout)
            time.sleep(0.005)
        params = self._params_of(received)
        cache.close()
        return params

    def _params_of(self, received: Any) -> List[Param]:
        """The entries of a received :class:`~motiond.ipc.MachineParams`, named."""
        with received:
            return answers.params_of(self.info, received.payload)

    # --- frames ----------------------------------------------------------------------------

    def latest(self) -> Frame:
        """The newest frame (zero-copy). Waits for the first one if none arrived yet."""
        self._check_open()
        self.service_jogs()
        frame = self._frames.refresh()
        if frame is None:
            return self.next_frame(1.0)
        return frame

    def try_next_frame(self) -> Optional[Frame]:
        """The next frame in publication order if one is waiting, else ``None``."""
        self._check_open()
        self.service_jogs()
        return self._frames.take_next()

    def next_frame(self, timeout: float = 1.0) -> Frame:
        """The next frame in publication order, sleeping on the tick event (no busy
        polling) for up to ``timeout`` s. Frames the client was too slow for (more than
        the service's 32-frame buffer) are lost: compare ``tick``s."""
        self._check_open()
        deadline = time.monotonic() + timeout
        while True:
            self.service_jogs()
            frame = self._frames.take_next()
            if frame is not None:
                return frame
            now = time.monotonic()
            if now >= deadline:
                raise NoFrame(timeout)
            self._wait_tick(self._jog_wait_cap(deadline - now))

    def frames(self, timeout: float = 1.0) -> Iterator[Frame]:
        """Every frame in order, each waited for up to ``timeout`` s; raises
        :class:`~motiond.errors.NoFrame` when the server stays silent.

        Hold at most one frame from the previous iteration: iceoryx2 lets a client
        borrow two samples at once (use ``frame.copy()`` to keep more)."""
        while True:
            frame = self.next_frame(timeout)
            yield frame
            del frame

    def wait_frames(
        self,
        what: str,
        timeout: float,
        done: Callable[[Frame], bool],
        subject: str = "the server",
        since: int = 0,
    ) -> Frame:
        """Waits until ``done(frame)`` is true for a frame at or after tick ``since``, and
        returns that frame. ``done`` may raise to abort the wait."""
        deadline = time.monotonic() + timeout
        frame = self.latest()
        while True:
            if frame.tick >= since and done(frame):
                return frame
            now = time.monotonic()
            if now >= deadline:
                raise WaitTimeout(subject, what, timeout)
            del frame
            try:
                frame = self.next_frame(deadline - now)
            except NoFrame:
                raise WaitTimeout(subject, what, timeout) from None

    def wait_ready(self, timeout: float = 5.0, axes: Optional[Sequence[str]] = None) -> Frame:
        """Waits until the boards of ``axes`` (every device when ``None``) are online: they
        answered, were configured and acknowledged their start-up stop, so they take
        goals."""
        if axes is None:

            def ready(frame: Frame) -> bool:
                states = frame.device_states()
                return bool(states) and all(s == DeviceState.ONLINE for s in states)

            subject = "every device"
        else:
            handles = [self.axis(name) for name in axes]

            def ready(frame: Frame) -> bool:
                return all(frame.axis(h.index).device_state == DeviceState.ONLINE for h in handles)

            subject = "the devices of " + ", ".join(axes)
        return self.wait_frames("come online", timeout, ready, subject=subject)

    # --- commands --------------------------------------------------------------------------

    def send(
        self,
        index: int,
        kind: Union[CommandKind, int],
        values: Sequence[float] = (0.0, 0.0, 0.0),
        target: Union[Target, int] = Target.AXIS,
    ) -> CommandReply:
        """Sends one request and returns the server's reply (a copy) as it is, accepted or
        not. ``index`` is an axis index, a signal index (``target=Target.SIGNAL``) or
        :data:`~motiond.ipc.ALL_AXES`; ``values`` as documented on
        :class:`~motiond.ipc.CommandKind`."""
        self._check_open()
        typed_kind = to_enum(CommandKind, int(kind))
        request = self._request(index, kind, values, target)
        sequence = int(request.sequence)
        try:
            pending = self._commands.send_copy(request)
        except Exception as error:
            raise IpcError("send a command", error) from error
        try:
            if pending.number_of_server_connections == 0:
                raise ServerGone(typed_kind)
            deadline = time.monotonic() + self._reply_timeout
            while True:
                try:
                    response = pending.receive()
                except Exception as error:
                    raise IpcError("receive a command reply", error) from error
                if response is not None:
                    reply = CommandReply.from_buffer_copy(
                        ctypes.string_at(response.payload_ptr, ctypes.sizeof(CommandReply))
                    )
                    response.delete()
                    if reply.sequence == sequence:
                        return reply
                    continue
                now = time.monotonic()
                if now >= deadline:
                    raise NoReply(typed_kind, self._reply_timeout)
                # The server answers within its tick and then notifies the tick event.
                self._wait_tick(min(deadline - now, _REPLY_POLL_CAP))
        finally:
            pending.delete()

    def _request(
        self,
        index: int,
        kind: Union[CommandKind, int],
        values: Sequence[float],
        target: Union[Target, int],
    ) -> CommandRequest:
        """The next request of this client (a new sequence number), values padded to 3."""
        self._sequence += 1
        request = CommandRequest(
            schema_version=SCHEMA_VERSION,
            kind=int(kind),
            client=self._id,
            sequence=self._sequence,
            axis=index,
            target=int(target),
        )
        padded = list(values)[:3] + [0.0] * (3 - min(3, len(values)))
        for slot, value in enumerate(padded):
            request.values[slot] = float(value)
        return request

    def command(
        self,
        index: int,
        kind: Union[CommandKind, int],
        values: Sequence[float] = (0.0, 0.0, 0.0),
        target: Union[Target, int] = Target.AXIS,
        label: Optional[str] = None,
    ) -> Accepted:
        """Sends one request; returns :class:`Accepted`, or raises the
        :class:`~motiond.errors.Refused` subclass of the server's reason."""
        reply = self.send(index, kind, values, target)
        if reply.reason == Reason.ACCEPTED:
            if target == Target.AXIS:
                self._note_goal(index, int(reply.tick_applied))
            return Accepted(sequence=int(reply.sequence), tick=int(reply.tick_applied))
        if label is None:
            label = answers.label(self.info, index, target)
        raise answers.refusal(self.info, reply, label)

    def _note_goal(self, index: int, tick: int) -> None:
        if index == ALL_AXES:
            self._goal_ticks = [tick] * len(self._goal_ticks)
        elif 0 <= index < len(self._goal_ticks):
            self._goal_ticks[index] = tick

    def goal_tick(self, index: int) -> int:
        """The tick of the last goal accepted for axis ``index`` (0 when none)."""
        if 0 <= index < len(self._goal_ticks):
            return self._goal_ticks[index]
        return 0

    # --- commissioning (module :mod:`motiond.commission`) --------------------------------

    def device_index(self, name: str) -> int:
        """The index (config order) of device ``name``; raises
        :class:`~motiond.errors.NoSuchDevice`."""
        return commission.device_index(self, name)

    def claim_device(self, name: str) -> "commission.DeviceClaim":
        """Claims every axis and signal of device ``name`` (what a commission needs), for
        a ``with`` block."""
        return commission.DeviceClaim(self, name)

    def commission(
        self,
        device: str,
        *,
        address: Optional[int] = None,
        baud: Optional[int] = None,
        factory_reset: bool = False,
    ) -> Accepted:
        """Changes one of ``device``'s own settings (exactly one of ``address``, ``baud``,
        ``factory_reset=True``): the server tells the board and finds it again where it
        now answers (:meth:`wait_commissioned`). Needs the device's claims
        (:meth:`claim_device`); refused while the e-stop is latched
        (:class:`~motiond.errors.EstopLatched`), while one of its axes moves
        (:class:`~motiond.errors.GroupBusy`), for a ``baud`` on a link other devices share
        while one of them is in use (:class:`~motiond.errors.GroupBusy` for a goal or a
        moving axis, :class:`~motiond.errors.ClaimedByOther` for another client's claim; the
        reply's ``value`` is that device's index), for a setting its board lacks
        (:class:`~motiond.errors.Unsupported`) or a value it does not take
        (:class:`~motiond.errors.OutOfRange`)."""
        return commission.commission(
            self, device, address=address, baud=baud, factory_reset=factory_reset
        )

    def wait_commissioned(
        self, device: str, accepted: Accepted, timeout: float = 5.0
    ) -> "commission.Commissioned":
        """Waits until ``device`` answers again after the commission ``accepted``: its
        address and firmware as found."""
        return commission.wait_commissioned(self, device, accepted, timeout)

    def estop(self) -> Accepted:
        """Emergency stop: every axis stops (with its e-stop category); latched until
        :meth:`reset`. Returns once a frame of the accepting tick or later shows the e-stop
        latched; raises :class:`~motiond.errors.EstopNotSeen` when none does within the
        reply timeout (accepted, but not known to be in force)."""
        accepted = self.command(ALL_AXES, CommandKind.E_STOP)
        started = time.monotonic()
        deadline = started + self._reply_timeout
        newest: Optional[int] = None
        while True:
            try:
                frame: Optional[Frame] = self.next_frame(max(0.0, deadline - time.monotonic()))
            except NoFrame:
                frame = None
            if frame is not None:
                newest = frame.tick
                latched = frame.tick >= accepted.tick and bool(
                    frame.flags & FrameFlags.ESTOP_LATCHED
                )
                del frame
                if latched:
                    return accepted
            if time.monotonic() >= deadline:
                raise EstopNotSeen(accepted.tick, time.monotonic() - started, newest)

    def notify_estop(self) -> None:
        """Latches the e-stop through the ``estop`` event service instead of the command
        service: its own ports, so it gets through when the command service's client
        slots are all taken. No reply."""
        if self._estop_notifier is None:
            try:
                event = self._node.service_builder(self._service("estop")).event().open()
                self._estop_notifier = event.notifier_builder().create()
            except Exception as error:
                raise IpcError("open the estop event", error) from error
        try:
            self._estop_notifier.notify()
        except Exception as error:
            raise IpcError("notify the estop event", error) from error

    def reset(self) -> Accepted:
        """Clears a latched e-stop, deadman expiries and faults whose cause is gone; axes
        without a running goal hold where they are. Claims (anyone's) stay."""
        return self.command(ALL_AXES, CommandKind.RESET)

    def stop_all(self) -> Accepted:
        """Stops every axis (decelerate and hold)."""
        return self.command(ALL_AXES, CommandKind.STOP)

    def off_all(self) -> Accepted:
        """De-energises every axis."""
        return self.command(ALL_AXES, CommandKind.OFF)

    # --- jogs ------------------------------------------------------------------------------

    def _jog_refresh_period(self) -> Optional[float]:
        current = self._info.current
        return refresh_period(0 if current is None else int(current.payload.command_timeout_ms))

    def _jog_wait_cap(self, remaining: float) -> float:
        return self._jogs.wait_cap(remaining, self._jog_refresh_period())

    def service_jogs(self) -> None:
        """Renews every running jog whose renewal is due. Called by every read and wait.

        A jog not renewed for a whole deadman (the program did not call into the client)
        has been stopped by the server; it is not renewed any more, so that a program that
        hung does not set the axis moving again when it wakes up (``Jog.expired``)."""
        if self._jogs:
            self._jogs.renew_due(self._jog_refresh_period(), self.command_timeout_cached())

    def command_timeout_cached(self) -> float:
        """The server's deadman, s, from the description already received."""
        current = self._info.current
        return 0.0 if current is None else current.payload.command_timeout_ms / 1000.0

    def keep_alive(self) -> None:
        """Renews running jogs without reading anything: call it from a loop that does not
        otherwise call into the client."""
        self.service_jogs()

    # --- groups' ports ----------------------------------------------------------------------

    def _publisher(self, leaf: str, payload: Any) -> Any:
        """A publisher on this client's node to the server's ``leaf`` service."""
        node = self.node  # a remote client has none: it raises
        try:
            service = (
                node.service_builder(self._service(leaf)).publish_subscribe(payload).open()
            )
            return service.publisher_builder().create()
        except Exception as error:
            if "ExceedsMaxSupportedPublishers" in repr(error):
                raise errors.PortsExhausted(
                    service_name(self._name, leaf), "publisher slot", error
                ) from error
            raise IpcError(f"publish on the {leaf} service", error) from error

    def _paths_port(self) -> Any:
        """The publisher of group paths (made on first use: a path is ≈400 KB of shared
        memory per sample)."""
        self._check_open()
        if self._paths_publisher is None:
            self._paths_publisher = self._publisher("paths", GroupPath)
        return self._paths_publisher

    def _reserve_setpoints_port(self) -> None:
        """Takes this client's publisher slot on ``setpoints`` with its command port (one
        try): a claimant's stream then cannot be starved by another process that takes every
        slot after this client connected (docs/SECURITY.md). A slot not free now is tried
        again by the first stream, whose error then says why."""
        try:
            self._setpoints_publisher = self._publisher("setpoints", Setpoint)
        except IpcError:
            self._setpoints_publisher = None

    def _setpoints_port(self) -> Any:
        """The publisher of streamed setpoints (taken at connect, else on first use)."""
        self._check_open()
        if self._setpoints_publisher is None:
            self._setpoints_publisher = self._publisher("setpoints", Setpoint)
        return self._setpoints_publisher

    def _next_path_id(self) -> int:
        """A path id not used before by this client."""
        self._path_id += 1
        return self._path_id

    # --- life ------------------------------------------------------------------------------

    def close(self) -> None:
        """Stops this client's running jogs and releases its ports."""
        if self._closed:
            return
        for jog in self._jogs:
            try:
                jog.stop()
            except errors.MotiondError:
                pass
        self._closed = True
        self._release()

    def _release(self) -> None:
        """Gives back what the connection holds (called once, by :meth:`close`)."""
        self._frames.close()
        self._info.close()
        if self._stats is not None:
            self._stats.close()
        # Give the port slots back now rather than whenever the garbage collector runs.
        for port in (
            self._tick,
            self._commands,
            self._estop_notifier,
            self._paths_publisher,
            self._setpoints_publisher,
        ):
            if port is not None:
                port.delete()
        self._estop_notifier = None
        self._paths_publisher = None
        self._setpoints_publisher = None

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Client(name={self._name!r}, id={int(self._id):#x})"
