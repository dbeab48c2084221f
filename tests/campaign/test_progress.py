"""Progress without a terminal: a plain line every `interval` seconds of a controlled clock, and at the end."""

import io

from teleop.campaign.progress import Progress


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_plain_lines_every_interval_with_rate_and_eta():
    clock, out = Clock(), io.StringIO()
    p = Progress(10, "campaign", out, bar=False, interval=5.0, clock=clock, ticker=False)
    clock.t += 2.0
    p.update()                   # 2 s: too soon for a line
    assert out.getvalue() == ""
    clock.t += 3.0
    p.update(ok=False)           # 5 s: 2 tasks, one failed
    assert out.getvalue() == "campaign: 2/10 tasks, 1 failed, 0.40 task/s, elapsed 0:05, ETA 0:20\n"
    clock.t += 1.0
    p.tick()                     # a tick between tasks prints only when the interval has passed
    assert out.getvalue().count("\n") == 1
    clock.t += 5.0
    p.tick()                     # a long task: the line comes anyway
    assert out.getvalue().count("\n") == 2
    p.close()
    p.close()
    last = out.getvalue().splitlines()[-1]
    assert last.startswith("campaign: 2/10 tasks, 1 failed") and out.getvalue().count("\n") == 3


def test_bar_on_a_terminal_counts_tasks():
    out = io.StringIO()
    with Progress(3, "campaign", out, bar=True, ticker=False) as p:
        p.update()
        p.note("task failed: x")
    text = out.getvalue()
    assert "1/3" in text and "task failed: x" in text
