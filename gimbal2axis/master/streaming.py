"""A scene run streamed to disk: what `gimbal2axis run` does, in memory bounded by a chunk of steps
whatever the run's length.

master.run holds the whole run (its inputs prepared up front, its record returned in memory), which
the sweeps, the reports and the tests want for their short runs; an hour at 1 ms is 3.6 million rows
of about 60 signals, 1.7 GB of record and more of inputs. Here the run is made CHUNK_ROWS
communication points at a time, with the same loops and the same bits:

- the base motion, the sensors' noise (each random draw of Sensors.prepare from a generator placed
  at its start, scene/sensors.py SensorStream) and the controller's set points of a chunk only, all
  elementwise or carried over from the chunk before, so equal to the rows of the whole run's;
- the loop (stepper.py: the compiled one for built-in controllers, else the Python one) on the
  chunk's tables (plan.StreamPlan): the C kernel indexes by the run's step, and reads a chunk's rows
  through shifted addresses; each chunk's record goes to a RecordSink;
- each chunk's record (its derived line-of-sight signals included, RunResult's) appended to
  <name>.parquet (one row group per chunk: a columnar file, so the plots and spectra read back only
  the columns they need) and its rows at the output interval to <name>.csv;
- the summary's metrics accumulated chunk by chunk; the spectra by Welch over the file read back a
  chunk at a time (spectra.WelchAccumulator); the plots from the file decimated to the minimum and
  maximum of each pixel column (plots never drop an extreme).

A run that fails, or is asked to stop (a StopRequest: SIGINT, SIGTERM), ends its files at the last
whole communication point and says so (StreamedResult.stopped; <name>_run.json; the Parquet file's
metadata "gimbal2axis.status").
"""
from __future__ import annotations

import math
import pathlib
import shutil
import time

import numpy as np

from ..errors import SceneError, StopSignal
from ..fmu import FMU
from ..progress import Progress
from ..scene.base_motion import INPUTS as BASE_INPUTS
from ..scene.scene import TRACKING_SIGNALS, Scene
from . import spectra
from .memory import available_memory, size_text
from .plan import StreamPlan
from .stepper import RecordWriteFailed, choose_loop, start, step_run
from .stopping import StopRequest
from .record_files import RunRecord, record_tables
from .results import AXIS_ERRORS, CARRIER_RATES, ISOLATION_AXES, ClampCount, RunResult

# Communication points per chunk: 2^14 rows of ~60 doubles are 7.9 MB of record, some 50 MB with
# their copies (the columns, Arrow's table, the CSV's rows): the ship scene's hour stays under 300 MB
# (docs/benchmarks.md). A row group per chunk: 220 for the hour, whose metadata the file carries.
# The compiled loop returns to Python every CHUNK_STEPS (stepper.py) within a chunk to show progress
# and see a stop.
CHUNK_ROWS = 1 << 14
# Pixel columns the plots' signals are decimated to (the figure is 1200 pixels wide at 100 dpi):
# per column the minimum and the maximum, so no extreme is lost.
PLOT_COLUMNS = 2000
# The widest a %.12g number and its comma can be in the CSV: sign, 12 digits, point, e-308, comma.
CSV_FIELD_BYTES = 20


