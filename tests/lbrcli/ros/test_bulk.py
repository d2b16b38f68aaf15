"""lbrcli.ros.bulk (the MCAP file written in bulk) against the `mcap` library's own writer fed one message at a time,
on random series: several channels sharing times, series with other times (ties, one message, messages larger than
a chunk), constants and per-message values, chunk sizes from below one row to many rows, every compression. Both
files are read back by the `mcap` reader and compared message by message; the bulk file's CRCs, message indexes,
chunk indexes and statistics are checked record by record."""

from __future__ import annotations

import io
import struct
import zlib

import numpy as np
import pytest

from lbrcli.ros import bulk

mcap_reader = pytest.importorskip("mcap.reader", reason="mcap is not installed (pip install -e .[test])")
from mcap.records import Chunk, ChunkIndex, Footer, MessageIndex  # noqa: E402
from mcap.stream_reader import StreamReader, get_chunk_data_stream  # noqa: E402
from mcap.writer import CompressionType, Writer  # noqa: E402

CODES = {"<f8": "d", "<i4": "i", "<u4": "I", "<u8": "Q", "<i2": "h"}


def _random_series(rng: np.random.Generator) -> list[dict]:
    """Channels as dicts: times, template, slots, values (the test's own description, written by both writers)."""
    channels = []
    for _ in range(rng.integers(1, 4)):  # groups of channels that share their times
        n = int(rng.choice([1, 2, 3, rng.integers(4, 400)]))
        times = np.sort(rng.integers(0, 10_000, n)) + int(rng.integers(0, 2)) * 1_700_000_000_000_000_000
        for _ in range(rng.integers(1, 4)):
            size = int(rng.integers(4, 300))
            template = rng.integers(0, 256, size, dtype=np.uint8).tobytes()
            slots, values, at = {}, {}, 0
            while True:  # slots at random (unaligned) offsets, in order, not overlapping
                dtype = str(rng.choice(list(CODES)))
                count = int(rng.integers(1, 5))
                at += int(rng.integers(0, 9))
                width = np.dtype(dtype).itemsize * count
                if at + width > size:
                    break
                name = f"s{len(slots)}"
                slots[name] = (at, dtype, count)
                info = np.iinfo(dtype) if dtype[1] in "iu" else None
                shape = ((n,) if count == 1 else (n, count)) if rng.random() < 0.8 else ((count,) if count > 1 else ())
                values[name] = (
                    rng.normal(0, 1e3, shape)
                    if info is None
                    else rng.integers(info.min, info.max, shape, dtype=dtype, endpoint=True)
                )
                at += width
            channels.append({"times": times, "template": template, "slots": slots, "values": values})
    for _ in range(rng.integers(0, 3)):  # single messages (a URDF, a whole trajectory), some larger than a chunk
        channels.append(
            {
                "times": np.array([int(rng.integers(0, 10_000))]),
                "template": rng.integers(0, 256, int(rng.integers(1, 30_000)), dtype=np.uint8).tobytes(),
                "slots": {},
                "values": {},
            }
        )
    return channels


def _message(channel: dict, k: int) -> bytes:
    """Message k of a channel, serialised on its own with struct (the reference's path)."""
    buf = bytearray(channel["template"])
    n = len(channel["times"])
    for name, (at, dtype, count) in channel["slots"].items():
        value = np.asarray(channel["values"][name])
        row = value[k] if value.shape[:1] == (n,) and (count == 1 or value.ndim == 2) else value
        struct.pack_into(f"<{count}{CODES[dtype]}", buf, at, *np.atleast_1d(row).tolist())
    return bytes(buf)


def _write_both(channels: list[dict], compression: str) -> tuple[bytes, bytes]:
    out = bulk.BulkWriter(compression, profile="test", library="lbr-test")
    ref = io.BytesIO()
    writer = Writer(
        ref,
        chunk_size=bulk.CHUNK_BYTES,
        compression={"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[
            compression
        ],
    )
    writer.start(profile="test", library="reference")
    schema = out.schema("test/msg/Blob", "ros2msg", b"uint8[] data\n")
    writer.register_schema("test/msg/Blob", "ros2msg", b"uint8[] data\n")
    for k, c in enumerate(channels):
        metadata = {"k": str(k)}
        out.add(out.channel(f"/c{k}", "cdr", schema, metadata), c["times"], c["template"], c["slots"], c["values"])
        writer.register_channel(f"/c{k}", "cdr", schema, metadata)
    queue = sorted((int(t), k, j) for k, c in enumerate(channels) for j, t in enumerate(c["times"]))
    for t, k, j in queue:
        writer.add_message(k + 1, t, _message(channels[k], j), t, sequence=j + 1)
    attachment = (b"<robot/>", 123, 456)
    out.attach("a.urdf", "application/xml", *attachment)
    writer.add_attachment(
        create_time=456, log_time=123, name="a.urdf", media_type="application/xml", data=attachment[0]
    )
    writer.finish()
    fh = io.BytesIO()
    out.write(fh)
    return fh.getvalue(), ref.getvalue()


