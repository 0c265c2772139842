"""Progress displays (gimbal2axis.progress for a scene run, gimbal2axis.sweep.progress for a sweep), both
through tqdm: into a pipe or a log whole lines and never a carriage return; on a terminal a bar
redrawn in place, also on one that reports no size."""
import io

import pytest

from gimbal2axis.progress import Progress as SceneProgress
from gimbal2axis.sweep.progress import Progress as SweepProgress

pytestmark = pytest.mark.python_bound


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_scene_run_logs_a_line_per_tenth_into_a_pipe():
    log = io.StringIO()
    bar = SceneProgress(2.0, stream=log, quiet_for=0.0)
    for k in range(1, 201):
        bar.update(k * 0.01)
    bar.close()
    text = log.getvalue()
    lines = text.splitlines()
    assert "\r" not in text
    assert len(lines) == 11, lines                   # the first update, then 10 %, 20 %, ..., 100 %
    assert lines[0].startswith("t = 0.010 of 2 s") and lines[1].startswith("t = 0.200 of 2 s")
    assert "s/s" in lines[1]                         # the real-time factor
    assert lines[-1].startswith("t = 2.000 of 2 s") and "100.0 %" in lines[-1]


def test_a_short_scene_run_stays_quiet():
    log = io.StringIO()
    bar = SceneProgress(2.0, stream=log)             # quiet for its first second
    bar.update(1.0)
    bar.close()
    assert log.getvalue() == ""


def test_a_scene_run_draws_a_bar_on_a_terminal_without_a_size():
    screen = Terminal()                              # no fileno: reports no size
    bar = SceneProgress(1.0, stream=screen, quiet_for=0.0)
    bar.update(0.5)
    bar.close()
    text = screen.getvalue()
    assert "\r" in text and "t = 1.000 of 1 s" in text and "100%" in text


def test_a_sweep_logs_lines_starting_with_the_count_into_a_pipe():
    log = io.StringIO()
    bar = SweepProgress(20, stream=log)
    for k in range(20):
        bar.update("ok" if k % 5 else "failed")
    bar.close()
    text = log.getvalue()
    lines = text.splitlines()
    assert "\r" not in text
    assert lines[0].startswith("[ 1/20]") and lines[-1].startswith("[20/20]")
    assert "ok 16  failed 4" in lines[-1]
    assert len(lines) == 11                          # the first case, then every 10 %
