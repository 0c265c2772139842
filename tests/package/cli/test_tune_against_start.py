"""`gimbal2axis tune` says what the search gained over the tuning file's start (trial 0), or that it has
not left the start yet: the README's 24 trials once returned the start as the best without a word
(issue 46)."""
import pathlib

from gimbal2axis.cli.tune import against_the_start
from gimbal2axis.tune.spec import load_tuning

REPO = pathlib.Path(__file__).resolve().parents[3]


def rows(*objectives):
    return [{"trial": n, "objective_mrad": value} for n, value in enumerate(objectives)]


def test_a_tuned_best_is_said_against_the_start():
    tuning = load_tuning(REPO / "tunings" / "ship_pid.toml")   # every parameter has its start
    trials = rows(0.12983, 0.2, 0.10029)
    assert against_the_start(tuning, trials, trials[2]) == ("start (trial 0, the tuning file's start values): "
                                                            "objective 0.12983 mrad; the best 22.8% lower")


def test_a_best_at_the_start_says_the_search_has_not_left_it():
    tuning = load_tuning(REPO / "tunings" / "ship_pid.toml")
    trials = rows(0.12983, 0.2, 0.12926)
    assert "has not left the start yet; give it more --trials" in against_the_start(tuning, trials, trials[2])
    assert "has not left the start" in against_the_start(tuning, trials, trials[0])


def test_without_a_start_nothing_is_said(tmp_path):
    text = (REPO / "tunings" / "ship_pid.toml").read_text()
    no_start = tmp_path / "no_start.toml"
    no_start.write_text(text.replace(", start = 400.0", ""))
    trials = rows(0.12983, 0.10029)
    assert against_the_start(load_tuning(no_start), trials, trials[1]) is None
