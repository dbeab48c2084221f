"""Crash-safe session recording in MCAP (opens in Foxglove / PlotJuggler) and a reader that never crashes.

    layout.py    row layout, topics, JSON encoding of a row, metadata records with a CRC
    ring.py      the shared-memory ring the loop pushes rows into (the recorder and the live view read it)
    writer.py    SessionWriter on the `mcap` package's Writer
    recorder.py  the recorder process and the loop-side Recorder handle
    stats.py     per-second timing statistics from the rows
    reader.py    read_session on the `mcap` package's StreamReader, with the guard that keeps the damage
                 promises (see its docstring)

Recordings made by the hand-written writer this package replaced (tests/data/session_v1_handwriter.mcap)
read back unchanged.
"""

from teleop.io.recording.layout import (FLOAT, INT, PROFILE, TOPIC_EVENTS, TOPIC_FORCE, TOPIC_ROBOT, TOPIC_SETPOINT,
                                     TOPIC_TIMING, Layout, RowEncoder, Signal, json_schema, metadata_record)
from teleop.io.recording.reader import MAGIC, Session, parse_session, read_session
from teleop.io.recording.recorder import Recorder
from teleop.io.recording.ring import Cursor, Ring
from teleop.io.recording.stats import SecondStats
from teleop.io.recording.writer import SessionWriter

__all__ = ["FLOAT", "INT", "MAGIC", "PROFILE", "TOPIC_EVENTS", "TOPIC_FORCE", "TOPIC_ROBOT", "TOPIC_SETPOINT",
           "TOPIC_TIMING", "Cursor", "Layout", "Recorder", "Ring", "RowEncoder", "SecondStats", "Session",
           "SessionWriter", "Signal", "json_schema", "metadata_record", "parse_session", "read_session"]
