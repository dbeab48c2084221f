"""Read a session recording with the `mcap` package's StreamReader; never crash on a damaged file.

The library parses every record and checks the chunk and data-section CRCs. Measured against the bare
`StreamReader(validate_crcs=True)` (mcap 1.6.0) on the file of tests/io/recording/test_recording.py's damage tests
(`write_file(10, flush_every=2, layout=SMALL)`, 7440 bytes, the same seeded trials): a cut at each of its
7432 byte offsets always raised (good), but of the 3000 bit-flip trials 693 raised nothing (flips in the
summary section: repeated schemas and channels, chunk indexes, statistics, metadata index, summary offsets,
footer; and one in the DataEnd record's length byte) and 1 returned messages that were not an intact
prefix (a damaged chunk skipped and later chunks returned before the data-section CRC failed at its end).
What the library could not do is kept here as a small guard:

- the footer's summary CRC and the trailing magic are not checked -> checked here;
- unknown opcodes are skipped (as the spec allows) -> in a data section only the records our writers
  produce are accepted;
- a short read is not an error in `ReadDataStream.read` (only an empty one is) -> `_StrictBytes` raises;
- a record whose fields run past its declared length is accepted (negative padding is ignored; found when
  a flipped length byte of the DataEnd record, which no CRC covers, went unnoticed) -> damage here;
- a chunk is decompressed into the size it declares -> the declared sizes are checked for plausibility
  first (a flipped size must not size an allocation);
- MCAP metadata records have no CRC -> ours carry one ("crc32"), checked here.

Records of one chunk are taken all or none; the intact prefix is everything before the first damage (the
records of the last record read whole included).
"""

from __future__ import annotations

import io
import json
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import zstandard
from mcap.records import Channel, Chunk, DataEnd, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

from teleop.core.errors import InputError
from teleop.io.recording.layout import PROFILE, crc_dict

MAGIC = b"\x89MCAP0\r\n"
_MAX_CHUNK = 256 * 1024 * 1024
# opcodes a data section of ours may hold: header, chunk, message index, metadata, data end (top level) and
# schema, channel, message (inside chunks); the summary section may hold any record
_DATA_OPS = {0x01, 0x03, 0x04, 0x05, 0x06, 0x07, 0x0C, 0x0F}


class _Damage(Exception):
    pass


class _StrictBytes(io.BytesIO):
    """BytesIO whose reads of n bytes return n bytes or raise (a truncated field is damage)."""

    def read(self, n=-1):
        b = super().read(n)
        if n is not None and n >= 0 and len(b) != n:
            raise _Damage(f"file ends inside a record (byte {self.tell()})")
        return b


class _GuardedReader(StreamReader):
    """StreamReader that rejects foreign opcodes in the data section and implausible chunk sizes."""

    in_summary = False

    def _read_record(self, opcode: int, length: int):
        if not self.in_summary and opcode not in _DATA_OPS:
            raise _Damage(f"unexpected record 0x{opcode:02x} in the data section")
        start = self._stream.count
        rec = super()._read_record(opcode, length)
        if self._stream.count - start > length:  # the library ignores a record shorter than its fields
            raise _Damage(f"record 0x{opcode:02x} is longer than the {length} bytes it declares")
        if isinstance(rec, Chunk):
            _check_chunk(rec)
        elif isinstance(rec, DataEnd):
            self.in_summary = True
        return rec


def _check_chunk(c: Chunk) -> None:
    size = c.uncompressed_size
    if size > _MAX_CHUNK or size > 2000 * len(c.data) + 4096:
        raise _Damage(f"implausible chunk size {size}")
    if c.compression == "zstd":
        try:
            declared = zstandard.frame_content_size(c.data)
        except zstandard.ZstdError as exc:
            raise _Damage(f"zstd: {exc}") from None
        if declared not in (size, -1):  # a damaged frame header must not size an allocation
            raise _Damage(f"zstd frame declares {declared} bytes, chunk {size}")
    elif c.compression not in ("", "lz4"):
        raise _Damage(f"unknown compression '{c.compression}'")
    if c.uncompressed_crc == 0 and c.compression == "":
        raise _Damage("chunk without a CRC")


@dataclass
class Session:
    """A session read back.

    Attributes:
        path: file name.
        metadata: {record name: {key: decoded JSON value}} ("session", "session_end").
        topics: {channel id: topic}.
        records: [(topic, log_time_ns, sequence, message dict)] in file order.
        damage: '' when the file is complete and every CRC matches, else what was wrong and where.
        complete: the footer was reached (the recording was closed properly).
        intact_bytes: length of the prefix that was parsed without damage.
        views: {topic: count} of messages in other encodings (the Foxglove views of teleop.io.recording.writer:
            foxglove.Log, foxglove.FrameTransforms), left to Foxglove.
    """

    path: str
    metadata: dict = field(default_factory=dict)
    topics: dict = field(default_factory=dict)
    records: list = field(default_factory=list)
    damage: str = ""
    complete: bool = False
    intact_bytes: int = 0
    views: dict = field(default_factory=dict)

    @property
    def is_intact(self) -> bool:
        return not self.damage

    def messages(self, topic: str) -> list:
        return [m for tp, _, _, m in self.records if tp == topic]

    def array(self, topic: str, name: str) -> np.ndarray:
        """Values of one field over the topic's messages, as an array ((N,) or (N, width))."""
        return np.array([m[name] for m in self.messages(topic)], dtype=float)


