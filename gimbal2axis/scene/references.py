"""Angle references (set points) per axis: constant, step, ramp, sine; angles in degrees in the
scene file, radians here. The reference 'target' (inverse kinematics of the line-of-sight target)
is handled by the controller, which knows the measured base attitude."""
from __future__ import annotations

import math

from ..errors import SceneError, check_keys, did_you_mean, number, positive, shown

KINDS = {
    "constant": {"value_deg"},
    "step": {"from_deg", "to_deg", "at_s"},
    "ramp": {"start_deg", "rate_deg_s", "start_s", "stop_s"},
    "sine": {"offset_deg", "amplitude_deg", "frequency_hz"},
}


class Reference:
    def __init__(self, where: str, spec: dict):
        kind = spec.get("type")
        if not isinstance(kind, str) or kind not in KINDS:
            known = sorted(KINDS) + ["target"]
            raise SceneError(f"[{where}] reference type must be one of {known}, got {shown(kind)}"
                             f"{did_you_mean(kind, known)}")
        check_keys(where, spec, KINDS[kind] | {"type"})
        self.kind = kind
        p = {key: number(f"{where}.{key}", value) for key, value in spec.items() if key != "type"}
        rad = math.radians
        if kind == "constant":
            value = rad(p.get("value_deg", 0.0))
            self.at = lambda t: value
        elif kind == "step":
            a, b, t_s = rad(p.get("from_deg", 0.0)), rad(p.get("to_deg", 0.0)), p.get("at_s", 0.0)
            self.at = lambda t: b if t >= t_s else a
        elif kind == "ramp":
            q0, rate = rad(p.get("start_deg", 0.0)), rad(p.get("rate_deg_s", 0.0))
            t0, t1 = p.get("start_s", 0.0), p.get("stop_s", math.inf)
            self.at = lambda t: q0 + rate * (min(max(t, t0), t1) - t0)
        else:
            q0, amp = rad(p.get("offset_deg", 0.0)), rad(p.get("amplitude_deg", 0.0))
            w = 2.0 * math.pi * positive(f"{where}.frequency_hz", spec.get("frequency_hz", 0.0))
            self.at = lambda t: q0 + amp * math.sin(w * t)
