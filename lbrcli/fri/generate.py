"""Regenerate the FRI descriptor sets from the .proto files: ``python -m lbrcli.fri.generate`` (needs grpcio-tools)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).parent
STEMS = ("fri_1_15", "fri_2_7")


def compile_descriptor(stem: str) -> bytes:
    """The FileDescriptorSet of ``<stem>.proto`` compiled by protoc (grpc_tools)."""
    from grpc_tools import protoc

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / f"{stem}.desc"
        rc = protoc.main(["protoc", f"-I{HERE}", f"--descriptor_set_out={out}", str(HERE / f"{stem}.proto")])
        if rc != 0:
            raise RuntimeError(f"protoc failed on {stem}.proto")
        return out.read_bytes()


def main() -> int:
    for stem in STEMS:
        (HERE / f"{stem}.desc").write_bytes(compile_descriptor(stem))
        print(f"wrote {HERE / stem}.desc")
    return 0


if __name__ == "__main__":
    sys.exit(main())
