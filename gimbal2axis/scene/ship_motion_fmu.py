"""A scene's [base_motion] as the parameters of the ship-motion FMU
(build/Gimbal2Axis-ShipMotion.fmu, docs/ship_motion_fmu.md), which makes the same sea state from them
with the same C kernel: its outputs are the scene runner's base inputs bit for bit. A recorded motion
is the FMU's motion = 1 with the file's path in its String parameter recording_file
(recording_parameters); sinusoids are not in that FMU."""
from __future__ import annotations

import math

from ..errors import SceneError, shown
from .base_motion import DEFAULT_GAMMA, SEA_STATE_DEFAULTS

DEGREES_OF_FREEDOM = ("pitch", "yaw", "roll", "surge", "sway", "heave")
ANGLES = ("pitch", "yaw", "roll")


def ship_motion_fmu_parameters(scene) -> dict:
    """{name: value} of the ship-motion FMU's parameters for `scene`'s [base_motion] (a sea state; a
    degree of freedom it does not name has amplitude 0)."""
    spec = scene.base_motion_spec or {}
    if spec.get("type") == "recorded":
        raise SceneError("a recorded [base_motion] is the ship-motion FMU's String parameter recording_file "
                         "(recording_parameters), not a set of numbers: this builds a sea state only")
    if spec.get("type") != "sea_state":
        raise SceneError(f"the ship-motion FMU makes a sea state: [base_motion] type = {shown(spec.get('type', 'fixed'))} "
                         "is not in it")
    scene.base_motion()   # the scene's own checks, with their messages
    components = spec.get("components", SEA_STATE_DEFAULTS["components"])
    values = {"seed": spec.get("seed", SEA_STATE_DEFAULTS["seed"])}
    for dof in DEGREES_OF_FREEDOM:
        item = spec.get(dof)
        values[f"{dof}.components"] = (item or {}).get("components", components)
        if item is None:
            values[f"{dof}.significant_amplitude"] = 0.0
            continue
        angle = dof in ANGLES
        amplitude = float(item["significant_amplitude_deg" if angle else "significant_amplitude_m"])
        values[f"{dof}.significant_amplitude"] = math.radians(amplitude) if angle else amplitude
        values[f"{dof}.peak_period"] = float(item["peak_period_s"])
        values[f"{dof}.gamma"] = float(item.get("gamma", DEFAULT_GAMMA))
    for i, v in enumerate(spec.get("velocity_m_s", [0.0, 0.0, 0.0]), start=1):
        values[f"velocity[{i}]"] = float(v)
    return values


def recording_parameters(scene) -> dict:
    """{name: value} of the ship-motion FMU's parameters for `scene`'s recorded [base_motion]: motion 1
    and the file's absolute path (recording_file, a String: set it with fmi2SetString)."""
    spec = scene.base_motion_spec or {}
    if spec.get("type") != "recorded":
        raise SceneError(f"[base_motion] type = {shown(spec.get('type', 'fixed'))} is not a recording")
    motion = scene.base_motion()   # the scene's own checks, with their messages
    return {"motion": 1, "recording_file": str(motion.path)}


TARGET_TABLE = "target_track.csv"   # the name the FMU's target_file starts with (ship_motion_variables.h)
TARGET_SAMPLE_S = 0.05              # the table's spacing, rounded to a whole number of communication steps
TARGET_COLUMNS = ("x", "y", "z", "x_dot", "y_dot", "z_dot", "x_ddot", "y_ddot", "z_ddot")


def target_table(scene, stop_time: float, step: float) -> bytes:
    """The ship-motion FMU's target table of `scene`'s moving target (its target = 1): the target's
    position relative to the gimbal in G with its rates and accelerations, as the scene runner
    computes them (gimbal2axis/target), at every multiple of the spacing from t = 0 until past the
    stop time (the FMU splines between the rows: the relative motion of a ship and a coastal point, an
    aircraft's straight line or a recorded track is smooth on that scale); numbers as Python's repr,
    so that the FMU reads the same doubles."""
    import numpy as np

    target = scene.moving_target
    if target is None:
        raise SceneError("the scene's [target] does not move: the ship-motion FMU has no target table to give")
    spacing = step * max(1, round(TARGET_SAMPLE_S / step))
    rows = max(4, int(np.ceil(stop_time / spacing)) + 2)
    times = np.arange(rows) * spacing
    from ..target.motion import Track
    for track in (getattr(target, "track", None), getattr(target.carrier, "track", None)):
        if isinstance(track, Track):
            track.check_covers("[target]", float(times[-1]))
    p, p_dot, p_ddot = target.relative(times, known=True)   # what the controller knows (its INS)
    columns = np.vstack([times, p, p_dot, p_ddot]).T
    lines = ["time," + ",".join(TARGET_COLUMNS)] + [",".join(repr(float(x)) for x in row) for row in columns]
    return ("\n".join(lines) + "\n").encode("ascii")
