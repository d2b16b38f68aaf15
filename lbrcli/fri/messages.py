"""FRI protobuf message classes, built at import from the descriptor sets compiled from the .proto files.

The ``fri_<version>.proto`` files are the source; ``fri_<version>.desc`` are their compiled FileDescriptorSets
(regenerate with ``python -m lbrcli.fri.generate``; a test checks they are in sync). Loading descriptors rather
than generated ``_pb2`` modules keeps the package independent of the protoc/protobuf runtime version pairing.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from functools import lru_cache
from importlib import resources
from typing import Any

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory


class FriVersion(str, Enum):
    """Wire format: 1.15 (bare protobuf) or 2.7 (length + protobuf + CRC-32 framing)."""

    V1_15 = "1.15"
    V2_7 = "2.7"

    @property
    def stem(self) -> str:
        return "fri_" + self.value.replace(".", "_")

    @property
    def package(self) -> str:
        return {"1.15": "lbr.fri115", "2.7": "lbr.fri27"}[self.value]


@dataclass(frozen=True)
class FriMessages:
    """Message classes and enum values of one FRI version."""

    version: FriVersion
    Monitoring: Any  # FRIMonitoringMessage class
    Command: Any  # FRICommandMessage class
    enums: dict[str, dict[str, int]]  # enum name -> {value name: number}


@lru_cache(maxsize=None)
def messages(version: FriVersion | str) -> FriMessages:
    """Message classes for an FRI version (cached; each version lives in its own descriptor pool)."""
    version = FriVersion(version)
    blob = resources.files("lbrcli.fri").joinpath(version.stem + ".desc").read_bytes()
    fds = descriptor_pb2.FileDescriptorSet.FromString(blob)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    pkg = version.package
    mon = message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{pkg}.FRIMonitoringMessage"))
    cmd = message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{pkg}.FRICommandMessage"))
    fdesc = pool.FindFileByName(version.stem + ".proto")
    enums = {name: {v.name: v.number for v in e.values} for name, e in fdesc.enum_types_by_name.items()}
    return FriMessages(version=version, Monitoring=mon, Command=cmd, enums=enums)
