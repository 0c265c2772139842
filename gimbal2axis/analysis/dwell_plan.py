"""What a freqresp sine dwell runs: the excitations of one mode (open loop, isolation, loop gain) on
one axis with their amplitudes, the scene as each mode runs it, the simulated variants (the scene's
model and the one without backlash and dry friction) and the names of their curves and plot."""
from __future__ import annotations

import dataclasses
import math

from ..errors import SceneError, shown
from . import frequency_response as fr

FULL_MODEL = "full model"
NO_BACKLASH = "no backlash, no dry friction"   # the curve of the linear prediction's fidelity (with ", <amplitude>")


@dataclasses.dataclass(frozen=True)
class Mode:
    kind: str                  # the Excitation's kind
    default_axis: str
    axes: tuple                # the axes it takes
    axis_refusal: str          # after "--axis X: "
    default_amplitude: float   # in the unit of --amplitude


MODES = {
    "open-loop": Mode("voltage", "1", fr.MOTOR_AXES, "open-loop drives motor 1 or 2", 1.0),
    "loop-gain": Mode("injection", "1", fr.MOTOR_AXES, "loop-gain injects at motor 1 or 2", 0.2),
    "isolation": Mode("base", "roll", tuple(fr.BASE_AXES), "isolation moves the carrier in roll, pitch or yaw", 1.0),
}


def unit_of(mode: str, drive: str = "voltage") -> str:
    """The unit of --amplitude: a motor's current command's in current drive."""
    return "deg/s" if mode == "isolation" else ("V" if drive == "voltage" else "A")


@dataclasses.dataclass(frozen=True)
class DwellPlan:
    mode: str
    scene: object              # the scene as the mode runs it (open loop: fixed base, no controller)
    axis: str
    amplitudes: list
    excitations: list          # one per amplitude
    outputs: list | None       # None: each excitation's default outputs

    @property
    def excitation(self):
        """The first excitation: what the prediction, the checks and the plot are made for."""
        return self.excitations[0]

    @property
    def unit(self) -> str:
        return unit_of(self.mode, self.excitation.drive)


def check_fixed_target(scene, mode: str) -> None:
    """A closed loop is measured about one operating point: a moving target would move it."""
    if mode != "open-loop" and scene.moving_target is not None:
        raise SceneError(f"{scene.name}: its [target] moves (type = \"{scene.target_spec.get('type', '?')}\"), and "
                         f"freqresp {mode} measures the closed loop about one operating point: give the scene a "
                         f"fixed [target] (type = \"direction\") or no target")


def plan_dwell(mode: str, scene, axis: str | None, amplitudes: list | None, offset: float, drive: str) -> DwellPlan:
    """The plan of `mode` on `axis` (None: the mode's default); refuses an axis the mode does not take."""
    spec = MODES[mode]
    axis = axis or spec.default_axis
    if axis not in spec.axes:
        raise SceneError(f"--axis {shown(axis)}: {spec.axis_refusal}")
    amplitudes = amplitudes or [spec.default_amplitude]
    outputs = None
    if spec.kind == "voltage":
        excitations = [fr.Excitation("voltage", axis, a, offset, drive) for a in amplitudes]
        scene = scene.with_changes(base_motion_spec={"type": "fixed"},
                                   fidelity={**scene.fidelity, "base.fixed": True},
                                   controller_spec={"type": "none"})
        outputs = excitations[0].default_outputs()
    elif spec.kind == "injection":
        excitations = [fr.Excitation("injection", axis, a, drive=drive) for a in amplitudes]
    else:
        excitations = [fr.Excitation("base", axis, math.radians(a)) for a in amplitudes]
    return DwellPlan(mode, scene, axis, amplitudes, excitations, outputs)


def variants(linear_only: bool, full_only: bool) -> list:
    """[(curve label, fidelity over the scene's or None)] of the simulated models."""
    chosen = []
    if not linear_only:
        chosen.append((FULL_MODEL, None))
    if not full_only:
        chosen.append((NO_BACKLASH, fr.LINEAR_FIDELITY))
    return chosen


def curve_name(plan: DwellPlan, label: str, amplitude: float) -> str:
    """The variant's label, with the amplitude when there are several."""
    return label if len(plan.amplitudes) == 1 else f"{label}, {amplitude:g} {plan.unit}"


def measure_curves(plan: DwellPlan, fmu, frequencies, dwell, chosen_variants: list, client=None) -> list:
    """Every point of every simulated curve (fr.sweep of each excitation and variant)."""
    rows = []
    for excitation, amplitude in zip(plan.excitations, plan.amplitudes):
        for label, fidelity in chosen_variants:
            rows += fr.sweep(plan.scene, fmu, frequencies, excitation, dwell, plan.outputs, fidelity, client,
                             curve_name(plan, label, amplitude))
    return rows


def plot_title(plan: DwellPlan, scene_name: str) -> str:
    excitation = plan.excitation
    amplitudes_text = ", ".join(f"{a:g}" for a in plan.amplitudes)
    if excitation.kind == "injection":
        return (f"{scene_name}: loop gain L = -U/A at {fr.command_signal(plan.axis, excitation.drive)} (other axis "
                f"closed) and sensitivity A/D, injection {amplitudes_text} V")
    return (f"{scene_name}: {excitation.input_signal} -> rates, amplitude{'s' if len(plan.amplitudes) > 1 else ''} "
            f"{amplitudes_text} {plan.unit}" + (" (LOS rate / carrier rate)" if excitation.kind == "base" else ""))


def plotted(plan: DwellPlan, rows: list, lines: list | None) -> tuple:
    """(rows, lines) the Bode plot draws: for a loop gain only L and S, as the LOS rate per D (-90 dB)
    would squeeze them (it is in the CSV)."""
    if plan.excitation.kind != "injection":
        return rows, lines
    shown_outputs = (fr.LOOP_GAIN, fr.SENSITIVITY)
    return ([r for r in rows if r["output"] in shown_outputs],
            lines and [line for line in lines if line[0].rsplit(": ", 1)[-1] in shown_outputs])
