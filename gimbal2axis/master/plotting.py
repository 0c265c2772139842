"""PNG plots of a run: angles, rates, voltages, currents, backlash, line-of-sight error, base motion.

Default panels depend on the scene (no LOS panel without a target, no base panel on a fixed base);
the scene's [plot] table adds panels, or replaces a default panel of the same name. Every sample is
drawn as recorded: axis limits come from the data, never the other way round.
"""
from __future__ import annotations

import math
import pathlib
import textwrap

import numpy as np

from . import spectra
from ..errors import excerpt
from ..limits import TITLE_DESCRIPTION_CHARS
from ..scene.drives import command_columns

DEG = 180.0 / math.pi
# The error angle between two unit vectors of doubles is exact to ~1e-15 rad: below 1e-12 rad
# (1e-9 mrad) it is zero (a run that starts on target), and a log axis down to there would squash
# every real error into the top of the panel.
ROUND_OFF_MRAD = 1e-9


def drawn(text: str, limit: int | None = None) -> str:
    """User text (a title, a description, a panel's name) as a figure draws it: cut to `limit` characters
    (the wrapping and the layout of a long text take minutes), and literal: matplotlib reads text between
    two '$' as mathtext, whose parser refuses most text (an unknown \\name raises when the figure is saved)."""
    return (excerpt(text, limit) if limit else text).replace("$", r"\$")


def run_title(scene) -> str:
    """The scene's title and the first line of its description, cut."""
    lines = scene.description.strip().splitlines()
    description = excerpt(lines[0], TITLE_DESCRIPTION_CHARS) if lines else ""
    return f"{scene.title}: {description}" if description else scene.title


def signal_unit(name: str) -> tuple[float, str]:
    """(scale, unit) a signal is plotted in."""
    if name in ("los_error", "alpha_error", "beta_error", "los_error_xel", "los_error_el") or name.startswith("theta_b"):
        return 1e3, "mrad"
    if name.endswith("_dot") or name.startswith("los.omega") or name.startswith("base.omega2"):
        return DEG, "deg/s"
    if name.endswith("_ddot"):
        return DEG, "deg/s2"
    if name in ("alpha", "beta", "alpha_m", "beta_m", "alpha_ref", "beta_ref", "los_azimuth", "los_elevation",
                "base.delta", "base.psi", "base.gamma"):
        return DEG, "deg"
    if name.startswith("u_R") or (name.startswith("amplifier") and name.endswith((".u", ".x_I"))):
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
    drives = [command_columns(s, motor) for motor in (1, 2)]
    # the armature voltages (in current drive the amplifier's output), the currents with their commands
    panels["voltages"] = [drive.voltage_column for drive in drives if drive.voltage_column in s]
    panels["currents"] = ["i_R1", "i_R2"] + [drive.applied for drive in drives if drive.kind == "current"]
    panels["backlash"] = [n for n in ("theta_b1", "theta_b2") if n in s]
    if result.has_target:
        panels["line-of-sight error"] = ["los_error"]
    if not result.scene.base_motion().fixed:
        panels["base attitude"] = ["base.delta", "base.psi", "base.gamma"]
    return {k: v for k, v in panels.items() if v}


LABELS = {"alpha": "alpha (azimuth)", "beta": "beta (elevation)", "alpha_ref": "alpha set point",
          "beta_ref": "beta set point", "los.omega[1]": "gyro x (elevation)", "los.omega[3]": "gyro z (cross-elev.)",
          "u_R1": "u_R1 applied", "u_R2": "u_R2 applied", "amplifier1.u": "u_R1 by the amplifier",
          "amplifier2.u": "u_R2 by the amplifier", "i_R1_cmd": "i_R1 commanded", "i_R2_cmd": "i_R2 commanded",
          "base.delta": "pitch delta", "base.psi": "yaw psi",
          "base.gamma": "roll gamma", "los_error": "LOS error",
          "los_error_xel": "LOS error, cross-elevation", "los_error_el": "LOS error, elevation"}


