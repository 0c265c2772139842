"""A moving target through the system of three FMUs (gimbal2axis/system/): the ship-motion FMU gives
the target's position from the gimbal out of the table `gimbal2axis system` puts in its resources,
the controller FMU points at it by the C kernel's pointing command with the feed-forward of its
rates and accelerations, and libcosim runs the system as the scene runner runs the scene (the
coastal point, the recorded boat, and the flyby through the keyhole). Also: the ship-motion FMU's
target outputs against the scene's target, and the refusals of a target table and of a target that
gives no direction."""
import pathlib
import zipfile

import fmpy
from fmpy.fmi1 import FMICallException
import numpy as np
import pytest

from gimbal2axis import load_scene, run
from gimbal2axis.scene.ship_motion_fmu import TARGET_TABLE, target_table
from gimbal2axis.system.engines import run_fmpy_ssp, run_libcosim
from gimbal2axis.system.from_scene import CONTROLLER, GIMBAL as GIMBAL_UNIT, SHIP, ship_system
from gimbal2axis.system.osp import write_osp
from gimbal2axis.system.ssp import write_ssp

pytest.importorskip("libcosimpy")
REPO = pathlib.Path(__file__).resolve().parents[3]
STOP = 2.0
GIMBAL = ["alpha", "beta", "u_R1", "u_R2"]
TARGET_OUTPUTS = [f"target.{q}[{i}]" for q in ("position", "velocity", "acceleration") for i in (1, 2, 3)]


def flyby_through_the_keyhole(tmp_path):
    """The keyhole flyby with its closest approach at 1.2 s: within the run, the command's azimuth
    rate reaches 12 rad/s."""
    text = (REPO / "scenes" / "track_flyby_keyhole.toml").read_text()
    assert "closest_approach_s = 15.0" in text
    path = tmp_path / "flyby_soon.toml"
    path.write_text(text.replace("closest_approach_s = 15.0", "closest_approach_s = 1.2"))
    return load_scene(path)


@pytest.fixture(params=["track_coastal_point", "track_recorded_boat", "flyby"])
def scene(request, tmp_path):
    if request.param == "flyby":
        return flyby_through_the_keyhole(tmp_path)
    return load_scene(REPO / "scenes" / f"{request.param}.toml")


def test_libcosim_runs_a_moving_target_as_the_scene_runner(scene, build_dir, gimbal_fmu, tmp_path):
    system = ship_system(scene, build_dir, stop_time=STOP)
    ship = system.component(SHIP)
    assert ship.start_values["target"] == 1 and TARGET_TABLE in ship.resources
    assert system.component(CONTROLLER).start_values["target.moving"] is True
    structure = write_osp(system, tmp_path / "osp")
    assert TARGET_TABLE and f"resources/{TARGET_TABLE}" in zipfile.ZipFile(structure.parent / ship.fmu.name).namelist()
    steps = int(round(STOP / scene.step_size))
    got = run_libcosim(structure, GIMBAL_UNIT, GIMBAL, steps)
    reference = {name: values[1:] for name, values in run(scene, gimbal_fmu, stop_time=STOP).signals.items()}
    # The same loop: the controller FMU's pointing command is the scene runner's in C (1e-12 apart at
    # most, tests/c_kernel/test_pointing_kernel.py) from the table's splines of the target's position (exact
    # for the flyby's straight line, within 1e-8 m for the others between the rows)
    for name in ("alpha", "beta"):
        assert np.max(np.abs(got[name] - reference[name])) < 1e-10, name   # measured: 1e-11 at most
    assert got["u_R1"][0] == 0.0 and np.max(np.abs(got["u_R1"][1:] - reference["u_R1"][:-1])) < 1e-6
    assert np.max(np.abs(got["u_R2"][1:] - reference["u_R2"][:-1])) < 1e-6
    assert np.ptp(reference["alpha"]) > 1e-3   # the gimbal turns after its target