class Metrics:
    """What the summary line needs of the line-of-sight error and the last row, accumulated chunk by
    chunk (results.RunResult.los_metrics over the whole record, with sums in chunk order), and the
    means over the metrics window the spectra remove."""

    def __init__(self, window_start: float, spectral: list[str], tracking=None):
        self.window_start = window_start
        self.tracking = tracking   # a target.metrics.TrackingMetrics with a moving target, else None
        self.sum_squares = {"window": 0.0, "all": 0.0}
        self.count = {"window": 0, "all": 0}
        self.maximum = {"window": -math.inf, "all": -math.inf}
        self.sums = {name: {"window": 0.0, "all": 0.0} for name in spectral}
        self.base_moves = False
        self.last = {}
        self.first_in_window = None   # the window's first sample's time

    def add(self, columns: dict) -> None:
        t = columns["time"]
        window = t >= self.window_start - 1e-12
        if self.first_in_window is None and window.any():
            self.first_in_window = float(t[window][0])
        e = columns["los_error"]
        for part, mask in (("window", window), ("all", slice(None))):
            values = e[mask]
            self.sum_squares[part] += float(np.sum(values ** 2))
            self.count[part] += int(values.size)
            if values.size:
                self.maximum[part] = max(self.maximum[part], float(np.max(values)))
            for name, sums in self.sums.items():
                sums[part] += float(np.sum(columns[name][mask]))
        if "base.delta_dot" in columns:
            self.base_moves = self.base_moves or any(np.any(columns[f"base.{n}_dot"] != 0)
                                                     for n in ("delta", "psi", "gamma"))
        self.last = {name: float(values[-1]) for name, values in columns.items()}
        if self.tracking is not None:
            self.tracking.add(columns)

    def part(self) -> str:
        """"window" when the window holds samples (RunResult: else the whole run)."""
        return "window" if self.count["window"] else "all"

    def mean(self, name: str) -> float:
        part = self.part()
        return self.sums[name][part] / self.count[part]


class StreamedResult(RunResult):
    """A RunResult whose record is on disk: `signals` holds the plots' signals decimated to the
    minimum and maximum per pixel column (exact when the run has fewer points than that), the
    summary's metrics and the spectra come from the chunks and the file (Metrics,
    spectra.WelchAccumulator). `parquet_path`: the whole record."""

    def __init__(self, scene, signals: dict, wall_time: float, stop_time: float, metrics: Metrics,
                 spectra_found: dict, isolation: dict, carrier_psd: dict, window_times: tuple):
        self.scene, self.signals, self.wall_time, self.stop_time = scene, signals, wall_time, stop_time
        self.stopped, self.requested_stop_time = None, stop_time
        self.derived = {}
        self.metrics, self._spectra, self._isolation, self.carrier_psd = metrics, spectra_found, isolation, carrier_psd
        self.window_times = window_times

    @property
    def base_moves(self) -> bool:
        return self.metrics.base_moves

    def final(self, name: str) -> float | None:
        return self.metrics.last.get(name)

    def los_metrics(self, from_s: float | None = None) -> dict:
        m, part = self.metrics, self.metrics.part()
        return {"final": m.last["los_error"], "rms": math.sqrt(m.sum_squares[part] / m.count[part]),
                "max": m.maximum[part], "from_s": m.window_start,
                "rms_all": math.sqrt(m.sum_squares["all"] / m.count["all"])}

    def los_spectra(self, from_s: float | None = None) -> dict:
        return self._spectra

    def isolation_estimates(self) -> dict:
        return self._isolation

    def carrier_spectrum(self, i: int) -> np.ndarray:
        return self.carrier_psd[i]

    def window_bounds(self) -> tuple[float, float]:
        return self.window_times

    def tracking_metrics(self):
        return self.metrics.tracking


def record_needs(plan: StreamPlan, columns: int) -> tuple[int, int]:
    """(bytes on disk at most, bytes in memory) of a streamed run of `plan` with `columns` signals:
    the Parquet file uncompressed (8 bytes a value: noise does not compress), the CSV at its widest,
    and in memory the chunk's tables, its copies as columns, Parquet and CSV rows, and the same again
    for the spectra's and plots' reading back."""
    rows = plan.n + 1
    csv_rows = rows // max(1, int(round(plan.scene.output_interval / plan.h))) + 2
    disk = rows * columns * 8 + csv_rows * columns * CSV_FIELD_BYTES
    memory = 4 * plan.chunk_rows * columns * 8
    return disk, memory


