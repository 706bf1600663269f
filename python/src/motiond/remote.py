"""Reaching a motiond on another host through ``motion-bridge``: :class:`RemoteClient`.

``motiond.Client("demo", remote="tcp/host-a:7447", identity="panel")`` (or
``RemoteClient(...)``) connects to the zenoh side of a ``motion-bridge`` running beside the
server instead of to shared memory. Needs the ``eclipse-zenoh`` package
(``pip install 'motiond[remote]'``).

Everything of :class:`~motiond.Client` works the same (handles, commands, waits, jogs with
their deadman, parameters, statistics), with these differences:

- payloads are private copies received over the network, not views of shared memory (a
  :class:`~motiond.Frame` holds no sample of the server's; keep as many as you like);
- frames arrive at the bridge's ``frame_rate`` (100 per second by default), not every tick;
- the bridge may refuse a command itself: :class:`~motiond.errors.BridgeRefused` with its
  ``code`` (``not-allowed``, ``rate-limited``, ``late``, ``bad-request``, ``busy``,
  ``no-session``);
- :meth:`~RemoteClient.notify_estop` sends the e-stop command (there is no event service
  across the network; the bridge never holds an e-stop back);
- :attr:`~RemoteClient.node` does not exist (there is no iceoryx2 node), and
  :attr:`~RemoteClient.id` is a random id of this client.

A remote's session is the bridge's to give: on connecting the client asks
``motiond/<name>/session/<identity>`` with an X25519 public key of its own and gets a public
session id (named by its liveliness token) and the bridge's public key; both sides agree on the
session's secret from the two keys, so it never travels (needs the ``cryptography`` package,
part of ``motiond[remote]``). Every command
carries the session id, a counter and a MAC made with the token (HMAC-SHA3-256) over the
identity, the request and the rest of the attachment, so a peer that sees a command cannot
make another, and a command replayed is refused. Stop and e-stop
need none (an identity that may only stop gets none; a bridge with 1024 sessions open
refuses new ones, and stop and e-stop still pass); other commands ask again when the client
has none or the bridge forgot it (it restarted).

The identity is the last chunk of the key expression the commands go to
(``motiond/<name>/command/<identity>``): the bridge applies that identity's allow-list. It
is proven only when the bridge's zenoh config authenticates users and restricts each to its
own key (see ``crates/motion-bridge/README.md``); give this client its credentials with
``zenoh_config``.

The wire contract (``crates/motion-bridge/README.md``, "The network contract"): payloads are
the ``motion-ipc`` structs in their C layout, little-endian, ``sizeof`` bytes; published
samples and replies carry a 16-byte attachment, the server's node id; a session opening sends
73 bytes (version 3, CLOCK_MONOTONIC at sending, u64 ns, the client's X25519 public key, its
zenoh id as zenoh prints it, zero-padded to 32 bytes: the session ends with that transport) and
gets 49 (version 3, the session id u128, the bridge's X25519 public key); the secret is the
first 16 bytes of SHA3-256 over ``b"motiond-session-v3"``, the X25519 shared secret, the
client's key, the bridge's key and the session id (:func:`session_secret`); a command query
carries 49 bytes (:func:`request_meta`): version 3,
the session id (u128, zero without a session), a counter (u64, rising), its CLOCK_MONOTONIC at
sending (u64 ns) and the MAC: the first 16 bytes of HMAC-SHA3-256 keyed by the token over
``b"motiond-request-v3"``, the identity's UTF-8 bytes and a zero byte, the request's 64 bytes
and bytes 1 to 32 of the attachment.
"""

from __future__ import annotations

import collections
import ctypes
import hashlib
import hmac
import json
import secrets
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable, Deque, List, Optional, Sequence, Tuple, Type, Union

from . import errors
from .client import Client
from .errors import (
    BridgeRefused,
    IncompatibleServer,
    NoBridge,
    NoInfo,
    NoReply,
    RemoteError,
    WaitTimeout,
)
from .frames import Frame, Received
from .session import DEFAULT_CONNECT_TIMEOUT, DEFAULT_REPLY_TIMEOUT, Param
from .ipc import (
    SCHEMA_VERSION,
    ClientId,
    CommandKind,
    CommandReply,
    MachineParams,
    MotionFrame,
    Payload,
    ServerInfo,
    ServerStats,
    Target,
    to_enum,
)

