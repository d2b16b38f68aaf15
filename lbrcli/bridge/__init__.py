"""Drive the robot from other processes: joint or TCP-pose targets over UDP or MQTT (binary or JSON), followed within
the limits by online IK and ruckig, the robot state sent back; a dead-man rule brakes when targets stop or the
source sends garbage.

Built on :mod:`lbrcli.fri`: :class:`TargetFollower` is an ``LBRClient``; a :class:`TargetInbox` over
:class:`UdpTransport` and :class:`MqttTransport` is its source; :class:`BridgeClient` and :class:`MqttBridgeClient`
are the source side in Python.
"""

from .client import BridgeClient, MqttBridgeClient
from .follower import TargetFollower
from .inbox import TargetInbox, Transport
from .mqtt import MqttTransport, MqttUnavailable
from .protocol import (
    KIND_JOINT,
    KIND_POSE,
    KIND_POSE_ZYX,
    BadTarget,
    State,
    Target,
    decode_state,
    decode_target,
    encode_state,
    encode_state_json,
    encode_target,
    sign,
    verify,
)
from .timeline import TargetTimeline, TimelineOptions
from .udp import UdpTargets, UdpTransport

__all__ = [
    "KIND_JOINT",
    "KIND_POSE",
    "KIND_POSE_ZYX",
    "BadTarget",
    "BridgeClient",
    "MqttBridgeClient",
    "MqttTransport",
    "MqttUnavailable",
    "State",
    "Target",
    "TargetFollower",
    "TargetInbox",
    "TargetTimeline",
    "TimelineOptions",
    "Transport",
    "UdpTargets",
    "UdpTransport",
    "decode_state",
    "decode_target",
    "encode_state",
    "encode_state_json",
    "encode_target",
    "sign",
    "verify",
]