def test_fmpy_runs_the_flyby_ssp_archive_through_the_keyhole(build_dir, gimbal_fmu, tmp_path):
    scene = flyby_through_the_keyhole(tmp_path)
    archive = write_ssp(ship_system(scene, build_dir, stop_time=STOP), tmp_path / "flyby.ssp")
    got = run_fmpy_ssp(archive, GIMBAL_UNIT, GIMBAL, scene.step_size, STOP)
    reference = run(scene, gimbal_fmu, stop_time=STOP).signals
    steps = len(reference["alpha"]) - 1
    # FMPy starts the connections at 0 (docs/systems.md): the first step's kick, then the same track
    window = np.arange(1, steps + 1) * scene.step_size >= 1.0
    error = np.abs(np.angle(np.exp(1j * (got["alpha"][:steps] - reference["alpha"][1:]))))
    assert error[window].max() < 1e-3
    assert np.ptp(reference["alpha"][1:][window]) > 1.0   # through the keyhole: the azimuth swings


def ship_outputs(fmu_path, table: bytes, tmp_path, step, steps, target=1):
    """The ship-motion FMU's target outputs at t_0 .. t_steps with `table` as its target file."""
    path = tmp_path / TARGET_TABLE
    path.write_bytes(table)
    result = fmpy.simulate_fmu(str(fmu_path), start_values={"target": target, "target_file": str(path)},
                               output=TARGET_OUTPUTS, step_size=step, output_interval=step, stop_time=steps * step)
    return result


def test_the_ship_fmus_target_outputs_are_the_scenes_target(build_dir, tmp_path):
    scene = load_scene(REPO / "scenes" / "track_coastal_point.toml")
    step = scene.step_size
    result = ship_outputs(build_dir / "Gimbal2Axis-ShipMotion.fmu", target_table(scene, 1.0, step), tmp_path, step,
                          1000)
    p, p_dot, p_ddot = scene.moving_target.relative(result["time"])
    # Between the table's rows the splines of a smooth motion; the scene's own rates are central
    # differences of pymap3d's positions over 0.05 s, whose rounding (1e-9 to 1e-8 m on kilometres)
    # leaves up to 1e-7 m/s and 1e-5 m/s2 of noise in them: the tolerances (on the pointing, below
    # 1e-11 rad/s and 1e-8 rad/s2). The gimbal's heave and its lever arm turned by the roll are in the
    # table too (issue 45): their splines between the rows leave 2e-7 m and 2e-6 m/s (4e-11 rad and 4e-10
    # rad/s at these ranges).
    for quantity, want, tolerance in (("position", p, 5e-7), ("velocity", p_dot, 2e-6), ("acceleration", p_ddot, 2e-5)):
        for i in range(3):
            got = result[f"target.{quantity}[{i + 1}]"]
            assert np.max(np.abs(got - want[i])) < tolerance, (quantity, i, np.max(np.abs(got - want[i])))
    assert np.max(np.abs(p[0])) > 100.0   # a target kilometres away, not zeros


@pytest.mark.parametrize("table, message", [
    (b"time,x,y\n0,1,2\n1,1,2\n2,1,2\n3,1,2\n", "no column 'z'"),
    (b"time,x,y,z,w\n0,1,2,3,4\n1,1,2,3,4\n2,1,2,3,4\n3,1,2,3,4\n", "unknown column 'w'"),
    (b"time,x,y,z\n0,1,2,3\n1,1,2,3\n", "4"),
    (b"time,x,y,z\n0.5,1,2,3\n1,1,2,3\n2,1,2,3\n3,1,2,3\n", "covers [0.5, 3] s"),
    (b"time,x,y,z\n0,1,2,3\n0.1,1,2,3\n0.2,1,2,3\n0.3,1,2,3\n", "covers [0, 0.3] s, not [0, 1] s"),
])
def test_a_bad_target_table_is_refused_naming_what(build_dir, tmp_path, table, message):
    # (the project's FMU wrapper collects the log: fmpy's own logger proxy keeps one target per process)
    from gimbal2axis.fmu import FMU
    path = tmp_path / "bad.csv"
    path.write_bytes(table)
    fmu = FMU(build_dir / "Gimbal2Axis-ShipMotion.fmu")
    log = []
    ship = fmu.instantiate("ship", log)
    try:
        ship.setupExperiment(startTime=0.0, stopTime=1.0)
        ship.setInteger([fmu.vr("target")], [1])
        ship.setString([fmu.vr("target_file")], [str(path)])
        ship.enterInitializationMode()
        with pytest.raises(FMICallException):
            ship.exitInitializationMode()
    finally:
        ship.freeInstance()
        fmu.close()
    text = " ".join(str(entry) for entry in log)
    assert "fmi2ExitInitializationMode" in text and message in text, text