def column_count(plan: StreamPlan, scene: Scene) -> int:
    """The record's signals: time, outputs, modes, commands (applied, commanded, asked) and set points, base
    inputs and heave,
    and the derived line-of-sight signals (RunResult)."""
    derived = 5 + (len(AXIS_ERRORS) if scene.target_spec is not None else 0) + \
        (len(TRACKING_SIGNALS) if scene.moving_target is not None else 0) + \
        (len(CARRIER_RATES) if not plan.motion.fixed else 0)
    return 1 + len(plan.real_names) + len(plan.mode_names) + 8 + len(BASE_INPUTS) + 1 + derived


def check_fits(plan: StreamPlan, scene: Scene, out: pathlib.Path) -> None:
    """Refuses, before the run, a record the disk under `out` (or the chunk the memory) cannot hold."""
    disk, memory = record_needs(plan, column_count(plan, scene))
    free = shutil.disk_usage(out).free
    steps = f"{plan.n + 1:,} points ({plan.t_end:g} s at {plan.h:g} s)"
    if disk > free:
        raise SceneError(f"{scene.name}: the record of {steps} needs up to {size_text(disk)} on disk, {out} has "
                         f"{size_text(free)} free; shorten the run (--stop-time) or lengthen step_size")
    available = available_memory()
    if available is not None and memory > available:
        raise SceneError(f"{scene.name}: a chunk of {plan.chunk_rows:,} points needs {size_text(memory)} of memory, "
                         f"{size_text(available)} is available")


def _derived_columns(scene: Scene, signals: dict, base_moving: bool) -> dict:
    """The chunk's record with RunResult's derived signals, in the CSV's column order."""
    result = RunResult(scene, signals, 0.0, 0.0)
    columns = {name: np.asarray(result.signal(name), dtype=float) for name in result.csv_columns()}
    if base_moving and not result.derived.keys() & set(CARRIER_RATES):
        # a chunk where the carrier stands still: RunResult leaves its rates out, the file keeps its columns
        attitude = [signals[f"base.{n}"] for n in ("psi", "gamma")]
        rates = [signals[f"base.{n}_dot"] for n in ("delta", "psi", "gamma")]
        from ..scene import geometry
        columns.update(zip(CARRIER_RATES, geometry.carrier_rate_in_payload(signals["alpha"], signals["beta"],
                                                                           *attitude, *rates)))
    return columns


def plot_names(scene: Scene, names: list[str]) -> list[str]:
    """The record's columns the plots may draw: every one of plotting.default_panels (which drops some
    once it sees the data: no set points, no target) and of the scene's [plot]."""
    from .plotting import default_panels

    probe = RunResult.__new__(RunResult)   # default_panels asks only for names and the scene
    probe.scene, probe.signals, probe.derived = scene, {name: np.zeros(1) for name in names}, {}
    panels = default_panels(probe)
    panels.update(scene.plot)
    wanted = {"time", "los_error", "alpha_ref"} | {name for signals in panels.values() for name in signals}
    return [name for name in names if name in wanted]