def draw_los_error(ax, result, t: np.ndarray, values: np.ndarray) -> None:
    """The line-of-sight error [mrad] on a log axis (a slew of a few rad and a settled error of
    micro-radians in one panel) whose limits come from the data's own minimum and maximum, so no
    sample is clipped. Zeros have no logarithm: with errors at round-off (ROUND_OFF_MRAD) or 0 the
    axis is symlog, linear from 0 up to the smallest error above round-off, and they sit at 0.
    The RMS line spans the window it is taken over."""
    ax.plot(t, values, "-", lw=0.9, label=LABELS["los_error"])
    m = result.los_metrics()
    # the window's first and last sample (los_metrics takes the whole run when the window is empty),
    # from the result: a decimated `t` has no sample at the window's start
    start, end = result.window_bounds()
    rms = m["rms"] * 1e3
    ax.hlines(rms, start, end, color="C1", lw=1.2, ls=":",
              label=f"RMS over [{start:g}, {end:g}] s: {rms:.3g} mrad")
    references = [rms]
    bound = result.scene.requirements.get("los_rms_max_mrad")
    if bound:
        ax.hlines(bound, start, end, color="C3", lw=0.8, ls="--", label=f"required RMS <= {bound:g} mrad")
        references.append(bound)
    finite = values[np.isfinite(values)]
    resolved = np.concatenate([finite[finite > ROUND_OFF_MRAD], [r for r in references if r > ROUND_OFF_MRAD]])
    if resolved.size == 0:
        return
    low, high = resolved.min(), resolved.max()
    if np.any(finite < low):
        ax.set_yscale("symlog", linthresh=low)
        ax.set_ylim(min(finite.min(), 0.0), high * 1.5)
    else:
        ax.set_yscale("log")
        ax.set_ylim(low / 1.5, high * 1.5)


def figure(result, limits: dict | None = None):
    """The figure of a run (matplotlib, Agg). `limits`: optional {signal: value} drawn as dashed
    +-lines (i_L, eta)."""
    # a Figure of its own, drawn by Agg when saved: pyplot (its backends and figure managers) is not needed
    from matplotlib.figure import Figure

    s, scene = result.signals, result.scene
    panels = default_panels(result)
    panels.update(scene.plot)
    limits = limits or {}
    t = s["time"]
    fig = Figure(figsize=(12, 1.9 * len(panels) + 0.8))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)
    for ax, (panel, names) in zip(axes[:, 0], panels.items()):
        units = set()
        for name in names:
            scale, unit = signal_unit(name)
            units.add(unit)
            style = "--" if name.endswith("_ref") else "-"
            values = np.asarray(result.signal(name), dtype=float) * scale
            if name == "los_error" and result.has_target:
                draw_los_error(ax, result, t, values)
            else:
                ax.plot(t, values, style, lw=0.9, label=LABELS.get(name, name))
            if name in limits:
                for sign in (1, -1):
                    ax.axhline(sign * limits[name] * scale, color="gray", lw=0.7, ls="--")
        ax.set_ylabel(f"{drawn(panel, 40)}\n[{', '.join(sorted(u for u in units if u)) or '-'}]", fontsize="small")
        ax.grid(True, alpha=0.3, which="both")
        # outside the axes: a legend box inside would cover samples
        ax.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0.0, fontsize="x-small")
    axes[-1, 0].set_xlabel("time [s]")
    if t[-1] > t[0]:   # a record of one point keeps matplotlib's margins around it
        axes[-1, 0].set_xlim(t[0], t[-1])
    title = run_title(scene)
    if scene.title != scene.name:
        title = f"{title} ({scene.path.name})"
    stopped = getattr(result, "stopped", None)
    if stopped is not None:
        title = f"PARTIAL: {stopped.kind} at t = {stopped.time:g} s of {result.requested_stop_time:g} s. {title}"
    fig.suptitle("\n".join(textwrap.wrap(drawn(title), 130)), fontsize="medium")
    fig.tight_layout()
    return fig


def plot(result, path: pathlib.Path, limits: dict | None = None) -> None:
    """Writes the PNG of `figure(result, limits)`."""
    figure(result, limits).savefig(path, dpi=100)   # no pyplot figure to close: it goes with its last reference


# How far below its peak the carrier's rate PSD still counts as input to the isolation estimate: the sea's
# band (in the ship scene it is 50 to 70 dB down from 0.5 Hz on, and 10 to 20 decades down above 20 Hz,
# at round-off).
CARRIER_RANGE_DB = 60.0


