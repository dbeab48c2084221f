"""One session's MCAP file, written with the `mcap` package's Writer.

JSON messages per topic with a JSON schema each (Foxglove and PlotJuggler open them with no set-up), floats
bit-exact (NaN/inf stored as null). Where one of Foxglove's well-known schemas fits, a view in it is written
beside the JSON (protobuf, foxglove-sdk's encoders): every state change as foxglove.Log on /teleop/log, the
end effector and stylus as foxglove.FrameTransforms on /tf at 100 Hz of session time (Foxglove's Log and
3D panels); teleop.io.recording.reader counts these views and leaves them to Foxglove. Crash safety comes from the library's `Writer.flush()`, which closes the
open chunk (zstd, with its CRC) and flushes the stream: the recorder calls it every `flush_interval`, so a
SIGKILL loses at most that much. The data section has the library's CRC (`enable_data_crcs`), the summary
(indexes, statistics) is written by `finish()` so Foxglove can seek a closed recording. Metadata records
("session", "session_end") carry a CRC32 of their content (MCAP metadata has none).

Cost: the library's add_message runs in the recorder process, which the loop does not share.
"""

from __future__ import annotations

import json

import numpy as np
from foxglove.messages import FrameTransforms, Log
from mcap.writer import CompressionType, IndexType, Writer

from teleop.io.recording.foxglove import fault_log, frame_transforms
from teleop.io.recording.layout import (PROFILE, TOPIC_EVENTS, TOPIC_TIMING, Layout, RowEncoder, event_schema,
                                        json_schema, metadata_record)
from teleop.io.recording.pacing import Pacer
from teleop.io.recording.stats import timing_schema

LIBRARY = "cdpr-teleop recorder (mcap python)"
TOPIC_LOG, TOPIC_TF = "/teleop/log", "/tf"
TF_RATE = 100.0  # /tf messages per second of session time [Hz]


class SessionWriter:
    """Write rows, events and metadata of one session to `stream` (a binary file object)."""

    def __init__(self, stream, layout: Layout, metadata: dict, t0_ns: int):
        self.stream = stream
        self.t0_ns = int(t0_ns)
        self.w = Writer(stream, chunk_size=1 << 26, compression=CompressionType.ZSTD, index_types=IndexType.ALL,
                        enable_crcs=True, enable_data_crcs=True)
        self.w.start(PROFILE, LIBRARY)
        self.encoder = RowEncoder(layout)
        self.channels = {}
        extra = ((TOPIC_EVENTS, event_schema()), (TOPIC_TIMING, timing_schema(layout)))
        for topic, schema in [(t, json_schema(layout, t)) for t in layout.topics()] + list(extra):
            sid = self.w.register_schema(topic, "jsonschema", schema)
            self.channels[topic] = self.w.register_channel(topic, "json", sid)
        self._views(layout)
        self.event_seq = 0
        self.w.add_metadata("session", metadata_record(metadata))
        self.w.flush()

    def _views(self, layout: Layout) -> None:
        """Channels in Foxglove's schemas (protobuf): /teleop/log always, /tf when the row has the poses."""
        for topic, cls in ((TOPIC_LOG, Log), (TOPIC_TF, FrameTransforms)):
            sc = cls.get_schema()
            sid = self.w.register_schema(sc.name, "protobuf", bytes(sc.data))
            self.channels[topic] = self.w.register_channel(topic, "protobuf", sid)
        names = {s.name for s in layout.signals}
        self.tf_cols = layout.columns() if {"setpoint_cp", "measured_cp"} <= names else None
        self.tf_pacer = Pacer(TF_RATE)
        self.n_tf = self.n_log = 0

    def log_time(self, t: float) -> int:
        return max(0, self.t0_ns + int(round(t * 1e9)))

    def write_row(self, row: np.ndarray) -> None:
        ch, add = self.channels, self.w.add_message
        for topic, tick, t, payload in self.encoder.encode(row):
            lt = self.log_time(t)
            add(ch[topic], lt, payload, lt, tick & 0xFFFFFFFF)
        if self.tf_cols is not None and self.tf_pacer.due(t):
            self.n_tf += 1
            lt = self.log_time(t)
            ee, stylus = row[self.tf_cols["setpoint_cp"]].tolist(), row[self.tf_cols["measured_cp"]].tolist()
            add(ch[TOPIC_TF], lt, frame_transforms(ee, stylus, lt), lt, self.n_tf)

    def write_json(self, topic: str, t: float, obj: dict) -> None:
        self.event_seq += 1
        lt = self.log_time(t)
        self.w.add_message(self.channels[topic], lt, json.dumps(obj, default=str).encode(), lt, self.event_seq)
        if topic == TOPIC_EVENTS:
            self.n_log += 1
            self.w.add_message(self.channels[TOPIC_LOG], lt, fault_log(obj, lt), lt, self.n_log)

    def flush(self) -> None:
        """Close the open chunk and flush the stream: everything written so far survives a crash."""
        self.w.flush()

    def finish(self, end_metadata: dict) -> None:
        self.w.flush()
        self.w.add_metadata("session_end", metadata_record(end_metadata))
        self.w.finish()
        self.stream.flush()
