"""The results table: one row per case (tidy), Parquet (the truth) plus CSV (for convenience);
merging new rows into an existing table (rows are keyed by case_id), and the summary plot. Reading
and writing the files, safely for several sweeps at once: store.py."""
from __future__ import annotations

import math
import pathlib

FIRST = ["case_id", "case", "sweep", "scene", "scene_hash", "stop_time"]
LAST = ["seed", "sampling_seed", "status", "los_rms_mrad", "los_peak_mrad", "los_final_mrad", "los_from_s",
        "i_peak_R1_A", "i_peak_R2_A", "i_peak_A", "events", "requirements_met", "wall_time_s", "cpu_time_s", "message", "fmu_log",
        "worker", "instance_use", "fmu_sha256"]
METRICS = ["los_rms_mrad", "los_peak_mrad", "i_peak_A", "events", "wall_time_s"]


def band_metrics(rows: list[dict]) -> list[str]:
    """The band RMS columns of a scene with [analysis.bands] (los_band_<name>_rms_mrad), in row order."""
    return list(dict.fromkeys(k for row in rows for k in row if is_band_metric(k)))


def is_band_metric(name: str) -> bool:
    return name.startswith("los_band_") and name.endswith("_rms_mrad")


# Columns a worker's result adds besides those of LAST (a case of a lockstep batch).
RESULT_EXTRAS = ["batch_size"]


def is_result_or_key(name: str) -> bool:
    """A column that is not a swept parameter: the case's key and metadata, a metric, a status."""
    return name in FIRST or name in LAST or name in RESULT_EXTRAS or is_band_metric(name)


def column_order(rows: list[dict], parameters: list[str]) -> list[str]:
    """FIRST, the parameters, other columns, LAST, with the band RMS columns (if any) after the other
    line-of-sight metrics."""
    names = [c for c in FIRST] + [p for p in parameters if p not in FIRST + LAST]
    bands = band_metrics(rows)
    seen = set(names) | set(LAST) | set(bands)
    extra = []
    for row in rows:
        for key in row:
            if key not in seen:
                seen.add(key)
                extra.append(key)
    at = LAST.index("los_from_s") + 1
    return names + extra + LAST[:at] + bands + LAST[at:]


def _arrow_column(values: list):
    """One typed column: bool, int64, float64 or string (nulls allowed)."""
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return pa.array(values, type=pa.bool_())
    if present and all(map(_is_integer, present)):
        return pa.array(values, type=pa.int64())
    if all(map(_is_number, present)):
        return pa.array([None if v is None else float(v) for v in values], type=pa.float64())
    return pa.array([None if v is None else str(v) for v in values], type=pa.string())


def _is_integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def to_arrow(rows: list[dict], parameters: list[str]):
    import pyarrow as pa

    names = column_order(rows, parameters)
    return pa.table({name: _arrow_column([row.get(name) for row in rows]) for name in names})


def read_rows(path: pathlib.Path) -> list[dict]:
    """The rows of a table ([] if there is none yet), whole even while a sweep replaces the file."""
    try:
        with open(path, "rb") as file:
            return read_parquet(file).to_pylist()
    except FileNotFoundError:
        return []


def read_parquet(file):
    """A Parquet table from one open file. Not pq.read_table(path): that opens the path several times
    (pyarrow's dataset reader: the footer from one open, the pages from another), so a file replaced
    in between, as a sweep saving its table does, reads as corrupt; an open file stays one version."""
    import pyarrow.parquet as pq

    return pq.ParquetFile(file).read(use_threads=False)   # no Arrow thread left busy when a refusal exits at once


def merge(existing: list[dict], new: list[dict]) -> list[dict]:
    """Existing rows, with those of the same case_id replaced by the new ones; sorted by case."""
    by_id = {row["case_id"]: row for row in existing}
    by_id.update({row["case_id"]: row for row in new})
    return sorted(by_id.values(), key=lambda r: (r.get("case") if r.get("case") is not None else math.inf,
                                                 r["case_id"]))


LABELS = {"los_rms_mrad": "LOS RMS [mrad]", "los_peak_mrad": "LOS peak [mrad]", "i_peak_A": "peak |i| [A]",
          "events": "events", "wall_time_s": "wall time [s]"}


def metric_label(name: str) -> str:
    if is_band_metric(name):
        return f"LOS RMS, band {name[len('los_band_'):-len('_rms_mrad')]} [mrad]"
    return LABELS.get(name, name)


def is_seed(name: str) -> bool:
    """A random seed: its values are labels, not an ordered quantity (no trend, no log scale)."""
    last = name.rpartition(".")[2]
    return last == "seed" or last.endswith("_seed")


def _wrap(name: str, width: int = 22) -> str:
    """A long dotted name on several lines, broken after dots, so neighbouring labels stay apart."""
    lines, line = [], ""
    for part in name.split("."):
        piece = part if not line else "." + part
        if line and len(line) + len(piece) > width:
            lines.append(line + ".")
            line = part
        else:
            line += piece
    return "\n".join(lines + [line])