def carrier_has_power(carrier_psd: np.ndarray) -> np.ndarray:
    """The bins where the carrier's rate PSD is within CARRIER_RANGE_DB of its peak."""
    carrier_psd = np.asarray(carrier_psd, dtype=float)
    peak = float(np.nanmax(carrier_psd)) if carrier_psd.size else 0.0
    return np.nan_to_num(carrier_psd, nan=0.0) >= peak * 10 ** (-CARRIER_RANGE_DB / 10) if peak > 0 else \
        np.zeros(carrier_psd.shape, dtype=bool)


def spectrum_figure(result):
    """The line-of-sight error in the frequency domain (spectra.py, docs/jitter.md), drawn beside the
    time plot: per axis the Welch PSD [mrad^2/Hz] and the cumulative RMS [mrad] on log-log axes, the
    scene's bands marked; on a moving base also the isolation estimated from the run (|H1| of the gyro
    against the carrier's rate about the same payload axis) and its coherence. None without a target.
    The 0-Hz bin has no place on a log axis: its value is in the legend (and the CSV), and it is in
    every cumulative RMS. The y limits are matplotlib's from every drawn value: nothing is clipped."""
    from matplotlib.figure import Figure   # as in figure(): no pyplot

    found = result.los_spectra()
    if not found:
        return None
    # A tracking scene's line of sight turns on purpose: its gyro rate is the target's, not what the
    # carrier's motion leaves, and the ratio is no isolation.
    isolation = result.isolation_estimates() if result.scene.moving_target is None else {}
    rows = 2 + (2 if isolation else 0)
    fig = Figure(figsize=(10, 2.6 * rows + 0.8))
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)
    axes = axes[:, 0]
    for index, (name, spectrum) in enumerate(found.items()):
        f, psd = spectrum.frequency, spectrum.psd * 1e6
        label = (f"{LOS_AXIS_LABELS[name]} (mean {spectrum.mean * 1e3:.3g} mrad removed; "
                 f"0-Hz bin {psd[0]:.3g} mrad^2/Hz)")
        shown = (f > 0) & (psd > 0)
        hidden = int((f > 0).sum() - shown.sum())
        if hidden:
            label += f"; {hidden} bins of exactly 0 not drawn"
        axes[0].loglog(f[shown], psd[shown], lw=0.9, color=f"C{index}", label=label)
        cumulative = spectrum.cumulative_rms() * 1e3
        axes[1].loglog(f[f > 0], cumulative[f > 0], lw=1.1, color=f"C{index}",
                       label=f"{LOS_AXIS_LABELS[name]}: total {cumulative[-1]:.3g} mrad RMS")
    spectrum = next(iter(found.values()))
    t = result.window_bounds()
    axes[0].set_title(f"Welch: {spectrum.resolution:g} Hz resolution, Hann window, 50 % overlap, "
                      f"{spectrum.segments} segment(s) over [{t[0]:g}, {t[-1]:g}] s", fontsize="small")
    axes[0].set_ylabel("LOS error PSD\n[mrad^2/Hz]", fontsize="small")
    axes[1].set_ylabel("cumulative RMS\n[mrad]", fontsize="small")
    rms = result.band_rms()
    for k, (band, (lo, hi)) in enumerate(result.scene.analysis.bands.items()):
        for ax in axes[:2]:
            ax.axvspan(max(lo, spectrum.resolution / 2), hi, color=f"C{k % 10}", alpha=0.07)
        axes[1].text(math.sqrt(max(lo, spectrum.resolution) * hi), 1.0, f"{band}\n{rms[band] * 1e3:.3g} mrad",
                     transform=axes[1].get_xaxis_transform(), ha="center", va="top", fontsize="x-small")
    if isolation:
        for index, (i, estimate) in enumerate(isolation.items()):
            f = estimate.frequency
            gain = np.abs(estimate.response)
            shown = (f > 0) & np.isfinite(gain) & (gain > 0)
            # bins whose H1 is not known are drawn light grey: the gain there is the estimate's noise. Known
            # needs both the coherence (random error within spectra.H1_RANDOM_ERROR) and input: where the
            # carrier's rate has no power, some of thousands of bins pass the coherence bound by chance and
            # show a gain of 1e4 to 1e6 (a ratio of two spectra at round-off level)
            known = shown & estimate.coherent & carrier_has_power(result.carrier_spectrum(i))
            axes[2].loglog(f[shown], gain[shown], lw=0.7, color="0.8",
                           label=None if index else f"gain not known: coherence < {estimate.coherence_bound:.2g} "
                                                    f"(random error > {spectra.H1_RANDOM_ERROR:.0%}), or the carrier's "
                                                    f"rate more than {CARRIER_RANGE_DB:.0f} dB below its peak")
            axes[2].loglog(f[shown], np.where(known, gain, np.nan)[shown], lw=0.9, marker=".", ms=3,
                           color=f"C{index + 2}",
                           label=f"los.omega[{i}] / carrier rate about payload axis {i} ({ISOLATION_LABELS[i]}): "
                                 f"{known.sum()} of {shown.sum()} bins known")
            axes[3].semilogx(f[f > 0], estimate.coherence[f > 0], lw=0.9, color=f"C{index + 2}",
                             label=f"{ISOLATION_LABELS[i]}")
        axes[3].axhline(estimate.coherence_bound, color="k", lw=0.8, ls="--",
                        label=f"{estimate.coherence_bound:.2g}: below, |H1| has more than {spectra.H1_RANDOM_ERROR:.0%} "
                              f"random error ({estimate.averages:.3g} independent averages)")
        axes[3].axhline(1.0 / max(estimate.segments, 1), color="gray", lw=0.7, ls=":",
                        label=f"1/segments = {1.0 / max(estimate.segments, 1):.2g} (no relation reads about this)")
        t = result.window_bounds()
        axes[2].set_title(f"isolation from this run over [{t[0]:g}, {t[-1]:g}] s: H1 estimate, "
                          f"{estimate.resolution:g} Hz resolution, {estimate.segments} segment(s)", fontsize="small")
        axes[2].set_ylabel("|H1| LOS rate /\ncarrier rate", fontsize="small")
        axes[3].set_ylabel("coherence", fontsize="small")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0.0, fontsize="x-small")
    axes[-1].set_xlabel("frequency [Hz]")
    fig.suptitle(f"{drawn(result.scene.title)}: line-of-sight error in the frequency domain", fontsize="medium")
    fig.tight_layout()
    return fig


