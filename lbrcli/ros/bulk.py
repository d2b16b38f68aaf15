"""An MCAP file written in bulk: whole series of fixed-layout messages filled as numpy records chunk by chunk,
compressed in parallel, written in order — no Python call per message (figures: benchmarks/bench_view.py).

Every message of a channel has the same bytes except a few numbers (a CDR template with slots, :mod:`.cdr`).
Channels that share their times (the topics of one log) make one kind of row: for each channel its whole Message
record (opcode, length, channel id, sequence, log and publish time, then the message), the numbers as typed fields
at their offsets, so filling a block of rows is one numpy assignment per field. Rows of all series are merged in
log-time order and cut into chunks of ``CHUNK_BYTES``; each chunk's Message Index records (log time and offset of
every message, per channel) follow from the row offsets; chunks are compressed by a thread pool (zstd, lz4 and the
CRC release the GIL) and written as they come back. The file is standard: the ``mcap`` library's records (header,
schemas, channels, chunks, attachments, data end, summary with statistics, chunk/attachment indexes and summary
offsets, footer with CRC) laid out as its own writer does, so Foxglove seeks it and every MCAP reader reads it.
"""

from __future__ import annotations

import os
import struct
import zlib
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import BinaryIO

import numpy as np
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.writer import LIBRARY_IDENTIFIER, MCAP0_MAGIC

CHUNK_BYTES = 1 << 20  # [bytes] uncompressed chunk size aimed at: the default of the mcap libraries (C++, Rust, Python)
ZSTD_LEVEL = 1  # libmcap's default, so rosbag2's; Foxglove's Rust writer: 3 (on a 60 s log as small, 1.4x the CPU)
COMPRESSIONS = ("zstd", "lz4", "none")
_MESSAGE = struct.Struct("<BQHIQQ")  # opcode, record length, channel id, sequence, log time, publish time
_HEAD = np.dtype([("sequence", "<u4"), ("log_time", "<u8"), ("publish_time", "<u8")])  # packed, as in the record
_HEAD_AT = 11  # [bytes] its offset in a Message record
_INDEX_HEAD = struct.Struct("<BQHI")  # Message Index: opcode, record length, channel id, byte length of its entries
# Chunk up to its compression name: opcode, record length, start and end time, uncompressed size and CRC, name length
_CHUNK_HEAD = struct.Struct("<BQQQQII")
_FOOTER_FIELDS = struct.Struct("<BQQQ")  # what the summary CRC covers after the summary: opcode, length, offsets


@dataclass(frozen=True)
class Series:
    """Messages of one channel at ``times``: ``template`` (one message's bytes) with ``values[slot]`` written at
    ``slots[slot]`` = (offset [bytes], numpy dtype, count) — arrays over the messages (first axis) or constants."""

    channel_id: int
    times: np.ndarray  # (n,) int64 [ns], non-decreasing
    template: bytes
    slots: dict[str, tuple[int, str, int]] = field(default_factory=dict)
    values: dict[str, np.ndarray] = field(default_factory=dict)


class _Rows:
    """The Message records of series that share their times, one row per time: for each series in turn its record
    (header, then the message) — rows filled block by block, the numbers as typed fields at their offsets."""

    def __init__(self, group: list[Series]) -> None:
        self.times = group[0].times
        n = len(self.times)
        template = bytearray()
        names: list[str] = []
        formats: list = []
        offsets: list[int] = []
        self.values: list[np.ndarray] = []
        head = np.empty(n, _HEAD)  # the same for every channel of the group: sequence from 1 (as rosbag2 and
        head["sequence"], head["log_time"], head["publish_time"] = np.arange(1, n + 1), self.times, self.times
        for j, s in enumerate(group):  # Foxglove's writer count), publish time = log time
            base = len(template)
            template += _MESSAGE.pack(Opcode.MESSAGE, _MESSAGE.size - 9 + len(s.template), s.channel_id, 0, 0, 0)
            template += s.template
            fields = [("head", base + _HEAD_AT, _HEAD, 1, head)]
            for slot, value in s.values.items():
                at, dtype, count = s.slots[slot]
                fields.append((slot, base + _MESSAGE.size + at, dtype, count, value))
            for name, at, dtype, count, value in fields:
                shape = (n,) if count == 1 else (n, count)
                names.append(f"{j}:{name}"), formats.append(dtype if count == 1 else (dtype, count))
                offsets.append(at), self.values.append(np.broadcast_to(np.asarray(value), shape))
        self.names = names
        self.width = len(template)
        self.template = np.frombuffer(bytes(template), np.uint8)
        self.dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": self.width})
        self.record_offsets = np.cumsum([0] + [_MESSAGE.size + len(s.template) for s in group])[:-1]

    def fill(self, a: int, b: int) -> memoryview:
        """The bytes of rows a..b-1."""
        block = np.empty((b - a, self.width), np.uint8)
        block[:] = self.template
        rows = block.view(self.dtype).reshape(b - a)
        for name, value in zip(self.names, self.values):
            rows[name] = value[a:b]
        return memoryview(block).cast("B")


