"""Tracking metrics of a run with a moving target, accumulated chunk by chunk (a run held in memory
is one chunk): the time on target (line-of-sight error within half the beam width), the time near
the keyhole (the pointing command within keyhole_deg of the azimuth axis, |beta_cmd| > 90 deg -
keyhole_deg) and the part of it off target, and there the largest azimuth rate and acceleration the
pointing command asked, the voltage the controller asked of motor 1 (before the clamp to +-U_L; with
motor1.drive = current the current command it asked, before the clamp to +-i_L), the
rate the azimuth achieved and the current motor 1 drew. The RMS and maximum of the pointing error
are the summary line's line-of-sight figures."""
from __future__ import annotations

import math

import numpy as np

# the signals the metrics read (recorded: alpha_dot, i_R1, u_R1_asked or in current drive i_R1_asked;
# derived: the rest)
NEEDED = ("time", "los_error", "beta_cmd", "alpha_cmd_dot", "alpha_cmd_ddot", "alpha_dot", "i_R1", "u_R1_asked",
          "i_R1_asked")


KEYHOLE_ORDER = ("asked_rate", "asked_acceleration", "asked_voltage", "asked_current", "achieved_rate", "current")


class TrackingMetrics:
    def __init__(self, beam_width_mrad: float, keyhole_deg: float, step_size: float, window_start: float = 0.0):
        self.half_beam = beam_width_mrad * 1e-3 / 2.0
        self.keyhole_beta = math.radians(90.0 - keyhole_deg)
        self.keyhole_deg, self.beam_width_mrad = keyhole_deg, beam_width_mrad
        self.h, self.window_start = step_size, window_start
        self.samples = self.on_target = self.near_keyhole = self.lost_near_keyhole = 0
        # asked_voltage of a motor 1 in voltage drive, asked_current (its current command) in current drive
        self.keyhole_max = {"asked_rate": 0.0, "asked_acceleration": 0.0, "achieved_rate": 0.0, "current": 0.0}
        self.asked_rate_max = 0.0

    def add(self, columns: dict) -> None:
        window = columns["time"] >= self.window_start - 1e-12
        error = columns["los_error"][window]
        on = error <= self.half_beam
        near = np.abs(columns["beta_cmd"][window]) > self.keyhole_beta
        self.samples += int(window.sum())
        self.on_target += int(on.sum())
        self.near_keyhole += int(near.sum())
        self.lost_near_keyhole += int((near & ~on).sum())
        asked = np.abs(columns["alpha_cmd_dot"][window])
        if asked.size:
            self.asked_rate_max = max(self.asked_rate_max, float(np.max(asked)))
        self.keyhole_max.setdefault("asked_current" if "i_R1_asked" in columns else "asked_voltage", 0.0)
        if near.any():
            for key, name in (("asked_rate", "alpha_cmd_dot"), ("asked_acceleration", "alpha_cmd_ddot"),
                              ("asked_voltage", "u_R1_asked"), ("asked_current", "i_R1_asked"),
                              ("achieved_rate", "alpha_dot"), ("current", "i_R1")):
                if name in columns:
                    self.keyhole_max[key] = max(self.keyhole_max[key],
                                                float(np.max(np.abs(columns[name][window][near]))))

    def as_dict(self) -> dict:
        """The figures, SI units (s, rad/s, rad/s2, V, A) and a fraction."""
        return {"time_on_target_s": self.on_target * self.h,
                "on_target_fraction": self.on_target / self.samples if self.samples else math.nan,
                "time_near_keyhole_s": self.near_keyhole * self.h,
                "time_lost_near_keyhole_s": self.lost_near_keyhole * self.h,
                "time_lost_s": (self.samples - self.on_target) * self.h,
                "asked_azimuth_rate_max": self.asked_rate_max,
                **{f"keyhole_{key}_max": self.keyhole_max[key] for key in KEYHOLE_ORDER if key in self.keyhole_max}}

    def summary(self) -> str:
        m = self.as_dict()
        text = (f"on target (beam {self.beam_width_mrad:g} mrad) {100 * m['on_target_fraction']:.1f} % of the time, "
                f"{m['time_lost_s']:.3g} s off; azimuth rate asked up to {math.degrees(m['asked_azimuth_rate_max']):.4g} "
                "deg/s")
        if self.near_keyhole:
            k = self.keyhole_max
            text += (f"; near the keyhole (within {self.keyhole_deg:g} deg of the zenith) {m['time_near_keyhole_s']:.3g} s, "
                     f"{m['time_lost_near_keyhole_s']:.3g} s of it off target; there the azimuth asked up to "
                     f"{math.degrees(k['asked_rate']):.4g} deg/s and {math.degrees(k['asked_acceleration']):.4g} deg/s2, "
                     f"the controller up to {asked_text(k)}, achieved up to {math.degrees(k['achieved_rate']):.4g} deg/s, motor 1 drew up to "
                     f"{k['current']:.3g} A")
        return text


def asked_text(keyhole_max: dict) -> str:
    """What the controller asked of motor 1 near the keyhole: "12.3 V", or "4 A" in current drive."""
    if "asked_current" in keyhole_max:
        return f"{keyhole_max['asked_current']:.4g} A"
    return f"{keyhole_max.get('asked_voltage', 0.0):.4g} V"
