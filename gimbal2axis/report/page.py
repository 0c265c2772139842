"""The comparison's page: <out>/<name>.html, one file a person reads (the table, then the figure,
embedded), with the figure also as <name>.png and the table as <name>.csv.

The figure: the line-of-sight error of each case over time (its first run; one panel each, the same
axes, so no case hides another), then per axis (cross-elevation, elevation) the error's PSD averaged
over the case's runs and its cumulative RMS over frequency, every case on one axis (log scales
spanning the data)."""
from __future__ import annotations

import base64
import csv
import html
import io
import math
import pathlib

import numpy as np

AXIS_TITLES = {"los_error_xel": "cross-elevation", "los_error_el": "elevation"}


def averaged_spectrum(runs: list, axis_name: str):
    """(frequency, PSD, cumulative RMS) of one axis's error, the PSD averaged over the runs (the
    same bins: the runs have the same length and resolution)."""
    spectra = [result.los_spectra()[axis_name] for result in runs]
    density = np.mean([spectrum.psd for spectrum in spectra], axis=0)
    return spectra[0].frequency, density, np.sqrt(np.cumsum(density) * spectra[0].resolution)


def _figure(results: list, title: str):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    count = len(results)
    time_rows = math.ceil(count / 2)
    fig, axes = plt.subplots(time_rows + 2, 2, figsize=(12, 3.0 * (time_rows + 2)), squeeze=False)
    fig.suptitle(title)
    # log above the 1st percentile of the errors, linear below it down to 0 (symlog): the start-up
    # transient, the jitter and the near-zero samples (a run that starts on target) all stay visible
    errors = [runs[0].signals["los_error"] * 1e3 for _, runs in results]
    linear_below = max(float(np.percentile(np.concatenate(errors), 1.0)), 1e-12)
    high = max(float(e.max()) for e in errors)
    for index, (case, runs) in enumerate(results):
        result = runs[0]
        ax = axes[index // 2][index % 2]
        ax.plot(result.signals["time"], errors[index], lw=0.5)
        ax.set_yscale("symlog", linthresh=linear_below)
        ax.set_ylim(0.0, high * 1.5)
        ax.axvspan(0.0, result.window_start(), color="0.9", zorder=0, label="before the metrics window")
        ax.set_title(f"{case.name}: RMS {result.los_metrics()['rms'] * 1e3:.4g} mrad from "
                     f"{result.window_start():g} s", fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("LOS error [mrad]")
    if count % 2:
        axes[time_rows - 1][1].axis("off")
    for column, axis_name in enumerate(AXIS_TITLES):
        density_ax, cumulative_ax = axes[time_rows][column], axes[time_rows + 1][column]
        for case, runs in results:
            frequency, density, cumulative = averaged_spectrum(runs, axis_name)
            shown = frequency > 0   # 0 Hz has no place on a log axis; its power is in the cumulative RMS
            density_ax.loglog(frequency[shown], density[shown] * 1e6, lw=0.8, label=case.name)
            cumulative_ax.semilogx(frequency[shown], cumulative[shown] * 1e3, lw=1.0, label=case.name)
        density_ax.set_title(f"{AXIS_TITLES[axis_name]} error: PSD", fontsize=9)
        density_ax.set_ylabel("PSD [mrad^2/Hz]")
        cumulative_ax.set_title(f"{AXIS_TITLES[axis_name]} error: cumulative RMS (from 0 Hz)", fontsize=9)
        cumulative_ax.set_ylabel("RMS [mrad]")
        for ax in (density_ax, cumulative_ax):
            ax.set_xlabel("frequency [Hz]")
            ax.grid(True, which="both", lw=0.3)
            ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _table_html(rows: list[dict]) -> str:
    columns = list(rows[0])
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{v:.4g}</td>" if isinstance(v, float) else f"<td>{html.escape(str(v))}</td>"
                                    for v in row.values()) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def write_page(comparison, results: list, rows: list[dict], out: pathlib.Path) -> dict:
    """Writes <out>/<name>.html, .png and .csv (name: the comparison file's stem); their paths."""
    out.mkdir(parents=True, exist_ok=True)
    stem = comparison.path.stem
    paths = {suffix: out / f"{stem}.{suffix}" for suffix in ("html", "png", "csv")}
    with open(paths["csv"], "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    figure = _figure(results, comparison.title)
    figure.savefig(paths["png"], dpi=110)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    import matplotlib.pyplot as plt
    plt.close(figure)
    scene = comparison.scene
    first = results[0][1][0]
    spectrum = next(iter(first.los_spectra().values()))
    notes = (f"Scene {html.escape(scene.path.name)}, {comparison.stop_time:g} s at a {scene.step_size:g} s step; "
             f"metrics over [{first.window_bounds()[0]:g}, {first.window_bounds()[1]:g}] s. PSD: Welch, Hann window, 50 % overlap, "
             f"{spectrum.resolution:.3g} Hz bins, {spectrum.segments} segments; the mean (static offset) is "
             f"removed first and given in the table. The same sea and encoders in every case; each case runs "
             f"{comparison.repeats} time(s), its sensors' seed moved on by 1 each time: the table gives the means "
             f"and the RMS's spread over the runs, the spectra are averaged over them, the time plots show the "
             f"first run.")
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(comparison.title)}</title>"
            "<style>body{font-family:sans-serif;max-width:1250px;margin:auto}table{border-collapse:collapse;"
            "font-size:13px}td,th{border:1px solid #bbb;padding:3px 6px;text-align:right}</style></head><body>"
            f"<h1>{html.escape(comparison.title)}</h1><p>{html.escape(comparison.description)}</p><p>{notes}</p>"
            f"<h2>Line-of-sight error [mrad]</h2>{_table_html(rows)}"
            f"<h2>Time and frequency</h2><img style='width:100%' src='data:image/png;base64,"
            f"{base64.b64encode(buffer.getvalue()).decode()}'></body></html>")
    paths["html"].write_text(page, encoding="utf-8")
    return paths