class Decimator:
    """The plots' signals as the chunks come, decimated to PLOT_COLUMNS pixel columns over [0, t_end]:
    per column its minimum and maximum, drawn at its first and last sample's time, so no extreme is
    lost; every sample when the run has at most two per column."""

    def __init__(self, names: list[str], t_end: float, rows: int):
        self.names, self.plotted = names, [name for name in names if name != "time"]
        self.exact = rows <= 2 * PLOT_COLUMNS
        self.kept = {name: [] for name in names}
        self.edges = np.linspace(0.0, t_end, PLOT_COLUMNS + 1)
        self.low = {name: np.full(PLOT_COLUMNS, np.nan) for name in self.plotted}
        self.high = {name: np.full(PLOT_COLUMNS, np.nan) for name in self.plotted}
        self.first_time, self.last_time = np.full(PLOT_COLUMNS, np.nan), np.full(PLOT_COLUMNS, np.nan)

    def add(self, columns: dict) -> None:
        if self.exact:
            for name in self.names:
                self.kept[name].append(np.asarray(columns[name], dtype=float).copy())
            return
        t = columns["time"]
        pixel = np.clip(np.searchsorted(self.edges, t, side="right") - 1, 0, PLOT_COLUMNS - 1)
        starts = np.flatnonzero(np.r_[True, pixel[1:] != pixel[:-1]])
        where = pixel[starts]
        self.first_time[where] = np.fmin(self.first_time[where], t[starts])
        self.last_time[where] = np.fmax(self.last_time[where], t[np.r_[starts[1:] - 1, len(t) - 1]])
        for name in self.plotted:
            values = columns[name]
            self.low[name][where] = np.fmin(self.low[name][where], np.fmin.reduceat(values, starts))
            self.high[name][where] = np.fmax(self.high[name][where], np.fmax.reduceat(values, starts))

    def signals(self) -> dict:
        if self.exact:
            return {name: np.concatenate(parts) if parts else np.empty(0) for name, parts in self.kept.items()}
        used = np.flatnonzero(np.isfinite(self.first_time))   # a run that stopped early fills fewer columns
        signals = {"time": np.column_stack([self.first_time[used], self.last_time[used]]).ravel()}
        for name in self.plotted:
            signals[name] = np.column_stack([self.low[name][used], self.high[name][used]]).ravel()
        return signals


def spectra_from_file(parquet_path: pathlib.Path, scene: Scene, metrics: Metrics, h: float, has_target: bool):
    """The Welch accumulators of the line-of-sight error's spectra and of the isolation estimate over
    the metrics window, fed from the file a row group (a chunk) at a time, its spectral columns only;
    None where there is nothing to estimate."""
    samples = metrics.count[metrics.part()]
    psd_names = list(AXIS_ERRORS) if has_target else []
    isolation_names = ([CARRIER_RATES[i - 1] for i in ISOLATION_AXES] + [f"los.omega[{i}]" for i in ISOLATION_AXES]) \
        if metrics.base_moves else []
    if samples < 2 or not psd_names + isolation_names:
        return None, None
    pairs = [(CARRIER_RATES[i - 1], f"los.omega[{i}]") for i in ISOLATION_AXES]
    psd = _welch(h, scene.analysis.psd_resolution_hz, samples, metrics, psd_names)
    isolation = _welch(h, scene.analysis.isolation_resolution_hz, samples, metrics, isolation_names, pairs)
    _feed_from_file(parquet_path, metrics, [accumulator for accumulator in (psd, isolation) if accumulator is not None])
    return psd, isolation


def _welch(h: float, resolution: float, samples: int, metrics: Metrics, names: list, pairs=()):
    """A Welch accumulator of `names` (their means over the window removed), None without names."""
    if not names:
        return None
    means = {name: metrics.mean(name) for name in names}
    return spectra.WelchAccumulator(1.0 / h, resolution, samples, means, pairs)


def _feed_from_file(parquet_path: pathlib.Path, metrics: Metrics, accumulators: list) -> None:
    """Feeds the accumulators their columns over the metrics window, read a row group at a time."""
    window_start = metrics.window_start if metrics.part() == "window" else -math.inf
    wanted = ["time"] + [name for accumulator in accumulators for name in accumulator.means]
    for batch in record_tables(parquet_path, wanted):
        columns = {name: batch.column(name).to_numpy() for name in wanted}
        del batch
        window = columns["time"] >= window_start - 1e-12
        for accumulator in accumulators:
            accumulator.feed({name: columns[name][window] for name in accumulator.means})


def release_freed_memory() -> None:
    """Hands the memory freed by a phase (the chunks' tables, Arrow's buffers) back to the system
    before the next: the allocators keep it otherwise, and the phases' peaks would add up."""
    import ctypes
    import ctypes.util

    import pyarrow as pa

    pa.default_memory_pool().release_unused()
    name = ctypes.util.find_library("c")
    if name:
        libc = ctypes.CDLL(name)
        if hasattr(libc, "malloc_trim"):   # glibc
            libc.malloc_trim(0)


