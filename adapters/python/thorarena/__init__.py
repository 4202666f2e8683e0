"""ThorArena's policy side in Python: join a benchmark run over iceoryx2 shared memory.

A minimal policy::

    import thorarena as ta

    session = ta.connect("demo", name="replay", joint_names=ta.G1_JOINT_NAMES)
    offset, scale = session.action_offset_rad, session.action_scale
    for obs, actions in session.steps():
        actions[:] = (obs["reference"][:, 0]["joint_pos"] - offset) / scale

`obs` is a read-only numpy structured array of `n_envs` records straight over shared memory
(fields: `protocol.Layout.env_dtype`), `actions` a writable `(n_envs, n_joints)` float64 array
over the loaned response. The wire protocol is crate `thorarena-ipc` of this repository.
"""

from .client import (
    IceoryxSession,
    Session,
    SessionInfo,
    connect,
    process_alive,
)
from .errors import (
    LayoutMismatch,
    NoSession,
    PrivateRootError,
    SessionRefused,
    SimulatorGone,
    ThorArenaError,
    Timeout,
    TransportError,
)
from .private_root import private_root
from .protocol import (
    COMMAND_END,
    COMMAND_STEP,
    FLAG_ACTIVE,
    FLAG_PREVIOUS_TERMINATED,
    FLAG_RESET,
    G1_JOINT_NAMES,
    MAGIC,
    PROTOCOL_VERSION,
    Hello,
    Layout,
    Profile,
    Status,
    Welcome,
    joint_names_hash,
)

__all__ = [
    "COMMAND_END",
    "COMMAND_STEP",
    "FLAG_ACTIVE",
    "FLAG_PREVIOUS_TERMINATED",
    "FLAG_RESET",
    "G1_JOINT_NAMES",
    "MAGIC",
    "PROTOCOL_VERSION",
    "Hello",
    "IceoryxSession",
    "Layout",
    "LayoutMismatch",
    "NoSession",
    "PrivateRootError",
    "Profile",
    "Session",
    "SessionInfo",
    "SessionRefused",
    "SimulatorGone",
    "Status",
    "ThorArenaError",
    "Timeout",
    "TransportError",
    "Welcome",
    "connect",
    "joint_names_hash",
    "private_root",
    "process_alive",
]

__version__ = "0.1.0"
