"""The ship-motion FMU's grid rule (issue 45, item 5) under a master that keeps time as OMSimulator
does: it sums t += h (passing the step fl(t + h) - t) and ends on its stop time with min(t + h, stop).
Its last step is then h short by all the sum's drift (0.00099999999854105681 s at 20 s of 1 ms
steps), or, where the sum fell short of the stop time by more than a millionth of h (every stop time
from 335 s on), a step of the drift's size. The FMU takes a step as its grid's when it ends where a
step of h would or on the grid's next point, and as the clock's rounding (no row) when it ends on
the grid's current point, to the communication-point tolerance the gimbal uses
(fmu_src/common/communication_point.h: communication_grid_rows), in FMI 2.0 and 3.0. The old rule
(|step - h| <= 1e-9 h, or a step below 1e-6 h) refused the last step at 1102 of the stop times 1 ..
1200 s.

The master's points are computed here; the FMU runs the master's steps from t = 0 (its grid is the
run's from its start), one run for FMI 3.0 that takes each stop time's last step from an FMU state
and goes back, one run per stop time of the issue for FMI 2.0 (which has no FMU states). One
component per degree of freedom: a step costs a microsecond."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from gimbal2axis.fmu import FMU
from test_communication_points import FMI2Stepper, FMI3Stepper

H = 1e-3
STOP_TIMES = [float(s) for s in range(1, 1201)]
ISSUE_STOP_TIMES = [20.0, 30.0, 100.0, 1200.0]
DOFS = ("pitch", "yaw", "roll", "surge", "sway", "heave")


def summed_points(h: float, until: float) -> np.ndarray:
    """The master's points t_0 = 0, t_{k+1} = t_k + h (sequential sums, as the master adds) until the
    first at or past `until`."""
    count = int(until / h) + 3
    return np.concatenate([[0.0], np.add.accumulate(np.full(count, h))])


def last_point_before(points: np.ndarray, stop: float) -> int:
    """The index m of the master's last point below the stop time: its last step is stop - t_m."""
    return int(np.searchsorted(points, stop, "left")) - 1


def old_rule_refuses(step: float, h: float) -> bool:
    return not (abs(step - h) <= 1e-9 * h or step < 1e-6 * h)


class ShipMotion:
    """The ship-motion FMU (FMI 2.0 or 3.0), one instance restarted by reset: raw doSteps
    (test_communication_points' steppers), its outputs, its log."""

    def __init__(self, version: int, build_dir, workdir):
        self.version, self.log = version, []
        if version == 2:
            fmu = FMU(build_dir / "Gimbal2Axis-ShipMotion.fmu")
            self.slave = fmu.instantiate("clock", self.log)
            self.stepper = FMI2Stepper(fmu, self.slave, self.log)
            self.vr, variables = fmu.vr, fmu.model_description.modelVariables
        else:
            path = build_dir / "Gimbal2Axis-ShipMotion-fmi3.fmu"
            md = read_model_description(str(path))
            self.slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(str(path), str(workdir)),
                                   modelIdentifier=md.coSimulation.modelIdentifier, instanceName="clock")
            self.slave.instantiate(logMessage=lambda env, status, category, message: self.log.append(message.decode()),
                                   loggingOn=True)
            self.stepper = FMI3Stepper(md, self.slave, self.log)
            self.vr, variables = self.stepper.vr, md.modelVariables
        self.output_vrs = [v.valueReference for v in variables if v.causality == "output"]
        self.components = [self.vr(f"{dof}.components") for dof in DOFS]

    def start(self) -> None:
        self.slave.reset()
        if self.version == 2:
            self.slave.setupExperiment(startTime=0.0)
            self.slave.setInteger(self.components, [1] * len(DOFS))
            self.slave.enterInitializationMode()
        else:
            self.slave.enterInitializationMode(startTime=0.0)
            self.slave.setInt32(self.components, [1] * len(DOFS))
        self.slave.exitInitializationMode()

    def step(self, point: float, step: float) -> None:
        status = self.stepper.step(point, step)
        assert status <= 1, f"doStep({point!r}, {step!r}) refused: {self.last_message()}"

    def run(self, points: np.ndarray, first: int, last: int) -> None:
        """The master's steps from points[first] to points[last]."""
        steps = np.diff(points[first:last + 1])
        for point, step in zip(points[first:last].tolist(), steps.tolist()):
            self.step(point, step)

    def last_message(self) -> str:
        entry = self.log[-1]
        return entry if isinstance(entry, str) else entry.text   # the adapter's text, fmpy's FMI 2.0 entries

    def outputs(self) -> np.ndarray:
        return np.array((self.slave.getReal if self.version == 2 else self.slave.getFloat64)(self.output_vrs))

    def close(self):
        self.slave.freeInstance()


