"""The operator's live view: the session served over Foxglove's WebSocket protocol while it runs.

    process.py   LiveView (loop-side handle) and the live process fed from the loop's shared-memory ring
    channels.py  the channels, their rates, and the messages built from a tick row (foxglove schemas)
    server.py    the Foxglove WebSocket server with per-viewer drop counters

Open it in Foxglove: "Open connection" -> Foxglove WebSocket -> ws://localhost:PORT, then import
examples/foxglove-layout.json (a session with FBG sensors: examples/foxglove-layout-fbg.json; docs/live-view.md).
"""

from teleop.loop.live.process import LiveView

__all__ = ["LiveView"]