def _messages(data: bytes) -> tuple[dict, object, list]:
    reader = mcap_reader.make_reader(io.BytesIO(data))
    per_topic: dict[str, list] = {}
    in_time_order = []
    for _, channel, message in reader.iter_messages(log_time_order=True):
        per_topic.setdefault(channel.topic, []).append(
            (message.log_time, message.publish_time, message.sequence, message.data)
        )
        in_time_order.append(message.log_time)
    return per_topic, reader.get_summary(), in_time_order


def _check_records(data: bytes) -> None:
    """CRCs (chunks, attachments, summary), message indexes pointing at their messages, chunk indexes at their
    chunks, messages in log-time order through the file."""
    records = list(StreamReader(io.BytesIO(data), emit_chunks=True, validate_crcs=True).records)
    summary = mcap_reader.make_reader(io.BytesIO(data)).get_summary()
    chunk_at = {ci.chunk_start_offset: ci for ci in summary.chunk_indexes}
    pos = 8  # magic
    last_time = -1
    chunk = chunk_data = None
    seen_in_chunk: dict[int, list] = {}
    for record in records:
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        if isinstance(record, Chunk):
            index: ChunkIndex = chunk_at.pop(pos)
            assert index.chunk_length == 9 + length and index.compressed_size == len(record.data)
            chunk, chunk_data = (
                index,
                get_chunk_data_stream(record, validate_crc=True)[0].read(record.uncompressed_size),
            )
            assert zlib.crc32(chunk_data) == record.uncompressed_crc != 0
            seen_in_chunk = {}
            o = 0
            while o < len(chunk_data):
                opcode, size, channel_id, _, log_time = struct.unpack_from("<BQHIQ", chunk_data, o)
                assert opcode == 0x05
                seen_in_chunk.setdefault(channel_id, []).append((log_time, o))
                assert log_time >= last_time  # the file is in log-time order
                assert index.message_start_time <= log_time <= index.message_end_time
                last_time = log_time
                o += 9 + size
            assert min(t for v in seen_in_chunk.values() for t, _ in v) == index.message_start_time
            assert max(t for v in seen_in_chunk.values() for t, _ in v) == index.message_end_time
        elif isinstance(record, MessageIndex):
            assert chunk.message_index_offsets[record.channel_id] == pos
            assert sorted(record.records) == sorted(seen_in_chunk.pop(record.channel_id))
            if not seen_in_chunk:  # every channel of the chunk has its index
                assert (
                    pos + 9 + length - chunk.message_index_offsets[min(chunk.message_index_offsets)]
                    == chunk.message_index_length
                )
        elif isinstance(record, Footer):
            assert pos == len(data) - 8 - 29  # the footer: opcode, length, two offsets, CRC; then the magic
            assert zlib.crc32(data[record.summary_start : pos + 25]) == record.summary_crc != 0
        pos += 9 + length
    assert not chunk_at  # every chunk index points at a chunk


@pytest.mark.parametrize("seed", range(24))
def test_the_bulk_file_reads_back_like_the_mcap_writers_file(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    monkeypatch.setattr(bulk, "CHUNK_BYTES", int(rng.choice([64, 700, 4096, 50_000, 1 << 20])))
    compression = ("zstd", "lz4", "none")[seed % 3]
    channels = _random_series(rng)
    data, ref = _write_both(channels, compression)
    got, summary, order = _messages(data)
    want, ref_summary, _ = _messages(ref)
    assert got.keys() == want.keys()
    for topic in want:
        assert got[topic] == want[topic], topic
    assert order == sorted(order)
    s, r = summary.statistics, ref_summary.statistics
    assert (s.message_count, s.channel_message_counts, s.message_start_time, s.message_end_time) == (
        r.message_count,
        r.channel_message_counts,
        r.message_start_time,
        r.message_end_time,
    )
    assert (s.schema_count, s.channel_count, s.attachment_count, s.chunk_count) == (
        1,
        len(channels),
        1,
        len(summary.chunk_indexes),
    )
    assert [(c.topic, c.metadata) for c in summary.channels.values()] == [
        (c.topic, c.metadata) for c in ref_summary.channels.values()
    ]
    [attachment] = mcap_reader.make_reader(io.BytesIO(data)).iter_attachments()
    assert (attachment.name, attachment.data, attachment.log_time, attachment.create_time) == (
        "a.urdf",
        b"<robot/>",
        123,
        456,
    )
    _check_records(data)
    assert {ci.compression for ci in summary.chunk_indexes} == {"" if compression == "none" else compression}


def test_a_channel_given_twice_or_times_out_of_order_are_refused():
    out = bulk.BulkWriter("none")
    c = out.channel("/a", "cdr", 0)
    out.add(c, np.array([1, 2]), b"xy")
    with pytest.raises(ValueError, match="already"):
        out.add(c, np.array([3]), b"z")
    with pytest.raises(ValueError, match="non-decreasing"):
        out.add(out.channel("/b", "cdr", 0), np.array([2, 1]), b"z")
    with pytest.raises(ValueError, match="compression"):
        bulk.BulkWriter("gzip")