__all__ = [
    "RemoteClient",
    "ANONYMOUS",
    "DEFAULT_PORT",
    "REFUSAL_CODES",
    "make_zenoh_config",
    "check_chunk",
    "request_meta",
    "session_secret",
]

#: The identity of a client that names none (the bridge's ``motiond/<name>/command``).
ANONYMOUS = "anonymous"
#: The port a bridge listens on by default (zenoh's own).
DEFAULT_PORT = 7447
#: The codes of the bridge's own refusals (the error reply ``"<code>: <text>"``).
REFUSAL_CODES = (
    "not-allowed",
    "rate-limited",
    "late",
    "no-server",
    "no-reply",
    "bad-request",
    "busy",
    "no-session",
)
# Samples a feed keeps when the program does not read them (the oldest go first, as the
# 32-frame buffer over shared memory).
_FEED_DEPTH = 32
_CONTRACT_VERSION = 3
_MAC_DOMAIN = b"motiond-request-v3"
_SESSION_DOMAIN = b"motiond-session-v3"
_NO_GROUPS = (
    "groups work over shared memory only for now: a remote client (motion-bridge) cannot "
    "send paths or setpoints; connect with motiond.Client(name) on the server's host"
)
_NO_TOKEN = bytes(16)
_CHUNK_EXTRA = set("-_.@+=")


def _zenoh() -> Any:
    try:
        import zenoh
    except ImportError as error:
        raise errors.ConnectError(
            "a remote client needs the eclipse-zenoh package: pip install 'motiond[remote]'"
        ) from error
    return zenoh


def check_chunk(what: str, name: str) -> None:
    """Raises :class:`~motiond.errors.ConnectError` unless ``name`` is one plain chunk of a
    key expression (letters, digits, ``-_.@+=``, not starting with ``@``) — the bridge's
    rule for server names and identities."""
    plain = (
        bool(name)
        and not name.startswith("@")
        and all((c.isascii() and c.isalnum()) or c in _CHUNK_EXTRA for c in name)
    )
    if not plain:
        raise errors.ConnectError(
            f"`{name}` cannot be a {what}: use letters, digits, `-`, `_` or `.` (no `/`, `*`, "
            "`$`, `?`, `#`, no leading `@`, not empty)"
        )


def make_zenoh_config(endpoint: str, base: Optional[Union[str, Path]] = None) -> Any:
    """zenoh's config of a remote client: ``base`` (a JSON5 file: TLS, credentials) if
    given, client mode, connecting to ``endpoint``, no multicast scouting."""
    zenoh = _zenoh()
    try:
        config = zenoh.Config.from_file(str(base)) if base is not None else zenoh.Config()
        config.insert_json5("mode", '"client"')
        config.insert_json5("scouting/multicast/enabled", "false")
        config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    except Exception as error:  # zenoh raises its own ZError
        raise errors.ConnectError(f"zenoh config ({base or 'default'}): {error}") from None
    return config


def request_meta(
    token: Optional[bytes], identity: str, request: bytes, session: int, counter: int, sent_ns: int
) -> bytes:
    """The 49-byte attachment of a command: version 3, ``session`` (u128), ``counter``
    (u64), ``sent_ns`` (u64), and the MAC made with the session's ``token`` over the identity,
    the ``request``'s bytes and the rest of the attachment (all zero without a session:
    ``token`` ``None``, stop and e-stop only)."""
    head = struct.pack(
        "<BQQQQ",
        _CONTRACT_VERSION,
        session & 0xFFFF_FFFF_FFFF_FFFF,
        session >> 64,
        counter,
        sent_ns,
    )
    if token is None:
        return head + bytes(16)
    message = _MAC_DOMAIN + identity.encode() + b"\0" + request + head[1:]
    return head + hmac.new(token, message, "sha3_256").digest()[:16]


def _x25519() -> Any:
    try:
        from cryptography.hazmat.primitives.asymmetric import x25519
    except ImportError as error:
        raise errors.ConnectError(
            "a remote client's session needs the cryptography package (X25519): "
            "pip install 'motiond[remote]'"
        ) from error
    return x25519


