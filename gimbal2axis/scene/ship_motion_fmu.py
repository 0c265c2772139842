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
