"""Drive the robot from other processes: targets over UDP (binary or JSON), followed within the limits by ruckig,
the robot state sent back; a dead-man rule brakes when targets stop or a source sends garbage.

Built on :mod:`lbrcli.fri`: :class:`TargetFollower` is an ``LBRClient``; :class:`UdpTargets` is its source.
"""

from .client import BridgeClient
from .follower import TargetFollower
from .protocol import BadTarget, State, Target, decode_state, decode_target, encode_state, encode_target
from .udp import UdpTargets

__all__ = [
    "BadTarget",
    "BridgeClient",
    "State",
    "Target",
    "TargetFollower",
    "UdpTargets",
    "decode_state",
    "decode_target",
    "encode_state",
    "encode_target",
]