def session_secret(private: bytes, client: bytes, bridge: bytes, session: int) -> bytes:
    """The session's 16-byte secret, agreed from this side's X25519 ``private`` key (32 raw
    bytes) and the two public keys, ``client`` and ``bridge`` (one of them this side's):
    SHA3-256 over ``b"motiond-session-v3"``, the shared secret, ``client``, ``bridge`` and
    the ``session`` id (u128 LE), its first 16 bytes. Raises ``ValueError`` when the other key
    is no usable public key."""
    x25519 = _x25519()
    key = x25519.X25519PrivateKey.from_private_bytes(private)
    own = _raw_public(key)
    theirs = bridge if client == own else client
    shared = key.exchange(x25519.X25519PublicKey.from_public_bytes(theirs))
    if shared == bytes(32):
        raise ValueError("not a usable X25519 public key")
    digest = hashlib.sha3_256(
        _SESSION_DOMAIN + shared + client + bridge + session.to_bytes(16, "little")
    ).digest()
    return digest[:16]


def _raw_public(key: Any) -> bytes:
    from cryptography.hazmat.primitives import serialization

    return bytes(
        key.public_key().public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    )


def _origin(sample: Any) -> int:
    attachment = sample.attachment
    if attachment is None:
        return 0
    data = attachment.to_bytes()
    return int.from_bytes(data, "little") if len(data) == 16 else 0


class _Copied:
    """A payload received over the network, in a private buffer: what an iceoryx2 sample is
    to :class:`~motiond.frames.Received` (``payload_ptr``, ``delete``)."""

    __slots__ = ("_buffer", "payload_ptr", "origin")

    def __init__(self, data: bytes, origin: int) -> None:
        self._buffer = ctypes.create_string_buffer(data, len(data))
        self.payload_ptr = ctypes.addressof(self._buffer)
        self.origin = origin

    def delete(self) -> None:
        """Nothing to give back: the buffer is this process's own."""


class _Feed:
    """The samples of one key expression, in order: those a zenoh subscription delivers
    (its callback runs on a zenoh thread) and those fetched with a query, bounded to the
    newest ``_FEED_DEPTH``. Duck-types :class:`~motiond.frames.LatestCache`."""

    def __init__(
        self, payload_type: Type[Payload], key: str, server: str, wrap: Optional[Callable[[Any], Any]]
    ) -> None:
        self._type = payload_type
        self._key = key
        self._server = server
        self._wrap = wrap if wrap is not None else (lambda s: Received(s, payload_type))
        self._queue: Deque[Tuple[bytes, int]] = collections.deque(maxlen=_FEED_DEPTH)
        self._ready = threading.Condition()
        self._newest: Optional[Any] = None
        self._subscriber: Any = None

    def subscribe(self, session: Any) -> None:
        """Subscribes to the key (samples arrive on zenoh's thread)."""
        self._subscriber = session.declare_subscriber(self._key, self._on_sample)

    def _on_sample(self, sample: Any) -> None:
        self.push(sample.payload.to_bytes(), _origin(sample))

    def push(self, data: bytes, origin: int) -> None:
        """Queues one payload's bytes."""
        with self._ready:
            self._queue.append((data, origin))
            self._ready.notify_all()

    @property
    def current(self) -> Optional[Any]:
        """The newest sample taken so far."""
        return self._newest

    def refresh(self) -> Optional[Any]:
        """Takes every waiting sample and keeps the newest; returns it (or the one before)."""
        while self.take_next() is not None:
            pass
        if self._newest is not None and self._newest.released:
            self._newest = None
        return self._newest

    def take_next(self) -> Optional[Any]:
        """The oldest waiting sample, kept as the newest; ``None`` when none waits."""
        with self._ready:
            if not self._queue:
                return None
            data, origin = self._queue.popleft()
        if len(data) != ctypes.sizeof(self._type):
            raise IncompatibleServer(
                f"{self._server} ({self._key}: {len(data)} bytes, this client's "
                f"{self._type.__name__} has {ctypes.sizeof(self._type)})",
                0,
                SCHEMA_VERSION,
            )
        received = self._wrap(_Copied(data, origin))
        self._newest = received
        return received

    def wait(self, timeout: float) -> bool:
        """Sleeps until a sample waits or ``timeout`` s pass; whether one waits."""
        with self._ready:
            return self._ready.wait_for(lambda: bool(self._queue), max(0.0, timeout))

    def close(self) -> None:
        """Ends the subscription and drops the kept sample."""
        if self._subscriber is not None:
            try:
                self._subscriber.undeclare()
            except Exception:  # the session may be closed already
                pass
            self._subscriber = None
        self._newest = None