def recording_bytes(path) -> bytes:
    """The bytes of recording `path`; InputError naming it when it is missing or a directory."""
    p = Path(path)
    try:
        return p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{p}: is a directory, expected an .mcap recording") from None


def read_session(path) -> Session:
    """Read a recording; never raises on damage (see Session.damage), only on a file that is not MCAP."""
    return parse_session(recording_bytes(path), str(path))


def parse_session(data: bytes, name: str = "<bytes>") -> Session:
    """Parse MCAP bytes into a Session, stopping at the first damaged record (the intact prefix is kept)."""
    if len(data) < len(MAGIC) or data[:len(MAGIC)] != MAGIC:
        raise InputError(f"{name}: not an MCAP recording (bad magic bytes at offset 0)")
    s = Session(path=name)
    stream = _StrictBytes(data)
    reader = _GuardedReader(stream, validate_crcs=True, record_size_limit=len(data))
    staged, staged_topics, boundary = [], {}, len(MAGIC)
    encodings: dict = {}  # channel id -> message encoding
    footer_at = None
    records = iter(reader.records)
    reading = False  # the damage, if any, was met reading the next record (not in one already read whole)
    try:
        while True:
            reading = True
            try:
                rec = next(records)
            except StopIteration:
                break
            reading = False
            pos = stream.tell()
            if pos != boundary:  # a new top-level record: what came before it is complete
                _commit(s, staged, staged_topics)
                staged, staged_topics = [], {}
                s.intact_bytes, boundary = boundary, pos
            if reader.in_summary:
                if isinstance(rec, Footer):
                    footer_at = pos - 9 - 20
                    _check_footer(data, rec, footer_at)
                continue
            if isinstance(rec, Channel):
                staged_topics[rec.id] = rec.topic
                encodings[rec.id] = rec.message_encoding
            elif isinstance(rec, Message):
                topic = staged_topics.get(rec.channel_id, s.topics.get(rec.channel_id))
                if topic is None:
                    raise _Damage(f"message on unknown channel {rec.channel_id}")
                if encodings.get(rec.channel_id) != "json":
                    staged.append((topic, None, None, None))  # a view: counted once its chunk is whole
                    continue
                try:
                    msg = json.loads(rec.data)
                except ValueError:
                    raise _Damage("message is not valid JSON") from None
                staged.append((topic, rec.log_time, rec.sequence, msg))
            elif isinstance(rec, Metadata):
                s.metadata[rec.name] = _metadata(rec)
            elif isinstance(rec, Header) and rec.profile not in (PROFILE, ""):
                s.metadata.setdefault("_profile", rec.profile)
            elif isinstance(rec, Schema):
                pass
        _commit(s, staged, staged_topics)
        s.complete, s.intact_bytes = True, len(data)
        if stream.tell() != len(data):
            s.complete = False
            s.damage = f"{len(data) - stream.tell()} bytes after the end of the recording"
    except _Damage as exc:
        _keep_whole(s, staged, staged_topics, boundary, reading)
        s.damage = f"at byte {boundary}: {exc}"
    except Exception as exc:  # noqa: BLE001 - the library's CRC errors, struct/zstd/lz4/UTF-8 errors of
        # damaged fields: damage to report, never a crash
        _keep_whole(s, staged, staged_topics, boundary, reading)
        s.damage = f"at byte {boundary}: {type(exc).__name__}: {exc}"
    if not s.complete and not s.damage:
        s.damage = f"file ends at byte {len(data)} before the footer (recording interrupted)"
    return s


def _keep_whole(s: Session, staged: list, topics: dict, boundary: int, reading: bool) -> None:
    """On damage met while reading the next record, the records staged from the one before (read whole, its
    CRC checked) are kept: a recording killed mid-write keeps its last flushed chunk."""
    if reading:
        _commit(s, staged, topics)
        s.intact_bytes = boundary


def _commit(s: Session, staged: list, topics: dict) -> None:
    """Take the records of a whole chunk (views are only counted)."""
    for r in staged:
        if r[3] is None:
            s.views[r[0]] = s.views.get(r[0], 0) + 1
        else:
            s.records.append(r)
    s.topics.update(topics)


def _metadata(rec: Metadata) -> dict:
    m = dict(rec.metadata)
    crc = m.pop("crc32", None)
    if crc is not None and crc != crc_dict(m):
        raise _Damage(f"metadata '{rec.name}' CRC mismatch")
    try:
        return {k: json.loads(v) for k, v in m.items()}
    except ValueError:
        raise _Damage(f"metadata '{rec.name}' is not JSON") from None


def _check_footer(data: bytes, f: Footer, pos: int) -> None:
    """Summary CRC (from the summary start through the footer's own offsets) and the trailing magic."""
    if data[pos] != 0x02 or data[-len(MAGIC):] != MAGIC or pos + 9 + 20 + len(MAGIC) != len(data):
        raise _Damage("bad trailing magic after the footer")
    if not f.summary_crc and (f.summary_start or f.summary_offset_start):
        raise _Damage("footer points to a summary without a CRC")
    if f.summary_crc:
        start = f.summary_start or pos
        if not 0 < start <= pos:
            raise _Damage("summary start outside the file")
        if zlib.crc32(data[start:pos + 9 + 16]) & 0xFFFFFFFF != f.summary_crc:
            raise _Damage("summary CRC mismatch")
