"""Turn a recording cut short (the recorder killed: no summary, no footer, perhaps a half-written last record)
into a complete, indexed MCAP file that any MCAP reader opens, seeking ones included.

The input is read record by record up to its first damaged or truncated record (chunks all or none, their
CRCs checked); every schema, channel, message, metadata record and attachment before that point is written
again with the `mcap` package's Writer, which adds the indexes, statistics, summary and footer. A metadata
record "recovered" says what was kept and why the reading stopped. Nothing is invented: a recording that
ended without its `session_end` record still has none.
"""

from __future__ import annotations

import io
from dataclasses import asdict, dataclass

from mcap.records import Attachment, Channel, Chunk, DataEnd, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, IndexType, Writer

from teleop.core.errors import InputError
from teleop.io.outputs import atomic_write
from teleop.io.recording.layout import metadata_record
from teleop.io.recording.reader import MAGIC, _check_chunk, _Damage, _StrictBytes, recording_bytes

RECOVERED = "recovered"  # name of the metadata record a recovered file carries


@dataclass
class Recovery:
    """What `recover_bytes` kept.

    Attributes:
        source: the input's name.
        input_bytes: its length.
        intact_bytes: length of the prefix whose records were kept.
        complete: the input's data section was whole, through its DataEnd record (only the summary, if
            anything, was missing; the file is rewritten all the same).
        stopped: '' when complete, else what ended the reading.
        messages, channels, schemas, metadata, attachments: records written.
    """

    source: str
    input_bytes: int
    intact_bytes: int = 0
    complete: bool = False
    stopped: str = ""
    messages: int = 0
    channels: int = 0
    schemas: int = 0
    metadata: int = 0
    attachments: int = 0


class _Reader(StreamReader):
    """StreamReader that checks a chunk's declared sizes before it sizes an allocation (reader._check_chunk)."""

    def _read_record(self, opcode: int, length: int):
        rec = super()._read_record(opcode, length)
        if isinstance(rec, Chunk):
            _check_chunk(rec)
        return rec


def recover_bytes(data: bytes, out, name: str = "<bytes>") -> Recovery:
    """Write to binary stream `out` a complete MCAP holding the records of `data` before its first damage."""
    if len(data) < len(MAGIC) or data[:len(MAGIC)] != MAGIC:
        raise InputError(f"{name}: not an MCAP recording (bad magic bytes at offset 0)")
    rep = Recovery(source=name, input_bytes=len(data))
    stream = _StrictBytes(data)
    reader = _Reader(stream, validate_crcs=True, record_size_limit=len(data))
    records, boundary, header = [], len(MAGIC), None
    try:
        for rec in reader.records:
            boundary = stream.tell()  # the end of the top-level record this one came in
            if isinstance(rec, Header):
                header = rec
            elif isinstance(rec, DataEnd):
                rep.intact_bytes, rep.complete = boundary, True
                break  # the summary is written anew
            elif isinstance(rec, (Schema, Channel, Message, Metadata, Attachment)):
                records.append(rec)
        else:
            rep.stopped = f"file ends at byte {len(data)} before its footer"
            rep.intact_bytes = stream.tell()
    except _Damage as exc:  # every record read before this one is whole (a chunk's records come all at once)
        rep.stopped, rep.intact_bytes = f"at byte {boundary}: {exc}", boundary
    except Exception as exc:  # noqa: BLE001 - CRC, struct, zstd, length-limit errors of a damaged record: the end
        rep.stopped, rep.intact_bytes = f"at byte {boundary}: {type(exc).__name__}: {exc}", boundary
    if header is None:
        raise InputError(f"{name}: no MCAP header record survived ({rep.stopped or 'empty'}); nothing to recover")
    if rep.complete:
        rep.stopped = ""
    _write(out, header, records, rep)
    return rep


def _write(out, header: Header, records: list, rep: Recovery) -> None:
    w = Writer(out, compression=CompressionType.ZSTD, index_types=IndexType.ALL, enable_crcs=True,
               enable_data_crcs=True)
    w.start(header.profile, header.library)
    schema_ids, channel_ids = {0: 0}, {}
    for rec in records:
        if isinstance(rec, Schema):
            schema_ids[rec.id] = w.register_schema(rec.name, rec.encoding, rec.data)
            rep.schemas += 1
        elif isinstance(rec, Channel):
            if rec.schema_id not in schema_ids:
                continue  # its schema was lost: its messages cannot be decoded
            channel_ids[rec.id] = w.register_channel(rec.topic, rec.message_encoding, schema_ids[rec.schema_id],
                                                     dict(rec.metadata))
            rep.channels += 1
        elif isinstance(rec, Message):
            if rec.channel_id in channel_ids:
                w.add_message(channel_ids[rec.channel_id], rec.log_time, rec.data, rec.publish_time, rec.sequence)
                rep.messages += 1
        elif isinstance(rec, Metadata):
            w.add_metadata(rec.name, dict(rec.metadata))
            rep.metadata += 1
        elif isinstance(rec, Attachment):
            w.add_attachment(rec.create_time, rec.log_time, rec.name, rec.media_type, rec.data)
            rep.attachments += 1
    w.add_metadata(RECOVERED, metadata_record({k: v for k, v in asdict(rep).items()}))
    w.finish()


def recover_file(src, dst) -> Recovery:
    """Recover recording `src` into `dst` (written whole or not at all); InputError on a file that is not MCAP."""
    data = recording_bytes(src)
    buf = io.BytesIO()
    rep = recover_bytes(data, buf, str(src))  # before anything is created: a bad input leaves no trace
    atomic_write(dst, lambda tmp: tmp.write_bytes(buf.getvalue()))
    return rep