class RemoteClient(Client, transport="remote"):
    """A :class:`~motiond.Client` that talks to a ``motion-bridge`` over zenoh (see the
    module's documentation). ``endpoint`` is the bridge's zenoh endpoint
    (``tcp/host-a:7447``; ``tls/…`` with a zenoh built with TLS and ``zenoh_config``)."""

    def __init__(
        self,
        name: str = "demo",
        timeout: float = DEFAULT_CONNECT_TIMEOUT,
        *,
        remote: Optional[str] = None,
        identity: str = ANONYMOUS,
        zenoh_config: Optional[Union[str, Path]] = None,
        reply_timeout: float = DEFAULT_REPLY_TIMEOUT,
        node_name: str = "motiond-python",
    ) -> None:
        del node_name  # no iceoryx2 node here
        if remote is None:
            raise errors.ConnectError("a remote client needs the bridge's endpoint (remote=)")
        if sys.byteorder != "little":
            raise errors.ConnectError(
                "the bridge's payloads are little-endian C layouts; this client maps them "
                "in place and needs a little-endian host"
            )
        zenoh = _zenoh()
        check_chunk("server name", name)
        check_chunk("remote identity", identity)
        started = time.monotonic()
        deadline = started + timeout
        self._init_state(name, reply_timeout)
        self._endpoint = remote
        self._identity = identity
        self._prefix = f"motiond/{name}"
        config = make_zenoh_config(remote, zenoh_config)
        while True:
            try:
                self._session = zenoh.open(config)
                break
            except Exception as error:
                if time.monotonic() >= deadline:
                    raise NoBridge(name, remote, str(error)) from None
                time.sleep(0.1)
        self._id = ClientId.from_int(secrets.randbits(128))
        self._feeds: List[_Feed] = []
        self._grant: Optional[Tuple[int, bytes]] = None
        self._token: Any = None
        self._counter = 0
        try:
            # Refused (an identity that may only stop, a full table) or unanswered, the
            # client goes on without a session: stop and e-stop need none, and the
            # description's fetch below says whether a bridge answers at all.
            self._open_session(min(2.0, max(0.2, deadline - time.monotonic())), -1)
        except errors.MotiondError:
            pass
        try:
            # Subscribe first, so that no description published meanwhile is missed.
            self._info = self._feed(ServerInfo, "info", subscribe=True)
            self._frames = self._feed(MotionFrame, "frame", subscribe=True, wrap=Frame)
            self._stats = self._feed(ServerStats, "stats", subscribe=True)
        except Exception as error:
            self._session.close()
            raise RemoteError("subscribe to the bridge's keys", error) from None
        why = self._first(self._info, max(timeout, 0.5) + started - time.monotonic())
        if why is not None:
            self.close()
            if why.startswith("no motion-bridge"):
                raise NoBridge(name, remote, why)
            raise NoInfo(name, f"{self._prefix}/info at {remote} ({why})", timeout)
        description = self.info
        if description.schema_version != SCHEMA_VERSION:
            self.close()
            raise IncompatibleServer(name, description.schema_version, SCHEMA_VERSION)
        self._goal_ticks = [0] * int(description.axis_count)
        # The newest statistics, if the bridge has them yet (published about once a second).
        self._fetch(self._stats, 0.3)

    # --- plumbing --------------------------------------------------------------------------

    def _feed(
        self, payload_type: Type[Payload], leaf: str, subscribe: bool, wrap: Any = None
    ) -> _Feed:
        feed = _Feed(payload_type, f"{self._prefix}/{leaf}", self._name, wrap)
        if subscribe:
            feed.subscribe(self._session)
        self._feeds.append(feed)
        return feed

    def _fetch(self, feed: _Feed, timeout: float) -> Optional[str]:
        """Asks the bridge for the newest sample of ``feed``'s key and queues it; ``None``
        when one arrived, else why not."""
        try:
            replies = self._session.get(feed._key, timeout=max(0.05, timeout))
            for reply in replies:
                if reply.ok is not None:
                    feed.push(reply.ok.payload.to_bytes(), _origin(reply.ok))
                    return None
                return _error_text(reply.err)
        except Exception as error:
            return f"zenoh: {error}"
        return f"no motion-bridge answers on {feed._key} at {self._endpoint}"

    def _first(self, feed: _Feed, timeout: float) -> Optional[str]:
        """Fetches until ``feed`` has a sample or ``timeout`` s pass; ``None`` or why not."""
        deadline = time.monotonic() + max(0.0, timeout)
        while True:
            if feed.refresh() is not None:
                return None
            remaining = deadline - time.monotonic()
            why = self._fetch(feed, min(1.0, max(0.2, remaining)))
            if why is None and feed.refresh() is not None:
                return None
            if time.monotonic() >= deadline:
                return why or "nothing arrived"
            time.sleep(0.05)

    def _wait_tick(self, timeout: float) -> None:
        """Sleeps until the next frame arrives or ``timeout`` (capped so Ctrl-C is seen)."""
        self._frames.wait(min(timeout, 0.05))

    # --- description -----------------------------------------------------------------------

    @property
    def node(self) -> Any:
        """Not available: a remote client has no iceoryx2 node."""
        raise errors.MotiondError("a remote client has no iceoryx2 node (it talks zenoh)")

    @property
    def endpoint(self) -> str:
        """The zenoh endpoint of the bridge."""
        return self._endpoint

    @property
    def identity(self) -> str:
        """The identity this client sends commands as."""
        return self._identity

    @property
    def groups(self) -> List[Any]:
        """Not available: see :meth:`group`."""
        raise errors.MotiondError(_NO_GROUPS)

    def group(self, name: str) -> Any:
        """Not available: groups take their paths and setpoints over shared memory, from
        the client's own iceoryx2 node; the bridge does not carry them (yet). The frames
        a remote client reads do carry the groups' states (``frame.group(i)``)."""
        raise errors.MotiondError(_NO_GROUPS)

    def _open_stats(self) -> None:
        """Subscribed at connection already (so :meth:`stats` is the client's own)."""

    def params(self, timeout: float = 1.0) -> List[Param]:
        """The machine parameters in effect, asked of the bridge (they are not published
        on the network)."""
        self.service_jogs()
        feed = _Feed(MachineParams, f"{self._prefix}/params", self._name, None)
        why = self._fetch(feed, timeout)
        received = feed.refresh()
        if received is None:
            raise WaitTimeout(
                f"the bridge at {self._endpoint}", f"send the machine parameters ({why})", timeout
            )
        return self._params_of(received)

    # --- commands --------------------------------------------------------------------------

    def _open_session(self, timeout: float, kind: Union[CommandKind, int]) -> None:
        """Asks the bridge for a session (for a command of ``kind``) and declares this
        client's liveliness under its public id; raises
        :class:`~motiond.errors.BridgeRefused` or :class:`~motiond.errors.RemoteError`."""
        key = f"{self._prefix}/session/{self._identity}"
        private = secrets.token_bytes(32)
        x25519 = _x25519()
        public = _raw_public(x25519.X25519PrivateKey.from_private_bytes(private))
        # The zenoh id as zenoh prints it: the bridge ends the session with this transport.
        zid = str(self._session.zid()).encode("ascii")[:32].ljust(32, b"\0")
        payload = struct.pack("<BQ", _CONTRACT_VERSION, time.monotonic_ns()) + public + zid
        try:
            replies = self._session.get(key, payload=payload, timeout=timeout, express=True)
            answer = next(iter(replies), None)
        except Exception as error:
            raise RemoteError("open a session", error) from None
        if answer is None:
            raise RemoteError(
                "open a session", TimeoutError(f"no motion-bridge answers on {key}")
            )
        if answer.ok is None:
            raise _refusal(kind, _error_text(answer.err), timeout)
        data = answer.ok.payload.to_bytes()
        if len(data) != 49 or data[0] != _CONTRACT_VERSION or data[1:17] == _NO_TOKEN:
            raise RemoteError(
                "open a session", ValueError(f"a {len(data)}-byte answer is not a session grant")
            )
        low, high = struct.unpack_from("<QQ", data, 1)
        session_id = low | (high << 64)
        try:
            token = session_secret(private, public, bytes(data[17:49]), session_id)
        except ValueError as error:
            raise RemoteError("open a session", error) from None
        try:
            liveliness = self._session.liveliness().declare_token(
                f"{self._prefix}/remote/{self._identity}/{session_id:032x}"
            )
        except Exception as error:
            raise RemoteError("declare this client's liveliness", error) from None
        self._drop_session()
        self._grant = (session_id, token)
        self._token = liveliness

    def _drop_session(self) -> None:
        self._grant = None
        if self._token is not None:
            try:
                self._token.undeclare()
            except Exception:
                pass
            self._token = None

    def send(
        self,
        index: int,
        kind: Union[CommandKind, int],
        values: Sequence[float] = (0.0, 0.0, 0.0),
        target: Union[Target, int] = Target.AXIS,
    ) -> Any:
        """Sends one request through the bridge and returns the server's reply (a copy);
        raises :class:`~motiond.errors.BridgeRefused` when the bridge refused it itself.
        A command other than stop and e-stop first opens a session if there is none, and
        once more if the bridge no longer knows this one (a refused request never reached
        the server)."""
        self._check_open()
        safety = int(kind) in (int(CommandKind.STOP), int(CommandKind.E_STOP))
        typed_kind = to_enum(CommandKind, int(kind))
        if not safety and self._grant is None:
            try:
                self._open_session(self._reply_timeout, typed_kind)
            except BridgeRefused as refused:
                # An identity that may only stop gets no session: the command itself is
                # refused with what this identity may do.
                if refused.code != "not-allowed":
                    raise
        try:
            return self._send_once(index, kind, values, target)
        except BridgeRefused as refused:
            if safety or refused.code != "no-session":
                raise
        self._drop_session()
        self._open_session(self._reply_timeout, typed_kind)
        return self._send_once(index, kind, values, target)

    def _send_once(
        self,
        index: int,
        kind: Union[CommandKind, int],
        values: Sequence[float],
        target: Union[Target, int],
    ) -> Any:
        typed_kind = to_enum(CommandKind, int(kind))
        request = self._request(index, kind, values, target)
        sequence = int(request.sequence)
        payload = bytes(request)
        # The session's secret never travels: a MAC made with it over the request does.
        if self._grant is not None:
            self._counter += 1
            session_id, token = self._grant
            meta = request_meta(
                token, self._identity, payload, session_id, self._counter, time.monotonic_ns()
            )
        else:
            meta = request_meta(None, self._identity, payload, 0, 0, time.monotonic_ns())
        key = f"{self._prefix}/command/{self._identity}"
        started = time.monotonic()
        try:
            replies = self._session.get(
                key,
                payload=payload,
                attachment=meta,
                timeout=self._reply_timeout,
                express=True,
            )
            answer = next(iter(replies), None)
        except Exception as error:
            raise RemoteError("send a command", error) from None
        if answer is None:
            if time.monotonic() - started >= 0.9 * self._reply_timeout:
                raise NoReply(typed_kind, self._reply_timeout)
            raise NoBridge(
                self._name,
                self._endpoint,
                f"no motion-bridge answers on {key} (is it running, for server `{self._name}`? "
                "does zenoh's access control let this user send on that key?)",
            )
        if answer.ok is None:
            raise _refusal(typed_kind, _error_text(answer.err), self._reply_timeout)
        data = answer.ok.payload.to_bytes()
        if len(data) != ctypes.sizeof(CommandReply):
            raise IncompatibleServer(
                f"{self._name} (a {len(data)}-byte reply; CommandReply has "
                f"{ctypes.sizeof(CommandReply)})",
                0,
                SCHEMA_VERSION,
            )
        reply = CommandReply.from_buffer_copy(data)
        if reply.sequence != sequence:
            raise RemoteError(
                "match a reply",
                ValueError(f"reply to request {reply.sequence}, expected {sequence}"),
            )
        return reply

    def notify_estop(self) -> None:
        """Latches the e-stop: across the network there is no event service, so this sends
        the e-stop command (the bridge never holds it back); no reply is awaited beyond the
        command's."""
        self.estop()

    # --- life ------------------------------------------------------------------------------

    def _release(self) -> None:
        """Ends the subscriptions and this client's liveliness, closes the session."""
        for feed in self._feeds:
            feed.close()
        self._drop_session()
        try:
            self._session.close()
        except Exception:
            pass

    def __repr__(self) -> str:
        return (
            f"RemoteClient(name={self._name!r}, remote={self._endpoint!r}, "
            f"identity={self._identity!r})"
        )


def _error_text(error: Any) -> str:
    try:
        return str(error.payload.to_string())
    except Exception:
        return "an error reply"


def _refusal(kind: Union[CommandKind, int], text: str, waited: float) -> errors.MotiondError:
    """The exception of a bridge's error reply ``"<code>: <text>"``."""
    code, _, message = text.partition(": ")
    if code == "no-server":
        return errors.ServerGone(kind)
    if code == "no-reply":
        return NoReply(kind, waited)
    if code in REFUSAL_CODES:
        return BridgeRefused(kind, code, message)
    return BridgeRefused(kind, "error", text)

