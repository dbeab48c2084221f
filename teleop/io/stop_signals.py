"""How a long command is stopped from outside: SIGINT (Ctrl-C), SIGTERM (timeout, systemd, SLURM) and SIGHUP
(the terminal closed), sent to the process or to its whole process group, once or repeatedly.

`teleop.apps.cli.main` installs one handler for the three (`install`) for the whole command. The first signal
is remembered in `STOP` (`STOP.signum`, `STOP.name`); what happens next depends on what the command is doing:

- a command that polls (the session loop, under ``with STOP.polled():``) is not interrupted: it checks
  ``STOP.signum`` between ticks, ends its run, writes its partial results marked interrupted and returns;
- any other command gets a KeyboardInterrupt where it stands, as Ctrl-C gives it.

Either way the command exits 128 + the signal's number (130 SIGINT, 143 SIGTERM, 129 SIGHUP). A repeated
signal never interrupts the clean-up the first one started. The processes a command forks (recorder, live
view, robot process) get the group's signals too: they ignore them (`ignore_stop_signals`, and the handler
does nothing in a forked child) and are shut down by the parent in order.
"""

from __future__ import annotations

import os
import signal
from contextlib import contextmanager

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def ignore_stop_signals() -> None:
    """In a forked child process: ignore SIGINT, SIGTERM and SIGHUP (its parent stops it)."""
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)


def exit_code(signum: int) -> int:
    """The shell's exit code of a command ended by signal `signum`: 128 + its number."""
    return 128 + int(signum)


class Stop:
    """The stop request of this process: `signum` (0: none yet) and how a signal is delivered (see module)."""

    def __init__(self):
        self.signum = 0
        self.count = 0  # signals received (the repeats do nothing more)
        self.polling = 0  # > 0 while a loop checks `signum` itself
        self.pid = os.getpid()
        self._old = {}

    @property
    def name(self) -> str:
        """"SIGTERM" etc., or "" when no signal arrived."""
        return signal.Signals(self.signum).name if self.signum else ""

    def handle(self, signum, frame=None) -> None:
        """The signal handler."""
        if os.getpid() != self.pid:  # a forked child, before it ignores the signals: its parent stops it
            return
        self.count += 1
        if self.signum:
            return  # a repeat: the first one's clean-up is under way
        self.signum = int(signum)
        if not self.polling:
            raise KeyboardInterrupt

    def install(self) -> None:
        """Take SIGINT, SIGTERM and SIGHUP (forgetting any earlier request)."""
        self.signum, self.count, self.polling, self.pid = 0, 0, 0, os.getpid()
        for s in STOP_SIGNALS:
            self._old[s] = signal.signal(s, self.handle)

    def uninstall(self, ignore: bool = False) -> None:
        """Give the signals back to the handlers they had before `install`, or with `ignore` set them to be
        ignored instead: one replacement per signal, so that no default handler is put back in between (a
        stopped command's repeat arriving there would kill the interpreter's shutdown, joining its children)."""
        for s, old in self._old.items():
            signal.signal(s, signal.SIG_IGN if ignore else old)
        self._old = {}

    @contextmanager
    def polled(self):
        """While active, a signal only sets `signum`: the code inside checks it (no KeyboardInterrupt)."""
        self.polling += 1
        try:
            yield self
        finally:
            self.polling -= 1

    def requested(self) -> bool:
        """True once a stop signal arrived."""
        return self.signum != 0


STOP = Stop()
