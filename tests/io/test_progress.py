"""Progress of long commands (teleop.io.progress): plain lines on a controlled clock, tqdm only on a terminal."""

import io

from teleop.io.progress import PlainProgress, progress


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_plain_line_every_interval_and_a_last_line():
    clock, out = Clock(), io.StringIO()
    with PlainProgress(10, "blind test", "participants", stream=out, interval_s=5.0, clock=clock,
                       first_s=5.0) as bar:
        for k in range(10):
            clock.t += 2.0  # 2 s per participant: a line at 6 s (k=2), 12 s (k=5), 18 s (k=8)
            bar.update()
    lines = out.getvalue().splitlines()
    assert lines == ["blind test: 3/10 participants (30 %), 6 s elapsed, about 14 s left",
                     "blind test: 6/10 participants (60 %), 12 s elapsed, about 8 s left",
                     "blind test: 9/10 participants (90 %), 18 s elapsed, about 2 s left",
                     "blind test: done, 10 participants in 20 s"]


def test_a_short_run_stays_silent_and_counts_add_up():
    clock, out = Clock(), io.StringIO()
    bar = PlainProgress(None, "palpate z", "ticks", stream=out, interval_s=5.0, clock=clock)
    for _ in range(4):
        clock.t += 0.45  # under FIRST_LINE_S in all
        bar.update(1000)
    bar.close()
    bar.close()
    assert out.getvalue() == "" and bar.n == 4000


def test_a_longer_run_says_what_it_does_within_two_seconds():
    clock, out = Clock(), io.StringIO()
    bar = PlainProgress(None, "palpate z", "ticks", stream=out, interval_s=5.0, clock=clock)
    for _ in range(8):
        clock.t += 1.0
        bar.update(1000)
    assert out.getvalue().splitlines() == ["palpate z: 2000 ticks, 2 s elapsed", "palpate z: 7000 ticks, 7 s elapsed"]


def test_not_a_terminal_gets_plain_lines():
    out = io.StringIO()  # isatty() is False
    bar = progress(5, "diagnose", unit="fits", stream=out, leave=False)
    assert isinstance(bar, PlainProgress)


def test_a_start_line_at_once_and_a_time_left_from_the_work_done():
    clock, out = Clock(), io.StringIO()
    bar = PlainProgress(10, "blind test", "participants", stream=out, interval_s=5.0, clock=clock, start_line=True)
    assert out.getvalue() == "blind test: 0/10 participants (0 %), 0 s elapsed\n"  # before the first participant
    clock.t += 6.0
    bar.update()  # one participant in 6 s: nine left, 54 s
    bar.set_postfix_str("note")
    clock.t += 6.0
    bar.update()
    bar.close()
    assert out.getvalue().splitlines()[1:] == ["blind test: 1/10 participants (10 %), 6 s elapsed, about 54 s left",
                                               "blind test: 2/10 participants (20 %), 12 s elapsed, about 48 s left, "
                                               "note",
                                               "blind test: done, 2 participants in 12 s, note"]