@dataclass(frozen=True)
class _Chunks:
    """Every row of every group in log-time order (ties: the order the series were added), cut into chunks."""

    times: np.ndarray  # (m,) [ns] of the rows in file order
    gid: np.ndarray  # (m,) their group
    row: np.ndarray  # (m,) their row in the group
    chunk: np.ndarray  # (m,) their chunk
    offset: np.ndarray  # (m,) [bytes] their offset in the chunk's records
    firsts: np.ndarray  # (chunks,) the first and last row of each chunk
    lasts: np.ndarray
    sizes: list[int]  # [bytes] uncompressed records of each chunk

    @classmethod
    def of(cls, groups: list[_Rows]) -> _Chunks:
        times = np.concatenate([g.times for g in groups])
        gid = np.concatenate([np.full(len(g.times), k) for k, g in enumerate(groups)])
        row = np.concatenate([np.arange(len(g.times)) for g in groups])
        order = np.lexsort((row, gid, times))
        times, gid, row = times[order], gid[order], row[order]
        size = np.array([g.width for g in groups], dtype=np.int64)[gid]
        start = np.cumsum(size) - size  # [bytes] each row's offset in the stream of all records
        chunk = start // CHUNK_BYTES
        chunk = np.concatenate([[0], np.cumsum(np.diff(chunk) > 0)])  # renumbered 0.. (a big row spans several)
        firsts = np.flatnonzero(np.r_[True, np.diff(chunk) > 0])
        lasts = np.r_[firsts[1:], len(chunk)] - 1
        return cls(
            times,
            gid,
            row,
            chunk,
            start - start[firsts][chunk],
            firsts,
            lasts,
            (start[lasts] + size[lasts] - start[firsts]).tolist(),
        )

    def runs(self):
        """(chunk, group, first row, end row, whether the chunk ends with it) of the runs of consecutive rows of one
        group, in file order."""
        new = np.r_[True, (np.diff(self.gid) != 0) | (np.diff(self.row) != 1) | (np.diff(self.chunk) != 0)]
        starts = np.flatnonzero(new)
        ends = np.r_[starts[1:], len(self.gid)]
        for a, b in zip(starts.tolist(), ends.tolist()):
            c = int(self.chunk[a])
            yield c, int(self.gid[a]), int(self.row[a]), int(self.row[b - 1]) + 1, b - 1 == self.lasts[c]

    def message_indexes(self, groups: list[_Rows], grouped: list[list[Series]]) -> list[list[tuple[int, bytes]]]:
        """Per chunk, (channel id, Message Index record) of every channel with messages in it."""
        indexes: list[list[tuple[int, bytes]]] = [[] for _ in self.firsts]
        for k, (g, series) in enumerate(zip(groups, grouped)):
            mine = np.flatnonzero(self.gid == k)
            bounds = np.searchsorted(self.chunk[mine], np.arange(len(self.firsts) + 1))
            for s, at in zip(series, g.record_offsets.tolist()):
                for c in np.flatnonzero(np.diff(bounds)).tolist():
                    sel = mine[bounds[c] : bounds[c + 1]]
                    indexes[c].append(
                        (s.channel_id, _message_index(s.channel_id, self.times[sel], self.offset[sel] + at))
                    )
        return indexes


def _compress(data, compression: str) -> tuple[int, bytes | memoryview]:
    """(CRC-32 of the uncompressed records, the chunk's compressed bytes) — run in worker threads."""
    crc = zlib.crc32(data)
    if compression == "zstd":
        import zstandard

        return crc, zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress(data)
    if compression == "lz4":
        import lz4.frame

        return crc, lz4.frame.compress(data)
    return crc, data


def _message_index(channel_id: int, times: np.ndarray, offsets: np.ndarray) -> bytes:
    entries = np.empty((len(times), 2), "<u8")
    entries[:, 0], entries[:, 1] = times, offsets
    return _INDEX_HEAD.pack(Opcode.MESSAGE_INDEX, 6 + entries.nbytes, channel_id, entries.nbytes) + entries.tobytes()


