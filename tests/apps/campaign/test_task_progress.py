"""Campaign progress without a terminal: teleop.io.progress's plain lines on a controlled clock, also while a
long task runs (the ticker), failures noted as they happen; a tqdm bar on a terminal."""

import io

from teleop.apps.campaign.task_progress import TaskProgress


class Clock:
    t = 100.0

    def __call__(self):
        return self.t


def test_plain_lines_also_between_tasks_and_a_last_line():
    clock, out = Clock(), io.StringIO()
    p = TaskProgress(10, "campaign", out, bar=False, interval=5.0, clock=clock, ticker=False)
    clock.t += 2.0
    p.update()                   # 2 s: too soon for a line
    assert out.getvalue() == ""
    clock.t += 3.0
    p.update(ok=False)           # 5 s: 2 tasks
    p.note("task failed: x=1; participants 1-1: PressAborted: ...")
    clock.t += 1.0
    p.tick()                     # 6 s: a tick prints only when the interval has passed
    clock.t += 5.0
    p.tick()                     # 11 s: a long task, nothing finished: the line comes anyway
    p.close()
    p.close()
    assert out.getvalue().splitlines() == [
        "campaign: 2/10 tasks (20 %), 5 s elapsed, about 20 s left",
        "task failed: x=1; participants 1-1: PressAborted: ...",
        "campaign: 2/10 tasks (20 %), 11 s elapsed, about 44 s left",
        "campaign: done, 2 tasks in 11 s"]
    assert p.failed == 1


def test_bar_on_a_terminal_counts_tasks_and_failures():
    out = io.StringIO()
    with TaskProgress(3, "campaign", out, bar=True, ticker=False) as p:
        p.update()
        p.update(ok=False)
        p.note("task failed: x")
    text = out.getvalue()
    assert "2/3" in text and "failed=1" in text and "task failed: x" in text