def _tick(value) -> str:
    """A grid value in at most 4 significant digits, without an exponent where it is avoidable
    (16000, not 1.6e+04)."""
    if isinstance(value, int) or not (1e-3 <= abs(value) < 1e6):
        return f"{value:.4g}"
    text = f"{value:.{max(0, 3 - math.floor(math.log10(abs(value))))}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _finite(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _numeric(rows: list[dict], name: str) -> bool:
    values = [r.get(name) for r in rows if r.get(name) is not None]
    return bool(values) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def _log_scale(values, ratio: float = 50.0) -> bool:
    """All positive and spanning `ratio` or more."""
    positive = [v for v in values if _finite(v) and v > 0]
    return bool(positive) and len(positive) == len(values) and max(positive) / min(positive) >= ratio


def plot_summary(rows: list[dict], parameters: list[str], path: pathlib.Path, title: str = "",
                 grid: list[str] | None = None) -> None:
    """Writes the summary plot of a sweep (summary_figure) to `path`, as PNG whatever its suffix (a
    temporary file of store.publish)."""
    import matplotlib.pyplot as plt

    fig = summary_figure(rows, parameters, title, grid)
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)


def summary_figure(rows: list[dict], parameters: list[str], title: str = "", grid: list[str] | None = None):
    """The summary plot of a sweep. A grid of exactly two numeric parameters (e.g. two gains): a heat
    map per metric over the two (the median over the samples of each grid point). Otherwise each
    metric (rows of panels) against each swept parameter (columns), with the median per value of a
    grid parameter; a seed gets no trend line. Failed cases are marked in red either way."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r.get("status") == "ok"]
    failed = [r for r in rows if r.get("status") != "ok"]
    metrics = _plotted_metrics(rows, ok)
    title = title or f"{len(rows)} cases: {len(ok)} ok, {len(failed)} failed"
    pair = _heat_map_pair(rows, grid or [])
    if pair and metrics:
        return _heat_maps(plt, rows, pair[0], pair[1], metrics, title)
    numeric = [p for p in parameters if _numeric(rows, p)] or ["case"]
    return _scatter_panels(plt, rows, ok, failed, numeric, metrics or ["wall_time_s"], title)


def _plotted_metrics(rows: list[dict], ok: list[dict]) -> list[str]:
    """The metrics some ok case has a finite value of."""
    return [m for m in METRICS + band_metrics(rows) if any(_finite(r.get(m)) for r in ok)]


def _heat_map_pair(rows: list[dict], grid: list[str]) -> list[str] | None:
    """The two grid parameters of a heat map: a grid of exactly two numeric parameters, no seed, each
    with more than one value; else None."""
    pair = [p for p in grid if _numeric(rows, p) and not is_seed(p) and len(_values_of(rows, p)) > 1]
    return pair if len(grid) == 2 and len(pair) == 2 else None


def _values_of(rows: list[dict], parameter: str) -> set:
    return {r[parameter] for r in rows if r.get(parameter) is not None}


def _scatter_panels(plt, rows, ok, failed, numeric, metrics, title):
    fig, axes = plt.subplots(len(metrics), len(numeric), figsize=(3.3 * len(numeric) + 0.9, 2.3 * len(metrics) + 1.0),
                             squeeze=False, sharex="col", layout="constrained")
    for j, p in enumerate(numeric):
        seed = is_seed(p)
        floats = any(isinstance(r.get(p), float) for r in rows)
        log_x = not seed and floats and _log_scale([float(r[p]) for r in rows if r.get(p) is not None], 10.0)
        for i, m in enumerate(metrics):
            ax = axes[i, j]
            _scatter_panel(ax, ok, failed, p, m, seed)
            if i == 0 and j == 0 and ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7, loc="upper right")
            _parameter_axis(ax, log_x, seed)
            if j == 0:
                ax.set_ylabel(metric_label(m), fontsize=8)
            if i == len(metrics) - 1:
                ax.set_xlabel(_wrap(p) + (" (a seed)" if seed else ""), fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    return fig


def _scatter_panel(ax, ok, failed, p, m, seed: bool) -> None:
    """Metric m of the ok cases against parameter p, the median per value of a grid parameter, the
    failed cases as red crosses on the axis."""
    import numpy as np

    pairs = [(float(r[p]), float(r[m])) for r in ok if r.get(p) is not None and _finite(r.get(m))]
    x = np.array([a for a, _ in pairs])
    y = np.array([b for _, b in pairs])
    ax.plot(x, y, ".", ms=3 if len(x) > 200 else 5, alpha=0.5 if len(x) > 200 else 0.9, color="tab:blue")
    if not seed:
        _median_line(ax, x, y)
    if m.startswith("los") and _log_scale(list(y)):
        ax.set_yscale("log")
    xf = [float(r[p]) for r in failed if r.get(p) is not None]
    if xf:
        ax.plot(xf, [0.0] * len(xf), "x", color="tab:red", transform=ax.get_xaxis_transform(), clip_on=False,
                label=f"failed ({len(failed)})")


def _median_line(ax, x, y) -> None:
    """The median of y per value of x, when x looks like a grid parameter's (few values, repeated)."""
    import numpy as np

    levels = np.unique(x)
    if 1 < len(levels) <= 12 and len(x) > len(levels):
        ax.plot(levels, [np.median(y[x == v]) for v in levels], "-o", color="k", ms=3, lw=1, label="median")


