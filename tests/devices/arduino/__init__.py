"""Tests of the Arduino link: host framing/messages (pure) and the real firmware in simavr over a pty."""