def record_for(scene: Scene, out: pathlib.Path, stop_time: float | None, stop: StopRequest | None) -> RunRecord:
    """The RunRecord a streamed run of `scene` writes into `out`."""
    t_end = scene.stop_time if stop_time is None else stop_time
    every = max(1, int(round(scene.output_interval / scene.step_size)))
    return RunRecord(out, scene.name, every, {"scene": scene.name, "stop_time_s": t_end,
                                               "step_size_s": scene.step_size}, stop)


class RecordSink:
    """Where a streamed run's chunks go (stepper.step_run's sink): each chunk's record, with its derived
    line-of-sight signals (RunResult's), appended to the RunRecord; the summary's metrics, the clamp
    count and the plots' decimated signals accumulated from it."""

    def __init__(self, scene: Scene, plan: StreamPlan, record: RunRecord):
        self.scene, self.record = scene, record
        self.metrics = Metrics(float(scene.requirements.get("from_s", 0.0)), spectral_names(scene, plan.motion.fixed),
                               tracking_metrics(scene))
        self.clamp = ClampCount(plan.drives)
        self.decimator = None

    def add(self, plan: StreamPlan, first: int, recorded: int) -> BaseException | None:
        """None when the chunk's points are kept; else why not: a StopSignal (a repeated signal before the
        chunk was written), a RecordWriteFailed (a full disk, say: the record ends at its last whole chunk).
        Another scene's files where this one's would go (check_no_collision) raise SceneError."""
        try:
            columns = _derived_columns(self.scene, plan.chunk_signals(recorded), not plan.motion.fixed)
            self.record.append(first, columns, plan.h)
        except SceneError:
            raise
        except StopSignal as signal:
            return signal
        except Exception as exc:
            return RecordWriteFailed(exc, first * plan.h)
        self.metrics.add(columns)
        self.clamp.add(plan.u_asked[:recorded], plan.u_cmd[plan.delay:plan.delay + recorded])
        if self.decimator is None:
            self.decimator = Decimator(plot_names(self.scene, list(columns)), plan.t_end, plan.n + 1)
        self.decimator.add(columns)
        return None

    def abandon(self, message: str) -> None:
        """The run failed before its first point: if the first chunk could not be written, the earlier
        run's files are gone, and _run.json says why."""
        if self.record.taken_over:
            self.record.close_without_merge()
            self.record.write_status({"status": "failed", "partial": True, "recorded_until_s": None,
                                      "reason": message, "files": []})


def spectral_names(scene: Scene, fixed_base: bool) -> list[str]:
    """The columns whose means over the metrics window the spectra remove."""
    return (list(AXIS_ERRORS) if scene.target_spec is not None else []) + \
        ([] if fixed_base else [CARRIER_RATES[i - 1] for i in ISOLATION_AXES] +
         [f"los.omega[{i}]" for i in ISOLATION_AXES])


def tracking_metrics(scene: Scene):
    """A target.metrics.TrackingMetrics with a moving target, else None."""
    if scene.moving_target is None:
        return None
    from ..target.metrics import TrackingMetrics
    return TrackingMetrics(scene.target_spec["beam_width_mrad"], scene.target_spec["keyhole_deg"],
                           scene.step_size, float(scene.requirements.get("from_s", 0.0)))