def _parameter_axis(ax, log_x: bool, seed: bool) -> None:
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    if log_x:
        ax.set_xscale("log")
    else:   # few ticks, no offset text: long values (seeds, 0.53308) would run together
        ax.xaxis.set_major_locator(MaxNLocator(nbins=4, integer=seed))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, pos: f"{v:.6g}"))


def _heat_maps(plt, rows, px, py, metrics, title):
    import numpy as np
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm

    cmap = colormaps["viridis"].with_extremes(bad="0.85")   # grey: no case of the grid point ran to the end

    xs, ys = sorted(_values_of(rows, px)), sorted(_values_of(rows, py))
    cells = _grid_cells(rows, px, py, xs, ys)
    samples = max(len(c) for c in cells.values())
    cols = min(len(metrics), 3)
    nrows = -(-len(metrics) // cols)
    width = max(3.8, 0.55 * len(xs) + 2.6)
    fig, axes = plt.subplots(nrows, cols, figsize=(width * cols, max(3.2, 0.4 * len(ys) + 2.2) * nrows + 0.6),
                             squeeze=False, layout="constrained")
    for k, m in enumerate(metrics):
        ax = axes[k // cols, k % cols]
        z, fails = _cell_medians(cells, xs, ys, m)
        finite = z[np.isfinite(z)]
        norm = LogNorm(finite.min(), finite.max()) if m.startswith("los") and _log_scale(list(finite)) else None
        image = ax.imshow(np.ma.masked_invalid(z), origin="lower", aspect="auto", cmap=cmap, norm=norm,
                          interpolation="nearest")
        if len(xs) * len(ys) <= 80:   # the numbers too, while they fit in the cells
            _cell_texts(ax, image, z, fails)
        _grid_axes(ax, px, xs, py if k % cols == 0 else None, ys)
        label = metric_label(m)
        bar = fig.colorbar(image, ax=ax)
        bar.set_label(label + (f", median of {samples}" if samples > 1 else ""), fontsize=8)
        bar.ax.tick_params(labelsize=7)
        ax.set_title(label, fontsize=9)
    for k in range(len(metrics), nrows * cols):
        axes[k // cols, k % cols].set_visible(False)
    fig.get_layout_engine().set(wspace=0.08, hspace=0.06)
    fig.suptitle(title, fontsize=10)
    return fig


def _grid_cells(rows: list[dict], px: str, py: str, xs: list, ys: list) -> dict:
    """{(x, y): the cases of that grid point}."""
    return {(x, y): [r for r in rows if r.get(px) == x and r.get(py) == y] for x in xs for y in ys}


def _grid_axes(ax, px: str, xs: list, py: str | None, ys: list) -> None:
    """Ticks at the grid values; the y label only where py is given (the first column: the same parameter
    along every row, once, clear of the colour bars)."""
    ax.set_xticks(range(len(xs)), [_tick(v) for v in xs], fontsize=7, rotation=45 if len(xs) > 6 else 0)
    ax.set_yticks(range(len(ys)), [_tick(v) for v in ys], fontsize=7)
    ax.set_xlabel(_wrap(px, 40), fontsize=8)
    if py is not None:
        ax.set_ylabel(_wrap(py, 30), fontsize=8)


def _cell_medians(cells: dict, xs: list, ys: list, m: str):
    """(the median of metric m over the ok cases of each grid point, NaN where none; failed cases per point),
    both indexed [y, x]."""
    import numpy as np

    z = np.full((len(ys), len(xs)), np.nan)
    fails = np.zeros((len(ys), len(xs)), dtype=int)
    for (x, y), members in cells.items():
        i, j = ys.index(y), xs.index(x)
        values = [float(r[m]) for r in members if r.get("status") == "ok" and _finite(r.get(m))]
        fails[i, j] = sum(r.get("status") != "ok" for r in members)
        if values:
            z[i, j] = np.median(values)
    return z, fails


def _cell_texts(ax, image, z, fails) -> None:
    """Each cell's median and its failed cases written in it."""
    import numpy as np

    for i in range(z.shape[0]):
        for j in range(z.shape[1]):
            text = f"{z[i, j]:.3g}" if np.isfinite(z[i, j]) else ""
            if fails[i, j]:
                text += ("\n" if text else "") + f"{fails[i, j]} failed"
            bright = np.isfinite(z[i, j]) and image.norm(z[i, j]) > 0.5   # viridis: yellow at the top
            color = "tab:red" if fails[i, j] else "k" if bright else "w"
            ax.text(j, i, text, ha="center", va="center", fontsize=7, color=color)
