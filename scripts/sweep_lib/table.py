"""The results table: one row per case (tidy), Parquet (the truth) plus CSV (for convenience);
merging new rows into an existing table (rows are keyed by case_id), and the summary plot."""
from __future__ import annotations

import math
import pathlib

FIRST = ["case_id", "case", "sweep", "scene", "scene_hash", "stop_time"]
LAST = ["seed", "sampling_seed", "status", "los_rms_mrad", "los_peak_mrad", "los_final_mrad", "los_from_s",
        "i_peak_R1_A", "i_peak_R2_A", "i_peak_A", "events", "requirements_met", "wall_time_s", "cpu_time_s", "message", "fmu_log",
        "worker", "instance_use", "fmu_sha256"]
METRICS = ["los_rms_mrad", "los_peak_mrad", "i_peak_A", "events", "wall_time_s"]


def column_order(rows: list[dict], parameters: list[str]) -> list[str]:
    names = [c for c in FIRST] + [p for p in parameters if p not in FIRST + LAST]
    seen = set(names) | set(LAST)
    extra = []
    for row in rows:
        for key in row:
            if key not in seen:
                seen.add(key)
                extra.append(key)
    return names + extra + LAST


def _arrow_column(values: list):
    """One typed column: bool, int64, float64 or string (nulls allowed)."""
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return pa.array(values, type=pa.bool_())
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return pa.array(values, type=pa.int64())
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return pa.array([None if v is None else float(v) for v in values], type=pa.float64())
    return pa.array([None if v is None else str(v) for v in values], type=pa.string())


def to_arrow(rows: list[dict], parameters: list[str]):
    import pyarrow as pa

    names = column_order(rows, parameters)
    return pa.table({name: _arrow_column([row.get(name) for row in rows]) for name in names})


def read_rows(path: pathlib.Path) -> list[dict]:
    if not path.is_file():
        return []
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()


def merge(existing: list[dict], new: list[dict]) -> list[dict]:
    """Existing rows, with those of the same case_id replaced by the new ones; sorted by case."""
    by_id = {row["case_id"]: row for row in existing}
    by_id.update({row["case_id"]: row for row in new})
    return sorted(by_id.values(), key=lambda r: (r.get("case") if r.get("case") is not None else math.inf,
                                                 r["case_id"]))


def write(rows: list[dict], parameters: list[str], parquet_path: pathlib.Path, csv_path: pathlib.Path) -> None:
    """Writes both files atomically (a temporary file renamed), so an interrupted sweep keeps a valid table."""
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    table = to_arrow(rows, parameters)
    parquet_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = parquet_path.with_suffix(".parquet.tmp")
    pq.write_table(table, tmp)
    tmp.replace(parquet_path)
    tmp = csv_path.with_suffix(".csv.tmp")
    pcsv.write_csv(table, tmp)
    tmp.replace(csv_path)


def plot_summary(rows: list[dict], parameters: list[str], path: pathlib.Path, title: str = "") -> None:
    """Each metric (rows of panels) against each swept parameter (columns); failed cases as red
    crosses on the lower edge of the panels, so they are visible too."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    numeric = []
    for p in parameters:
        vals = [r.get(p) for r in rows if r.get(p) is not None]
        if vals and all(isinstance(v, (int, float)) for v in vals):
            numeric.append(p)
    metrics = [m for m in METRICS if any(r.get(m) is not None and r.get("status") == "ok"
                                         and not (isinstance(r.get(m), float) and math.isnan(r[m])) for r in rows)]
    if not numeric or not metrics:
        numeric = numeric or ["case"]
        metrics = metrics or ["wall_time_s"]
    ok = [r for r in rows if r.get("status") == "ok"]
    failed = [r for r in rows if r.get("status") != "ok"]
    fig, axes = plt.subplots(len(metrics), len(numeric), figsize=(3.2 * len(numeric) + 1.0, 2.3 * len(metrics) + 0.8),
                             squeeze=False, sharex="col")
    labels = {"los_rms_mrad": "LOS RMS [mrad]", "los_peak_mrad": "LOS peak [mrad]", "i_peak_A": "peak |i| [A]",
              "events": "events", "wall_time_s": "wall time [s]"}
    for j, p in enumerate(numeric):
        x_all = np.array([float(r[p]) for r in rows if r.get(p) is not None])
        floats = any(isinstance(r.get(p), float) for r in rows)
        log_x = floats and x_all.size and np.all(x_all > 0) and x_all.max() / x_all.min() >= 10
        for i, m in enumerate(metrics):
            ax = axes[i, j]
            x = np.array([float(r[p]) for r in ok if r.get(p) is not None and r.get(m) is not None])
            y = np.array([float(r[m]) for r in ok if r.get(p) is not None and r.get(m) is not None])
            ax.plot(x, y, ".", ms=3 if len(x) > 200 else 5, alpha=0.5 if len(x) > 200 else 0.9, color="tab:blue")
            levels = np.unique(x)
            if 1 < len(levels) <= 12 and len(x) > len(levels):   # a grid parameter: median per value
                med = [np.nanmedian(y[x == v]) for v in levels]
                ax.plot(levels, med, "-o", color="k", ms=3, lw=1, label="median")
            positive = y[np.isfinite(y) & (y > 0)]
            if m.startswith("los") and positive.size and positive.max() / positive.min() >= 50:
                ax.set_yscale("log")
            xf = [float(r[p]) for r in failed if r.get(p) is not None]
            if xf:
                ax.plot(xf, [0.0] * len(xf), "x", color="tab:red", transform=ax.get_xaxis_transform(), clip_on=False,
                        label=f"failed ({len(failed)})")
                if i == 0 and j == 0:
                    ax.legend(fontsize=7, loc="upper right")
            if log_x:
                ax.set_xscale("log")
            if j == 0:
                ax.set_ylabel(labels.get(m, m), fontsize=8)
            if i == len(metrics) - 1:
                ax.set_xlabel(p, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, alpha=0.3)
    fig.suptitle(title or f"{len(rows)} cases: {len(ok)} ok, {len(failed)} failed", fontsize=10)
    fig.subplots_adjust(left=0.8 / fig.get_figwidth(), right=0.98, bottom=0.6 / fig.get_figheight(),
                        top=1 - 0.45 / fig.get_figheight(), wspace=0.3, hspace=0.12)
    fig.savefig(path, dpi=110)
    plt.close(fig)
