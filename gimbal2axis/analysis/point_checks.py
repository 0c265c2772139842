"""Which points of a freqresp dwell are not a frequency response (fr.mark_rows): harmonics and drift
of every simulated point; with the linear prediction, the points of its fidelity against it, and in
open loop every point's operating point (the window's gimbal angles) against the prediction's."""
from __future__ import annotations

import math

from . import frequency_response as fr
from .dwell_plan import NO_BACKLASH


def check_points(rows: list[dict], scene, fmu_file, excitation, with_prediction: bool) -> None:
    """Writes every simulated row's marks (fr.mark_rows)."""
    if not with_prediction:
        fr.mark_rows(rows)
        return
    predicted = {(r["output"], r["frequency_hz"]): _complex_gain(r) for r in rows if r["curve"] == fr.LINEAR_CURVE}
    changes = operating_point_changes(rows, scene, fmu_file, excitation) if excitation.kind == "voltage" else {}
    fr.mark_rows(rows, lambda curve: curve.startswith(NO_BACKLASH),
                 lambda output, f: predicted.get((output, f)),
                 lambda row: changes.get((row["curve"], row["frequency_hz"], row["output"])))


def _complex_gain(row: dict) -> complex:
    """The row's gain and phase as one number (a gain without phase, the combined 'los': its gain)."""
    if math.isnan(row["phase_deg"]):
        return complex(row["gain"])
    phase = math.radians(row["phase_deg"])
    return row["gain"] * complex(math.cos(phase), math.sin(phase))


def operating_point_changes(rows: list[dict], scene, fmu_file, excitation) -> dict:
    """{(curve, frequency, output): (G of the linear model at the window's mean alpha and beta over G at the
    prediction's point, 'beta 5 -> -123 deg')} of every open-loop point: the prediction is made at the
    scene's initial angles, and on a fixed base gravity moves an unbalanced payload away from them while the
    dwell settles. Linearized without backlash and dry friction as the prediction (1 ms each)."""
    from ..fmu import FMU
    from . import linearization

    changes = {}
    with FMU(fmu_file) as fmu:
        start = fr.linear_point(scene, fmu, excitation, fr.LINEAR_FIDELITY)
        reference = linearization.linearize(start)
        for row in rows:
            if row["curve"] == fr.LINEAR_CURVE or row["output"] not in reference.outputs:
                continue
            moved = linearization.linearize(fr.linear_point(_moved_scene(scene, row), fmu, excitation,
                                                            fr.LINEAR_FIDELITY))
            f = [row["frequency_hz"]]
            G0 = complex(reference.frequency_response(f, excitation.input_signal, row["output"])[0])
            G = complex(moved.frequency_response(f, excitation.input_signal, row["output"])[0])
            if G0 != 0:
                changes[(row["curve"], row["frequency_hz"], row["output"])] = (
                    G / G0, f"beta {math.degrees(start['beta']):.3g} -> {row['beta_mean_deg']:.3g} deg")
    return changes


def _moved_scene(scene, row: dict):
    """The scene started at the row's window mean angles."""
    # within half a turn (a start angle beyond it is refused as degrees): the same configuration, as an
    # axis that walked round during the dwell (a torque-driven one, in current drive) left it
    alpha, beta = (math.remainder(math.radians(row[key]), 2 * math.pi) for key in ("alpha_mean_deg",
                                                                                  "beta_mean_deg"))
    # the rotors follow their loads there (start_values), not the angles the scene may give them
    initial = {k: v for k, v in scene.initial.items() if k not in ("alpha_m", "beta_m")}
    return scene.with_changes(initial={**initial, "alpha": alpha, "beta": beta})


def operating_point_hint(rows: list[dict]) -> str | None:
    """Why open-loop points left the prediction's operating point, when some did (the payload falls)."""
    moved = [r for r in rows if "operating point" in r.get("marks", "")]
    if not moved:
        return None
    first = moved[0]
    measured = [r for r in rows if "marks" in r]
    return (f"{len(moved)} of {len(measured)} points were measured away from the linear prediction's operating "
            f"point (e.g. {first['curve']}, {first['output']} at {first['frequency_hz']:.3g} Hz: "
            f"{next(m for m in first['marks'].split('; ') if m.startswith('operating point'))}): on the fixed base "
            f"and without a controller, gravity turns a payload whose centre of mass is off the elevation axis "
            f"while the dwell settles; balance it (--set \"body2.d_bd[2]=0\" --set \"body2.d_bd[3]=0\") to "
            f"measure the plant where it is linearized (docs/frequency_response.md)")


def checks_summary(rows: list[dict], with_prediction: bool) -> str:
    """The printed line: the marked points counted, or that every point is a frequency response."""
    return fr.marks_summary(rows) or (
        f"every point is a frequency response to {100 * fr.LINEARITY_TOLERANCE:g} % and "
        f"{fr.PHASE_TOLERANCE_DEG:g} deg (no harmonics, no drift"
        + (", on the linear prediction)" if with_prediction else ")"))