@pytest.fixture(scope="module")
def points():
    return summed_points(H, max(STOP_TIMES))


def test_the_old_rule_refused_the_last_step_at_the_issues_stop_times(points):
    refused = [stop for stop in STOP_TIMES
               if old_rule_refuses(stop - points[last_point_before(points, stop)], H)]
    assert set(ISSUE_STOP_TIMES) <= set(refused) and len(refused) == 1102, len(refused)
    # both kinds of last step: h short by the drift (the sum reached the stop time), and the drift itself
    short = [stop - points[last_point_before(points, stop)] for stop in refused]
    assert min(short) < 1e-3 * H and max(short) > 0.999 * H


@pytest.fixture(scope="module")
def ship3(build_dir, tmp_path_factory):
    instance = ShipMotion(3, build_dir, tmp_path_factory.mktemp("ship_clock"))
    yield instance
    instance.close()


def test_fmi3_takes_the_last_step_to_every_stop_time_from_1_to_1200_s_on_the_grids_row(ship3, points):
    """One run of the master's sum; at each stop time's last point below it, its last step from an
    FMU state, whose outputs must be the grid's row at the stop time (the run's own row there)."""
    ship3.start()
    last_points = {last_point_before(points, stop): stop for stop in STOP_TIMES}
    rows = {round(stop / H): stop for stop in STOP_TIMES}
    ended, expected = {}, {}
    done = 0
    for m in sorted(set(last_points) | set(rows)):
        ship3.run(points, done, m)
        done = m
        if m in rows:
            expected[rows[m]] = ship3.outputs()
        if m in last_points:
            stop = last_points[m]
            state = ship3.slave.getFMUState()
            ship3.step(float(points[m]), stop - float(points[m]))
            assert ship3.stepper.last_successful_time() == stop
            ended[stop] = ship3.outputs()
            ship3.slave.setFMUState(state)
            ship3.slave.freeFMUState(state)
    assert sorted(ended) == STOP_TIMES
    for stop in STOP_TIMES:
        np.testing.assert_array_equal(ended[stop], expected[stop], err_msg=f"stop time {stop} s")


@pytest.fixture(scope="module")
def ship2(build_dir, tmp_path_factory):
    instance = ShipMotion(2, build_dir, tmp_path_factory.mktemp("ship_clock"))
    yield instance
    instance.close()


@pytest.mark.parametrize("stop", ISSUE_STOP_TIMES)
def test_fmi2_takes_the_last_step_to_the_issues_stop_times(ship2, points, stop):
    m = last_point_before(points, stop)
    ship2.start()
    ship2.run(points, 0, m)
    ship2.step(float(points[m]), stop - float(points[m]))
    assert ship2.stepper.last_successful_time() == stop


@pytest.mark.parametrize("version", [2, 3])
def test_a_step_of_another_size_off_the_grid_is_still_refused(ship2, ship3, version):
    ship = ship2 if version == 2 else ship3
    ship.start()
    ship.step(0.0, H)
    assert ship.stepper.step(H, 0.5 * H) >= 3
    assert "differs from the first step's 0.001, and the step's end 0.0015 is not a point of the grid" in ship.last_message()
