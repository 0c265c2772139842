"""Recordings whose numbers are finite but whose splines are not (issue 44, items 8 and 11): a time or
a value near the largest double, values whose change or rate overflows over their time step, time
steps below the least one (subnormal). The C kernel's reader (c_kernel/src/recorded_motion_csv.c)
refuses each naming the line and the column, so the scene runner (scene/base_motion.Recorded), the
command and the ship-motion FMU (FMI 2.0 and 3.0, the recording and the target table) refuse it
with the file's name, instead of a NaN with status OK or an "out of memory"."""
import re
import signal

import pytest
from fmpy.fmi1 import FMICallException

from gimbal2axis.cli import main as cli_main
from gimbal2axis.errors import SceneError
from gimbal2axis.fmu import FMU
from gimbal2axis.scene.base_motion import Recorded
from test_ship_motion_fmu import RECORDED_SCENE
from test_small_fmus_fmi3 import Fmi3Twin

SHIP_MOTION_FMUS = {2: "Gimbal2Axis-ShipMotion.fmu", 3: "Gimbal2Axis-ShipMotion-fmi3.fmu"}

# {case: (the file, what its refusal names: the line (and data row), the column, why)}
HOSTILE = {
    "time_1e308": ("time,gamma\n0,0\n1,0.1\n2,0.2\n3,0.3\n1e308,0.4\n",
                   ["line 6 (data row 5)", "'time'", "1e+308", "1e+09 s"]),
    "value_1e308": ("time,x\n0,0\n1,0\n2,1e308\n3,0\n4,0\n", ["line 4 (data row 3)", "'x'", "1e+308", "overflow"]),
    "values_1e308_apart": ("time,x\n0,0\n1,-1e308\n2,1e308\n3,0\n4,0\n",
                           ["line 3 (data row 2)", "'x'", "-1e+308", "overflow"]),
    "rate_overflows": ("time,gamma\n0,0\n1e-9,1e300\n1,0\n2,0\n", ["line 3 (data row 2)", "'gamma'", "overflow"]),
    "subnormal_time_steps": ("time,gamma\n0,0\n5e-324,0.1\n1e-323,0.2\n1.5e-323,0.3\n1,0.4\n",
                             ["line 3 (data row 2)", "'time'", "4.94066e-324 s after", "below the least time step", "1e-09 s"]),
}


def refusal(content: str, tmp_path) -> tuple:
    """The file of `content` and the scene runner's refusal of it: its reason, after the file's name."""
    path = tmp_path / "motion.csv"
    path.write_text(content)
    with pytest.raises(SceneError) as refused:
        Recorded(path)
    message = str(refused.value)
    assert "\n" not in message, message
    return path, message.split(f"{path}: ", 1)[1]


@pytest.mark.parametrize("case", HOSTILE)
def test_the_scene_runner_refuses_the_recording_naming_line_and_column(case, tmp_path):
    content, named = HOSTILE[case]
    path, reason = refusal(content, tmp_path)
    for fragment in named:
        assert fragment in reason, (fragment, reason)
    assert "memory" not in reason


@pytest.fixture(scope="module")
def ship_motion_fmus(build_dir, tmp_path_factory):
    """{FMI version: the ship-motion FMU}."""
    fmi2 = FMU(build_dir / SHIP_MOTION_FMUS[2])
    yield {2: fmi2, 3: Fmi3Twin(build_dir / SHIP_MOTION_FMUS[3], tmp_path_factory.mktemp("ship_motion_fmi3"))}
    fmi2.close()


def last_message(log: list) -> str:
    entry = log[-1]
    return entry.text if hasattr(entry, "text") else entry[2]   # fmpy's FMI 2.0 entries, the adapter's tuples


def initialization_refusal(fmu, values: dict) -> str:
    """What the FMU logs when exitInitializationMode refuses `values` (the file parameters)."""
    log = []
    slave = fmu.instantiate(log=log)
    try:
        slave.setupExperiment(startTime=0.0)
        for name, value in values.items():
            setter = slave.setString if isinstance(value, str) else slave.setInteger
            setter([fmu.vr(name)], [value])
        slave.enterInitializationMode()
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        return last_message(log)
    finally:
        slave.freeInstance()


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", HOSTILE)
def test_the_ship_motion_fmu_refuses_the_recording_with_the_scene_runners_reason(ship_motion_fmus, version, case,
                                                                                   tmp_path):
    path, reason = refusal(HOSTILE[case][0], tmp_path)
    message = initialization_refusal(ship_motion_fmus[version], {"motion": 1, "recording_file": str(path)})
    assert message == f"fmi{version}ExitInitializationMode: recorded motion {path}: {reason}"


@pytest.mark.parametrize("version", [2, 3])
def test_the_ship_motion_fmu_refuses_a_target_table_whose_spline_overflows(ship_motion_fmus, version, tmp_path):
    path = tmp_path / "target.csv"
    path.write_text("time,x,y,z\n0,0,0,100\n1,0,1e308,100\n2,0,0,100\n3,0,0,100\n")
    message = initialization_refusal(ship_motion_fmus[version], {"target": 1, "target_file": str(path)})
    assert re.fullmatch(rf"fmi{version}ExitInitializationMode: target table {re.escape(str(path))}: "
                        r"line 3 \(data row 2\), column 'y'.*overflow.*", message), message


def test_the_run_command_refuses_subnormal_time_steps_in_one_line_saying_what_failed(tmp_path, capsys):
    content, named = HOSTILE["subnormal_time_steps"]
    (tmp_path / "motion.csv").write_text(content)
    scene = tmp_path / "scene.toml"
    scene.write_text(RECORDED_SCENE.format(stop_time=0.5, step=0.01))
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        status = cli_main.main(["run", str(scene), "--out", str(tmp_path / "out")])
    finally:   # the command installs its own handlers; pytest's are put back
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert status == 2 and len(lines) == 1, captured.err
    assert lines[0].startswith("gimbal2axis run: error: ") and str(tmp_path / "motion.csv") in lines[0], lines[0]
    for fragment in named:
        assert fragment in lines[0], (fragment, lines[0])


@pytest.mark.parametrize("version", [2, 3])
def test_the_ship_motion_fmu_refuses_a_recording_that_ends_before_t_0(ship_motion_fmus, version, tmp_path):
    # Without a stop time, row 0 (t = 0) would be the last cubic extrapolated 5 s past the end.
    path = tmp_path / "early.csv"
    path.write_text("time,gamma\n-10,0\n-9,1e150\n-8,0\n-5,0\n")
    message = initialization_refusal(ship_motion_fmus[version], {"motion": 1, "recording_file": str(path)})
    assert message == (f"fmi{version}ExitInitializationMode: recorded motion {path} covers [-10, -5] s, not t = 0, "
                       "where the outputs start")