LOS_AXIS_LABELS = {"los_error_xel": "cross-elevation", "los_error_el": "elevation"}
ISOLATION_LABELS = {1: "elevation", 3: "cross-elevation"}


def plot_spectrum(result, path: pathlib.Path) -> bool:
    """Writes the PNG of `spectrum_figure(result)`; False (nothing written) without a target."""
    fig = spectrum_figure(result)
    if fig is None:
        return False
    fig.savefig(path, dpi=100)
    return True


# The signals the tracking figure draws (a run with a moving target: results.tracking_signals).
TRACKING_PLOT_SIGNALS = ("time", "los_error", "target_elevation", "beta_cmd", "alpha_cmd_dot", "beta_cmd_dot",
                         "alpha_dot", "beta_dot", "i_R1", "i_R2", "i_R1_cmd", "i_R2_cmd")
TRACKING_PLOT_POINTS = 20000   # samples drawn at most (evenly strided): the figure's pixels hold fewer


def tracking_figure(scene, columns: dict, title_prefix: str = ""):
    """The tracking figure of a run with a moving target: the pointing error against time (the time
    near the keyhole shaded) and against the target's elevation, the azimuth and elevation rates the
    pointing command asked and those achieved, and the motors' currents. `columns`: the
    TRACKING_PLOT_SIGNALS (whole or strided record)."""
    from matplotlib.figure import Figure

    t = columns["time"]
    error = columns["los_error"] * 1e3
    spec = scene.target_spec
    half_beam = spec["beam_width_mrad"] / 2.0
    near = np.abs(columns["beta_cmd"]) > math.radians(90.0 - spec["keyhole_deg"])
    fig = Figure(figsize=(12, 10))
    axes = fig.subplots(4, 1, squeeze=False)[:, 0]
    ax = axes[0]
    positive = np.where(error > ROUND_OFF_MRAD, error, np.nan)
    ax.semilogy(t, positive, lw=0.8, label="line-of-sight error")
    ax.axhline(half_beam, color="C3", lw=0.8, ls="--", label=f"half beam ({half_beam:g} mrad)")
    if near.any():
        edges = np.flatnonzero(np.diff(np.r_[0, near.astype(int), 0]))
        for start, stop in zip(edges[::2], edges[1::2]):
            ax.axvspan(t[start], t[stop - 1], color="C1", alpha=0.15, lw=0)
        ax.axvspan(np.nan, np.nan, color="C1", alpha=0.15, label=f"near the keyhole (within {spec['keyhole_deg']:g} deg)")
    ax.set_ylabel("pointing error\n[mrad]", fontsize="small")
    ax.set_xlabel("time [s]", fontsize="small")
    ax = axes[1]
    ax.semilogy(np.degrees(columns["target_elevation"]), positive, ".", ms=1.0, alpha=0.5)
    ax.axhline(half_beam, color="C3", lw=0.8, ls="--")
    ax.set_xlabel("target elevation in G [deg]", fontsize="small")
    ax.set_ylabel("pointing error\n[mrad]", fontsize="small")
    ax = axes[2]
    # what was achieved under what was asked, which is drawn dashed on top
    for name, label, style, color in (("alpha_dot", "azimuth rate achieved", "-", "C0"),
                                      ("beta_dot", "elevation rate achieved", "-", "C1"),
                                      ("alpha_cmd_dot", "azimuth rate asked", "--", "navy"),
                                      ("beta_cmd_dot", "elevation rate asked", "--", "saddlebrown")):
        ax.plot(t, np.degrees(columns[name]), style, color=color, lw=0.9, label=label)
    ax.set_ylabel("joint rates\n[deg/s]", fontsize="small")
    ax.set_xlabel("time [s]", fontsize="small")
    ax = axes[3]
    for name in ("i_R1", "i_R2"):
        if name in columns:
            ax.plot(t, columns[name], lw=0.9, label=f"{name} (motor {name[-1]})")
    for name, color in (("i_R1_cmd", "navy"), ("i_R2_cmd", "saddlebrown")):   # current drive: what was commanded
        if name in columns:
            ax.plot(t, columns[name], "--", color=color, lw=0.9, label=f"{name} (commanded)")
    ax.set_ylabel("currents\n[A]", fontsize="small")
    ax.set_xlabel("time [s]", fontsize="small")
    for ax in axes:
        ax.grid(True, alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0.0, fontsize="x-small")
    for ax in (axes[0], axes[2], axes[3]):
        if t[-1] > t[0]:
            ax.set_xlim(t[0], t[-1])
    kinds = {"earth_point": "a point on the Earth", "flyby": "an aircraft's flyby", "track": "a recorded track"}
    title = f"{title_prefix}{scene.title}: tracking {kinds[spec['type']]}"
    fig.suptitle("\n".join(textwrap.wrap(drawn(title), 130)), fontsize="medium")
    fig.tight_layout()
    return fig