def _record(record) -> bytes:
    builder = RecordBuilder()
    record.write(builder)
    return builder.end()


class BulkWriter:
    """Collects schemas, channels, message series and attachments; :meth:`write` lays the whole file out at once."""

    def __init__(self, compression: str = "zstd", profile: str = "", library: str = "") -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {COMPRESSIONS}, got {compression!r}")
        self.compression = compression
        self.header = Header(profile=profile, library=f"{library} {LIBRARY_IDENTIFIER}".strip())
        self.schemas: list[Schema] = []
        self.channels: list[Channel] = []
        self.series: list[Series] = []
        self.attachments: list[Attachment] = []

    def schema(self, name: str, encoding: str, data: bytes) -> int:
        for s in self.schemas:
            if (s.name, s.encoding, s.data) == (name, encoding, data):
                return s.id
        self.schemas.append(Schema(id=len(self.schemas) + 1, name=name, encoding=encoding, data=data))
        return self.schemas[-1].id

    def channel(self, topic: str, message_encoding: str, schema_id: int, metadata: dict[str, str] | None = None) -> int:
        self.channels.append(
            Channel(
                id=len(self.channels) + 1,
                topic=topic,
                message_encoding=message_encoding,
                schema_id=schema_id,
                metadata=dict(metadata or {}),
            )
        )
        return self.channels[-1].id

    def add(self, channel_id: int, times: np.ndarray, template: bytes, slots=None, values=None) -> None:
        """Messages of a channel (each channel once): see :class:`Series`."""
        times = np.asarray(times, dtype=np.int64).reshape(-1)
        if any(s.channel_id == channel_id for s in self.series):
            raise ValueError(f"channel {channel_id} has its messages already")
        if len(times) == 0 or np.any(np.diff(times) < 0) or times[0] < 0:
            raise ValueError("message times must be non-negative, non-decreasing and at least one")
        self.series.append(Series(channel_id, times, bytes(template), dict(slots or {}), dict(values or {})))

    def attach(self, name: str, media_type: str, data: bytes, log_time: int, create_time: int) -> None:
        self.attachments.append(
            Attachment(create_time=create_time, log_time=log_time, name=name, media_type=media_type, data=data)
        )

    def write(self, out: BinaryIO) -> dict[int, int]:
        """Write the file to ``out`` (a binary file); returns the messages per channel id."""
        grouped = self._by_times()
        groups = [_Rows(g) for g in grouped]
        chunks = _Chunks.of(groups)
        counts = {s.channel_id: len(s.times) for s in self.series}
        pos = _write(out, [MCAP0_MAGIC, _record(self.header)] + [_record(r) for r in (*self.schemas, *self.channels)])
        pos, chunk_indexes = self._write_chunks(out, pos, groups, chunks, chunks.message_indexes(groups, grouped))
        pos, attachment_indexes = self._write_attachments(out, pos)
        pos += _write(out, [_record(DataEnd(data_section_crc=0))])
        statistics = Statistics(
            message_count=int(sum(counts.values())),
            schema_count=len(self.schemas),
            channel_count=len(self.channels),
            attachment_count=len(self.attachments),
            metadata_count=0,
            chunk_count=len(chunk_indexes),
            message_start_time=int(chunks.times[0]),
            message_end_time=int(chunks.times[-1]),
            channel_message_counts=dict(sorted(counts.items())),
        )
        self._write_summary(out, pos, statistics, chunk_indexes, attachment_indexes)
        return counts

    def _by_times(self) -> list[list[Series]]:
        """The series grouped by their times (the topics of one log share them: one kind of row)."""
        grouped: list[list[Series]] = []
        for s in self.series:
            same = next(
                (g for g in grouped if len(g[0].times) == len(s.times) and np.array_equal(g[0].times, s.times)), None
            )
            (same.append(s) if same is not None else grouped.append([s]))
        return grouped

    def _write_chunks(self, out: BinaryIO, pos: int, groups, chunks, indexes) -> tuple[int, list[ChunkIndex]]:
        """The data section's chunks from offset ``pos`` [bytes], each followed by its message indexes: the offset
        after them and the chunk indexes."""
        compression = "" if self.compression == "none" else self.compression
        chunk_indexes: list[ChunkIndex] = []

        def written(c: int, job) -> int:  # chunk c and its message indexes, once compressed: bytes written
            crc, body = job.result()
            head, index = _chunk_head(chunks, c, crc, body, compression, pos)
            at = pos + _write(out, [head, body])
            for channel_id, message_index in sorted(indexes[c]):
                index.message_index_offsets[channel_id] = at
                index.message_index_length += len(message_index)
                at += _write(out, [message_index])
            chunk_indexes.append(index)
            return at - pos

        # chunks filled in turn (runs of consecutive rows of one group), compressed by a pool meanwhile and written
        # in order as they come back (a few in flight: the memory of a few chunks, whatever the log's length)
        workers = os.cpu_count() or 1
        with ThreadPoolExecutor(workers) as pool:
            pending: deque = deque()
            parts: list[memoryview] = []
            for c, g, a, b, complete in chunks.runs():
                parts.append(groups[g].fill(a, b))
                if complete:
                    data = parts[0] if len(parts) == 1 else b"".join(parts)
                    pending.append((c, pool.submit(_compress, data, self.compression)))
                    parts = []
                while pending and (len(pending) > 2 * workers or pending[0][1].done()):
                    pos += written(*pending.popleft())
            while pending:
                pos += written(*pending.popleft())
        return pos, chunk_indexes

    def _write_attachments(self, out: BinaryIO, pos: int) -> tuple[int, list[AttachmentIndex]]:
        """The attachments from offset ``pos`` [bytes]: the offset after them and their indexes."""
        attachment_indexes = []
        for a in self.attachments:
            record = _record(a)
            attachment_indexes.append(
                AttachmentIndex(
                    offset=pos,
                    length=len(record),
                    log_time=a.log_time,
                    create_time=a.create_time,
                    data_size=len(a.data),
                    name=a.name,
                    media_type=a.media_type,
                )
            )
            pos += _write(out, [record])
        return pos, attachment_indexes

    def _write_summary(
        self, out: BinaryIO, summary_start: int, statistics: Statistics, chunk_indexes: list, attachment_indexes: list
    ) -> None:
        """The summary section at ``summary_start`` [bytes] (schemas, channels, statistics, chunk and attachment
        indexes, summary offsets), the footer with its CRC and the closing magic."""
        summary, offsets = bytearray(), []
        for opcode, records in (
            (Opcode.SCHEMA, self.schemas),
            (Opcode.CHANNEL, self.channels),
            (Opcode.STATISTICS, [statistics]),
            (Opcode.CHUNK_INDEX, chunk_indexes),
            (Opcode.ATTACHMENT_INDEX, attachment_indexes),
        ):
            if records:
                body = b"".join(_record(r) for r in records)
                offsets.append(
                    SummaryOffset(group_opcode=opcode, group_start=summary_start + len(summary), group_length=len(body))
                )
                summary += body
        summary_offset_start = summary_start + len(summary)
        summary += b"".join(_record(o) for o in offsets)
        crc = zlib.crc32(
            _FOOTER_FIELDS.pack(Opcode.FOOTER, 20, summary_start, summary_offset_start), zlib.crc32(summary)
        )
        footer = Footer(summary_start=summary_start, summary_offset_start=summary_offset_start, summary_crc=crc)
        _write(out, [summary, _record(footer), MCAP0_MAGIC])


def _chunk_head(chunks, c: int, crc: int, body: bytes, compression: str, pos: int) -> tuple[bytes, ChunkIndex]:
    """The Chunk record of chunk ``c`` up to its compressed ``body`` (with its CRC), written at ``pos`` [bytes], and
    its index (the message index offsets filled in as they are written)."""
    lo, hi = int(chunks.times[chunks.firsts[c]]), int(chunks.times[chunks.lasts[c]])
    length = _CHUNK_HEAD.size - 9 + len(compression) + 8 + len(body)
    head = _CHUNK_HEAD.pack(Opcode.CHUNK, length, lo, hi, chunks.sizes[c], crc, len(compression))
    head += compression.encode() + struct.pack("<Q", len(body))
    index = ChunkIndex(
        message_start_time=lo,
        message_end_time=hi,
        chunk_start_offset=pos,
        chunk_length=len(head) + len(body),
        message_index_offsets={},
        message_index_length=0,
        compression=compression,
        compressed_size=len(body),
        uncompressed_size=chunks.sizes[c],
    )
    return head, index


def _write(out: BinaryIO, parts: list) -> int:
    """Write ``parts``; their length [bytes]."""
    out.writelines(parts)
    return sum(memoryview(p).nbytes for p in parts)
