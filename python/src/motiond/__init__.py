"""Python client of motiond, the real-time shared-memory motion server.

Connect to a running server, read its per-tick frames straight from shared memory, command
its axes and signals, wait for them::

    import motiond

    with motiond.Client("demo") as client:
        client.wait_ready()
        x = client.axis("x")
        x.ramp_to(10.0)                 # 0.0 velocity/accel: the axis's maxima
        x.wait_until_arrived(timeout=10)
        print(x.state().position, x.unit)

        with x.jog(-2.0):               # renewed while we read; stops when the block ends
            for frame in client.frames():
                if frame.axis(x.index).position < 5.0:
                    break

        gantry = client.group("gantry")   # [[group]]: axes that move together
        gantry.move_to([100.0, 0.0, 20.0])
        gantry.wait_done(timeout=30)    # GroupAborted names the reason, axis, figures

        with client.group("base").stream("velocity") as stream:   # claims the group
            stream.run_each_tick(lambda frame: [10.0, 10.0], duration=1.0)

Everything goes through iceoryx2 (the ``iceoryx2`` package from PyPI) and the payload
mirrors of :mod:`motiond.ipc`. Refusals raise the :class:`Refused` subclass of the
server's :class:`Reason` (:class:`OutOfRange`, :class:`EstopLatched`, …).
"""

from __future__ import annotations

import iceoryx2 as _iox2

# iceoryx2 warns on stdout when it runs without a config file (the normal case for a
# client); keep a client quiet unless IOX2_LOG_LEVEL asks for more.
_iox2.set_log_level_from_env_or(_iox2.LogLevel.Error)

from . import ipc  # noqa: E402
from .axis import Axis, AxisStatus  # noqa: E402
from .client import Client  # noqa: E402
from .commission import Commissioned, DeviceClaim  # noqa: E402
from .errors import *  # noqa: E402,F401,F403
from .errors import __all__ as _error_names  # noqa: E402
from .frames import Frame, Received  # noqa: E402
from .group import Group, GroupClaim, PathStarted  # noqa: E402
from .groupstate import GroupStatus  # noqa: E402
from .ipc import (  # noqa: E402
    AxisFlags,
    AxisMode,
    CommandKind,
    CommissionWhat,
    DeviceState,
    FaultCode,
    FrameFlags,
    GroupAbort,
    GroupMotion,
    Reason,
    SignalFlags,
    SignalKind,
    StreamMode,
    StreamState,
)
from .jog import Jog  # noqa: E402
from .remote import RemoteClient  # noqa: E402
from .session import (  # noqa: E402
    DEFAULT_CONNECT_TIMEOUT,
    DEFAULT_REPLY_TIMEOUT,
    Accepted,
    Param,
)
from .signal import Signal, SignalEvent, SignalStatus  # noqa: E402
from .stream import DEFAULT_LEAD, SetpointStream  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "ipc",
    "Client",
    "RemoteClient",
    "Accepted",
    "Param",
    "Commissioned",
    "DeviceClaim",
    "Axis",
    "AxisStatus",
    "Signal",
    "SignalEvent",
    "SignalStatus",
    "Jog",
    "Group",
    "GroupClaim",
    "GroupStatus",
    "PathStarted",
    "DEFAULT_LEAD",
    "SetpointStream",
    "Frame",
    "Received",
    "AxisFlags",
    "AxisMode",
    "CommandKind",
    "CommissionWhat",
    "DeviceState",
    "FaultCode",
    "FrameFlags",
    "GroupAbort",
    "GroupMotion",
    "StreamMode",
    "StreamState",
    "Reason",
    "SignalFlags",
    "SignalKind",
    "DEFAULT_CONNECT_TIMEOUT",
    "DEFAULT_REPLY_TIMEOUT",
    *_error_names,
]