def run_streamed(scene: Scene, fmu: FMU, out: pathlib.Path, progress: bool = False, stop_time: float | None = None,
                 controller=None, compiled: bool | None = None, stop: StopRequest | None = None,
                 chunk_rows: int = CHUNK_ROWS, record: RunRecord | None = None) -> StreamedResult:
    """Runs `scene` chunk by chunk, writing <out>/<name>.parquet and <name>.csv as it goes (a RunRecord:
    record_files.py); returns a StreamedResult (for the summary, plots and spectra). A failure in the
    loop (the FMU's, the controller's, a full disk's) or a `stop` request ends the files at the last
    whole chunk or point and the result says so (stopped); a failure before the first point (or at
    initialization) raises SceneError and leaves an earlier run's files as they were, as does a run
    the disk cannot hold. The result's wall_time is the run's whole: preparing, stepping, writing."""
    wall0 = time.perf_counter()
    stop = stop or StopRequest()
    plan = StreamPlan(scene, fmu, stop_time, controller, chunk_rows)
    check_fits(plan, scene, out)
    loop = choose_loop(plan.controller, compiled)
    sink = RecordSink(scene, plan, record or record_for(scene, out, stop_time, stop))
    stopped = _step_streamed(scene, fmu, plan, loop, sink, stop, progress)
    record, metrics = sink.record, sink.metrics
    end = plan.t_end if stopped is None else stopped.time
    status = {"status": "complete" if stopped is None else stopped.kind, "partial": stopped is not None,
              "stop_time_s": plan.t_end, "recorded_until_s": end, "reason": None if stopped is None else stopped.reason}
    stop.stepping, stop.phase = False, "finishing the record"   # a signal from here on raises at once
    record.close(status)
    record.write_status({**status, "files": [record.csv_path.name, record.parquet_path.name]})
    wall = time.perf_counter() - wall0
    del plan   # the chunk's tables
    release_freed_memory()
    if record.pending_signal is not None:   # a signal while merging: the folder of chunks is the record
        raise record.pending_signal
    if stop.kind is not None and (stop.signals > 1 or stopped is None):   # a signal the loop did not see
        stop.raise_stop()
    stop.phase = "computing the spectra and drawing the plots"
    found, estimates, carrier = streamed_spectra(record.parquet_path, scene, metrics)
    t_window = (metrics.first_in_window if metrics.part() == "window" else 0.0, end)
    result = StreamedResult(scene, sink.decimator.signals(), wall, end, metrics, found, estimates, carrier, t_window)
    result.stopped, result.requested_stop_time = stopped, status["stop_time_s"]
    result.loop, result.parquet_path, result.csv_path = loop, record.parquet_path, record.csv_path
    result.status = status
    result.voltage_clamp = sink.clamp
    return result


def _step_streamed(scene: Scene, fmu: FMU, plan: StreamPlan, loop: str, sink: RecordSink, stop: StopRequest,
                   progress: bool):
    """The streamed run's instance made, started and stepped into `sink` (stepper.step_run): its Stop, or
    None for a whole run. From here to the record's end, a first signal asks the run to end at its next
    step (stop.stepping)."""
    log: list = []
    slave = fmu.instantiate(scene.name, log)
    bar = Progress(plan.t_end, enabled=progress)
    stop.stepping = True
    try:
        plan.load_chunk(0, plan.chunk_rows)
        start(slave, scene, fmu, plan, log)
        return step_run(scene, plan, slave, log, loop, sink, stop, bar)
    except BaseException:
        stop.stepping = False
        raise
    finally:
        slave.freeInstance()


def streamed_spectra(parquet_path: pathlib.Path, scene: Scene, metrics: Metrics) -> tuple[dict, dict, dict]:
    """The line-of-sight error's spectra, the isolation estimates and the carrier's spectra from the
    record's file (the plots' signals were decimated as the chunks came)."""
    psd, isolation = spectra_from_file(parquet_path, scene, metrics, scene.step_size, scene.target_spec is not None)
    release_freed_memory()
    found = {name: psd.spectrum(name) for name in AXIS_ERRORS} if psd is not None and psd.segments else {}
    estimates, carrier = {}, {}
    if isolation is not None and isolation.segments:
        for i in ISOLATION_AXES:
            estimates[i] = isolation.transfer(CARRIER_RATES[i - 1], f"los.omega[{i}]")
            carrier[i] = isolation.spectrum(CARRIER_RATES[i - 1]).psd
    return found, estimates, carrier
