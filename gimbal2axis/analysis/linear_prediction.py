"""The linear prediction a freqresp dwell is drawn against, without backlash and dry friction: in open
loop the plant's G(jw) from the core's A, B, C, D (linearization.py); for isolation and loop gain the
sampled-data closed loop of the scene's PID controller (isolation_prediction.py), the loop gain with
its predicted margins."""
from __future__ import annotations

from . import frequency_response as fr


def linear_prediction(scene, fmu_path, excitation, outputs, f_min, f_max):
    """(the linear model's Bode lines, a function giving its rows at the simulated points, a line of text
    to print or None)."""
    from ..fmu import FMU

    with FMU(fmu_path) as fmu:
        if excitation.kind == "voltage":
            return _open_loop(scene, fmu, excitation, outputs, f_min, f_max)
        from . import isolation_prediction as isolation

        loop = isolation.build_loop(scene, fmu, fr.LINEAR_FIDELITY)
    if excitation.kind == "injection":
        margins = isolation.predicted_margins(loop, excitation.axis)
        summary = (f"linear model, loop gain at {fr.command_signal(excitation.axis, excitation.drive)}: "
                   f"{margins.describe()}")
        return (isolation.loop_gain_lines(loop, excitation.axis, f_min, f_max),
                _at_simulated(isolation.loop_gain_rows, loop, excitation.axis), summary)
    return (isolation.isolation_lines(loop, excitation.axis, f_min, f_max),
            _at_simulated(isolation.isolation_rows, loop, excitation.axis), None)


def _open_loop(scene, fmu, excitation, outputs, f_min, f_max):
    from . import linearization

    model = linearization.linearize(fr.linear_point(scene, fmu, excitation, fr.LINEAR_FIDELITY))
    lines = fr.linear_lines(model, excitation.input_signal, outputs, f_min, f_max)
    return lines, lambda rows: fr.linear_rows(model, rows), None


def _at_simulated(function, loop, axis):
    """The closed loop's rows at the simulated rows' frequencies."""
    return lambda rows: function(loop, axis, sorted({r["frequency_hz"] for r in rows}))