def test_a_target_with_no_direction_holds_the_angles_with_a_warning_naming_its_inputs(build_dir):
    """A master that starts its connections at 0 (FMPy's SSP runner) gives the controller a target at
    the gimbal in its first step: that step holds the measured angles and says why (fmi2Warning); a
    target exactly on the azimuth axis likewise. Then the track goes on as the inputs say."""
    from gimbal2axis.fmu import FMU
    fmu = FMU(build_dir / "Gimbal2Axis-Controller.fmu")
    log = []
    controller = fmu.instantiate("controller", log, logging_on=True)
    positions = [(0.0, 0.0, 0.0), (0.0, 0.0, 300.0), (-1000.0 * np.sin(0.25), 1000.0 * np.cos(0.25), 100.0)]
    set_points = []
    try:
        controller.setDebugLogging(True, ["logStatusWarning"])
        controller.setupExperiment(startTime=0.0)
        fmu.set_values(controller, {"target.moving": True, "alpha": 0.25, "beta": 0.1, "azimuth.kp": 100.0})
        controller.enterInitializationMode()
        controller.exitInitializationMode()
        for k, position in enumerate(positions):
            controller.setReal([fmu.vr(f"target.position[{i}]") for i in (1, 2, 3)], list(position))
            controller.doStep(k * 1e-3, 1e-3)
            set_points.append(fmu.get_values(controller, ["set_point.alpha", "set_point.beta"]))
    finally:
        controller.freeInstance()
        fmu.close()
    warnings = [entry for entry in log if entry.status == 1]
    assert len(warnings) == 2, log
    assert "fmi2DoStep: at t = 0 s: target.position = (0, 0, 0) m is the gimbal's own place" in str(warnings[0])
    assert "target.position = (0, 0, 300) m lies exactly on the azimuth axis" in str(warnings[1])
    # the steps' set points: held at the measured angles twice, then toward the target
    assert set_points[0] == [0.25, 0.1] and set_points[1] == [0.25, 0.1]
    assert set_points[2] == pytest.approx([0.25, np.arctan2(100.0, 1000.0)], abs=1e-12)


def test_the_controller_tracks_alike_in_fmi_2_and_fmi_3_and_refuses_a_nan_target(build_dir, tmp_path):
    """The controller FMU's two versions through the same inputs toward an aircraft passing 10 m
    beside the zenith: the same voltages bit for bit, the keyhole's command in them; a NaN in a
    target input refused in both, naming it."""
    from gimbal2axis.fmu import FMU
    from test_controller_fmu import start_controller
    from test_small_fmus_fmi3 import Fmi3Twin
    scene = flyby_through_the_keyhole(tmp_path)
    times = np.arange(400) * 5e-3
    p, p_dot, p_ddot = scene.moving_target.relative(times)
    parameters = {"target.moving": True, "azimuth.kp": 400.0, "azimuth.k_ff": 4.8, "azimuth.k_acc": 0.18,
                  "elevation.kp": 400.0, "elevation.k_acc": 0.16}
    voltages = {}
    for version, fmu in (("2.0", FMU(build_dir / "Gimbal2Axis-Controller.fmu")),
                         ("3.0", Fmi3Twin(build_dir / "Gimbal2Axis-Controller-fmi3.fmu", tmp_path / "fmi3"))):
        log = []
        slave = start_controller(fmu, parameters, log)
        names = TARGET_OUTPUTS
        rows = []
        for k, t in enumerate(times):
            values = np.concatenate([p[:, k], p_dot[:, k], p_ddot[:, k]])
            slave.setReal([fmu.vr(name) for name in names], list(values))
            slave.doStep(t, 5e-3)
            rows.append(slave.getReal([fmu.vr("u_R1"), fmu.vr("u_R2"), fmu.vr("set_point.alpha")]))
        with pytest.raises(FMICallException):
            slave.setReal([fmu.vr("target.position[2]")], [float("nan")])
        assert any("target.position[2] = nan is not finite" in str(entry) for entry in log), log
        slave.freeInstance()
        voltages[version] = np.array(rows)
    assert np.array_equal(voltages["2.0"], voltages["3.0"])
    # the command's azimuth swings through the keyhole (the gimbal at rest: the kp term saturates)
    assert np.ptp(voltages["2.0"][:, 2]) > 2.0 and np.max(np.abs(voltages["2.0"][:, 0])) == pytest.approx(24.0)
