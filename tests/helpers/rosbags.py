"""An independent reader of lbr export's MCAP files: every message by topic, deserialised by rosbags."""

from __future__ import annotations

from pathlib import Path


def rosbags_messages(path: Path) -> dict[str, list]:
    import rosbags.highlevel as rosbags  # (a test dependency; the tests that use it skip without it)

    out: dict[str, list] = {}
    with rosbags.AnyReader([path]) as reader:
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, reader.deserialize(raw, conn.msgtype)))
    return out
