"""PNG plots of a run: angles, rates, voltages, currents, backlash, line-of-sight error, base motion.

Default panels depend on the scene (no LOS panel without a target, no base panel on a fixed base);
the scene's [plot] table adds panels, or replaces a default panel of the same name.
"""
from __future__ import annotations

import math
import pathlib

import numpy as np

DEG = 180.0 / math.pi


def signal_unit(name: str) -> tuple[float, str]:
    """(scale, unit) a signal is plotted in."""
    if name in ("los_error", "alpha_error", "beta_error") or name.startswith("theta_b"):
        return 1e3, "mrad"
    if name.endswith("_dot") or name.startswith("los.omega"):
        return DEG, "deg/s"
    if name.endswith("_ddot"):
        return DEG, "deg/s2"
    if name in ("alpha", "beta", "alpha_m", "beta_m", "alpha_ref", "beta_ref", "los_azimuth", "los_elevation",
                "base.delta", "base.psi", "base.gamma"):
        return DEG, "deg"
    if name.startswith("u_R"):
        return 1.0, "V"
    if name.startswith("i_R"):
        return 1.0, "A"
    if name.startswith("T_E"):
        return 1.0, "N.m"
    if name == "heave":
        return 1.0, "m"
    return 1.0, ""


def default_panels(result) -> dict:
    s = result.signals
    panels = {"angles": ["alpha", "beta"]}
    if not np.all(np.isnan(s["alpha_ref"])):
        panels["angles"] += ["alpha_ref", "beta_ref"]
    panels["rates"] = ["alpha_dot", "beta_dot", "los.omega[1]", "los.omega[3]"]
    panels["voltages"] = ["u_R1", "u_R2"]
    panels["currents"] = ["i_R1", "i_R2"]
    panels["backlash"] = [n for n in ("theta_b1", "theta_b2") if n in s]
    if result.has_target:
        panels["line-of-sight error"] = ["los_error"]
    if not result.scene.base_motion().fixed:
        panels["base attitude"] = ["base.delta", "base.psi", "base.gamma"]
    return {k: v for k, v in panels.items() if v}


LABELS = {"alpha": "alpha (azimuth)", "beta": "beta (elevation)", "alpha_ref": "alpha set point",
          "beta_ref": "beta set point", "los.omega[1]": "gyro x (elevation)", "los.omega[3]": "gyro z (cross-elev.)",
          "u_R1": "u_R1 applied", "u_R2": "u_R2 applied", "base.delta": "pitch delta", "base.psi": "yaw psi",
          "base.gamma": "roll gamma", "los_error": "LOS error"}


def plot(result, path: pathlib.Path, limits: dict | None = None) -> None:
    """Writes the PNG. `limits`: optional {signal: value} drawn as dashed +-lines (i_L, eta)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s, scene = result.signals, result.scene
    panels = default_panels(result)
    panels.update(scene.plot)
    limits = limits or {}
    t = s["time"]
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(10, 1.9 * len(panels) + 0.8), squeeze=False)
    for ax, (panel, names) in zip(axes[:, 0], panels.items()):
        units = set()
        for name in names:
            scale, unit = signal_unit(name)
            units.add(unit)
            style = "--" if name.endswith("_ref") else "-"
            values = np.asarray(s[name], dtype=float) * scale
            if name == "los_error":
                floor = max(np.percentile(values, 2), 1e-4 * values.max(), 1e-9)
                ax.semilogy(t, np.maximum(values, floor), style, lw=0.9, label=LABELS.get(name, name))
                m = result.los_metrics()
                ax.axhline(m["rms"] * 1e3, color="C1", lw=0.8, ls=":",
                           label=f"RMS from {m['from_s']:g} s: {m['rms'] * 1e3:.3g} mrad")
                bound = scene.requirements.get("los_rms_max_mrad")
                if bound:
                    ax.axhline(bound, color="C3", lw=0.8, ls="--", label=f"required RMS <= {bound:g} mrad")
            else:
                ax.plot(t, values, style, lw=0.9, label=LABELS.get(name, name))
            if name in limits:
                for sign in (1, -1):
                    ax.axhline(sign * limits[name] * scale, color="gray", lw=0.7, ls="--")
        ax.set_ylabel(f"{panel}\n[{', '.join(sorted(u for u in units if u)) or '-'}]", fontsize="small")
        ax.grid(True, alpha=0.3, which="both")
        ax.legend(loc="upper right", fontsize="x-small", ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 0].set_xlim(t[0], t[-1])
    title = f"{scene.name}: {scene.description}"
    fig.suptitle(title if len(title) < 110 else title[:107] + "...", fontsize="medium")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