def plot_tracking(result, path: pathlib.Path, parquet_path: pathlib.Path | None = None) -> bool:
    """Writes <scene>_tracking.png (tracking_figure) of a run with a moving target, from the record
    in memory or, for a streamed run, the Parquet file's columns; False (nothing written) without a
    moving target."""
    scene = result.scene
    if scene.moving_target is None:
        return False
    if parquet_path is not None:
        from .record_files import record_columns

        columns = record_columns(parquet_path, TRACKING_PLOT_SIGNALS)
    else:
        columns = {name: np.asarray(result.signal(name), dtype=float) for name in TRACKING_PLOT_SIGNALS
                   if name in result.signals or name in result.derived}
    stride = max(1, len(columns["time"]) // TRACKING_PLOT_POINTS)
    if stride > 1:
        # the largest errors stay in: every sample whose error is its stride's maximum is kept too
        keep = np.zeros(len(columns["time"]), dtype=bool)
        keep[::stride] = True
        error = columns["los_error"]
        blocks = np.arange(0, len(error), stride)
        keep[blocks + np.array([np.argmax(error[i:i + stride]) for i in blocks])] = True
        columns = {name: values[keep] for name, values in columns.items()}
    stopped = getattr(result, "stopped", None)
    prefix = f"PARTIAL: {stopped.kind} at t = {stopped.time:g} s. " if stopped is not None else ""
    tracking_figure(scene, columns, prefix).savefig(path, dpi=100)
    return True
