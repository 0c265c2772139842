"""A failure names its culprit in one bounded line (issue 44, item 15): a user controller whose
step() returns what is no pair of voltages, or sets a `reference` that is no pair of angles, ends the
run part-way (exit 3, the record kept) with the controller's class and file and what was wrong with the
value, never a bare OverflowError or ValueError; user text in a message (a controller's exception, a
name) is cut to an excerpt with its control characters escaped, so that a 1 MB or multi-line text, a
NUL or a terminal escape cannot flood or rewrite the terminal."""
import json

import pytest

from gimbal2axis.cli.main import main
from gimbal2axis.errors import EXCERPT_CHARS, LONGEST_MESSAGE_CHARS, excerpt, one_line, shown

from support.scenes import cheap_scene

pytestmark = pytest.mark.python_bound

# A cheap gimbal on a fixed base: these runs need the controller's failure, not the physics.
SCENE = cheap_scene(stop_time=0.05) + """[controller]
type = "python"
file = "culprits.py"
class = "{cls}"
"""

# Each controller misbehaves from t = 0.02 s on, after some steps: the run fails part-way.
CONTROLLERS = '''
import math

import numpy as np

LATE = 0.02


class Steady:
    batch = False

    def reset(self, context):
        pass

    def step(self, t, m):
        return self.late(t) if t >= LATE else (0.1, -0.1)


class HugeInteger(Steady):
    def late(self, t):
        return (10 ** 400, 0.0)


class Text(Steady):
    def late(self, t):
        return ("1.0", 0.0)


class ThreeValues(Steady):
    def late(self, t):
        return (0.0, 0.0, 0.0)


class NotANumber(Steady):
    def late(self, t):
        return (math.nan, 0.0)


class TextReference(Steady):
    def late(self, t):
        self.reference = "up"
        return (0.0, 0.0)


class HugeReference(Steady):
    def late(self, t):
        self.reference = (10 ** 400, 0.0)
        return (0.0, 0.0)


class FloodingMessage(Steady):
    def late(self, t):
        raise ValueError("first\\x00\\nsecond\\x1b[31m" + "y" * 1_000_000)


class BatchHugeInteger:
    batch = True

    def reset(self, context):
        pass

    def step(self, t, m):
        return [[10 ** 400, 0.0]] if t >= LATE else np.array([[0.1, -0.1]])


class BatchHugeReference(BatchHugeInteger):
    def step(self, t, m):
        if t >= LATE:
            self.reference = (10 ** 400, 0.0)
        return np.array([[0.1, -0.1]])
'''


def run(tmp_path, capsys, cls: str) -> tuple[int, str, dict]:
    (tmp_path / "culprits.py").write_text(CONTROLLERS)
    scene = tmp_path / "culprit.toml"
    scene.write_text(SCENE.format(cls=cls))
    out = tmp_path / "out"
    status = main(["run", str(scene), "--stop-time", "0.05", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    record = json.loads((out / "culprit_run.json").read_text()) if (out / "culprit_run.json").is_file() else {}
    return status, err, record


@pytest.mark.parametrize("cls, what", [
    ("HugeInteger", "beyond a float's range"),
    ("Text", "must be numbers"),
    ("ThreeValues", "(0.0, 0.0, 0.0)"),
    ("NotANumber", "must be finite"),
    ("TextReference", "self.reference to 'up'"),
    ("HugeReference", "self.reference to 1000"),
    ("BatchHugeInteger", "beyond a float's range"),
    ("BatchHugeReference", "self.reference (set by step() at t = 0.02 s) must be"),
])
def test_a_controller_value_that_is_no_voltage_or_angle_names_the_class_and_file(tmp_path, capsys, fmu_path,
                                                                                  cls, what):
    status, err, record = run(tmp_path, capsys, cls)
    lines = err.strip().splitlines()
    assert status == 3, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert f"{cls} (" in lines[0] and "culprits.py" in lines[0] and "t = 0.02" in lines[0], lines[0]
    assert what in lines[0], lines[0]
    assert "OverflowError" not in lines[0] and "could not convert" not in lines[0], lines[0]
    assert len(lines[0]) < 1000, len(lines[0])
    assert record.get("status") != "complete", record


def test_a_megabyte_exception_text_with_control_characters_is_one_escaped_excerpt(tmp_path, capsys, fmu_path):
    status, err, _ = run(tmp_path, capsys, "FloodingMessage")
    lines = err.strip().splitlines()
    assert status == 3 and len(lines) == 1, err[:2000]
    assert "FloodingMessage (" in lines[0] and "culprits.py:" in lines[0], lines[0]
    assert "first\\x00\\nsecond\\x1b[31m" in lines[0] and "\x1b" not in err and "\x00" not in err, lines[0]
    length = len("first\x00\nsecond\x1b[31m") + 1_000_000
    assert f"…({length} characters)" in lines[0] and len(lines[0]) < 1000, len(lines[0])


def test_an_excerpt_escapes_what_is_not_printable_and_cuts_with_the_length():
    assert excerpt("a\x00b\nc\td\x1b[2J\u202e") == "a\\x00b\\nc\\td\\x1b[2J\\u202e"
    assert excerpt("plain C:\\path, ünïcödé") == "plain C:\\path, ünïcödé"
    cut = excerpt("\n" * 1000)
    assert cut.startswith("\\n" * (EXCERPT_CHARS // 2)) and cut.endswith("…(1000 characters)")
    assert len(cut) <= EXCERPT_CHARS + len("…(1000 characters)")
    assert excerpt("x" * 10_000_000).endswith("…(10000000 characters)")


def test_shown_quotes_any_value_in_bounded_text():
    assert shown("a\nb") == "'a\\nb'"
    assert "bits" in shown(10 ** 5000)   # repr refuses an int of more than 4300 digits

    class Hostile:
        def __repr__(self):
            raise RuntimeError("no repr")

    assert shown(Hostile()) == "a Hostile object"


def test_one_line_is_the_last_defence_of_a_printed_message():
    message = "run failed:\n" + "\x1b[2K" + "z" * 5000
    line = one_line(message)
    assert "\n" not in line and "\x1b" not in line and line.startswith("run failed:\\n\\x1b[2K")
    assert line.endswith(f"…({len(message)} characters)") and len(line) <= LONGEST_MESSAGE_CHARS + 30
