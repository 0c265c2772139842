"""A scene run's files on disk, written so that no way of ending loses what was computed and
<name>_run.json always says what the files beside it hold.

A run touches nothing of an earlier run of its scene until it has recorded its first chunk: a run
refused at its parameters, its controller's reset() or its first step leaves the earlier record and
its _run.json as they were. Then it takes the name over (RunRecord.take_over): first <name>_run.json
says "running" (with the process's id), then the earlier run's files go, and the record is written
as it comes:

- <name>.parquet is, while the run goes, a folder of Parquet files, one per chunk
  (part-000000.parquet, ...), each written under a hidden name and renamed when whole: pyarrow,
  pandas, polars and DuckDB read the folder as one table, and a run killed at any moment (SIGKILL,
  the OOM killer) leaves every chunk it finished readable. When the run ends, however it ends, the
  chunks are merged into one file with a row group per chunk, which replaces the folder in one
  rename. Where the disk cannot hold the merged file beside the chunks, or the merge is interrupted,
  the folder stays the record, and _run.json says so ("parquet_layout": "folder").
- <name>.csv grows by whole rows: a chunk's rows go in one write, and a write that fails (a full
  disk) is cut back to the last whole row.
- <name>_run.json is written aside and renamed, after each chunk: "running" and where the record
  ends, so a killed run's says how far its files go.
- A reserve of RESERVE_BYTES is held while the run writes and given back before its last files, so a
  disk that fills up still takes the final _run.json and the CSV's last row.
"""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import datetime
import io
import json
import os
import pathlib
import re
import shutil

import numpy as np

from . import units

# The files a run of scene <name> writes beside its record, by suffix: all are an earlier run's once
# a new run of the scene takes the name over.
DERIVED_SUFFIXES = (".png", "_psd.csv", "_isolation.csv", "_spectrum.png", "_tracking.png")
RECORD_SUFFIXES = (".csv", ".parquet", "_run.json")
RESERVE_BYTES = 1 << 20
CHUNK_FILE = "part-{:06d}.parquet"
STATUS_SUFFIX = "_run.json"


def run_files(name: str) -> set[str]:
    """Every file a run of scene `name` may write (its record, _run.json, its plots and spectra)."""
    return {f"{name}{suffix}" for suffix in RECORD_SUFFIXES + DERIVED_SUFFIXES}


def check_no_collision(out: pathlib.Path, name: str) -> None:
    """Refuses a run of scene `name` into `out` where one of its files is a file of another scene's run
    there (scene `a`'s a_psd.csv is scene `a_psd`'s record): every run's _run.json marks the scene's
    files as its own before any is written, so two scenes never share a file, whichever came first."""
    from ..errors import SceneError, excerpt

    mine = run_files(name)
    for status in out.glob(f"*{STATUS_SUFFIX}"):
        other = status.name[:-len(STATUS_SUFFIX)]
        if other == name:
            continue
        shared = sorted(run_files(other) & mine)
        if shared:
            raise SceneError(f"scene {excerpt(name)!r} would write {excerpt(shared[0])} in {out}, a file of scene "
                             f"{excerpt(other)!r} whose run is there ({status.name}): give this run another --out (or "
                             "move that run's files away)")


@contextlib.contextmanager
def folder_lock(out: pathlib.Path):
    """The folder's lock while a run claims its scene's files (check_no_collision and its _run.json
    written as one step): two scenes starting at once into one folder see each other. The folder itself
    is locked (flock on its descriptor), so no lock file is left in it; where folders cannot be opened
    (Windows), a hidden lock file."""
    if os.name == "nt":
        import msvcrt
        with open(out / ".gimbal2axis.folder.lock", "a+b") as handle:
            msvcrt.locking(handle.fileno(), msvcrt.LK_LOCK, 1)
            yield
        return
    import fcntl

    descriptor = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)   # the lock goes with it


def write_atomically(path: pathlib.Path, data: bytes) -> None:
    """`path` holds `data` whole or is as it was: written under a hidden name beside it, then renamed."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(temporary, "wb") as file:
            file.write(data)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def is_record_folder(path: pathlib.Path) -> bool:
    """A folder of a run's chunks (a run in progress, or one killed before its merge), which the next run
    of the scene replaces; any other folder of that name is the user's and stays untouched."""
    if not path.is_dir() or path.is_symlink():
        return False
    chunk = re.compile(r"^\.?part-\d{6}\.parquet(\.tmp)?$")
    return all(chunk.match(entry.name) and entry.is_file() for entry in path.iterdir())


def remove_path(path: pathlib.Path) -> None:
    """Removes a file or a folder (a record's chunks) at `path`, if there is one."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def exchange(a: pathlib.Path, b: pathlib.Path) -> bool:
    """Swaps the two paths in one step (Linux's renameat2 with RENAME_EXCHANGE: a folder for a file
    included); False where the system has no such call."""
    name = ctypes.util.find_library("c")
    if os.name != "posix" or not name:
        return False
    libc = ctypes.CDLL(name, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:
        return False
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    error = ctypes.get_errno()
    if error in (22, 38, 95):   # EINVAL, ENOSYS, EOPNOTSUPP: a file system or kernel without the exchange
        return False
    raise OSError(error, os.strerror(error), str(b))


def record_tables(path: pathlib.Path, columns: list[str] | None = None):
    """The record at `path` (the merged file or the folder of chunks) a chunk at a time, as pyarrow
    tables of `columns` (all when None), in time order."""
    import pyarrow.parquet as pq

    if path.is_dir():
        for part in sorted(path.glob("part-*.parquet")):
            yield pq.read_table(part, columns=columns, use_threads=False)
        return
    file = pq.ParquetFile(path)
    for group in range(file.num_row_groups):
        yield file.read_row_group(group, columns=columns, use_threads=False)


def record_columns(path: pathlib.Path, names) -> dict:
    """The record's columns of `names` that it has, as numpy arrays over the whole record."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    first = min(path.glob("part-*.parquet")) if path.is_dir() else path
    available = set(pq.read_schema(first).names)
    table = pa.concat_tables(record_tables(path, [name for name in names if name in available]))
    return {name: table.column(name).to_numpy() for name in table.column_names}


class RunRecord:
    """<out>/<name>.parquet, <name>.csv and <name>_run.json of one run, written as the chunks come.
    `status` is what _run.json says besides the state of the files (the scene, the stop time asked
    for, the step size); `stop`: the run's master.StopRequest, whose shield keeps a signal from
    cutting a file's write in half."""

    def __init__(self, out: pathlib.Path, name: str, every: int, status: dict, stop=None):
        self.out, self.name, self.every, self.base_status, self.stop = out, name, every, dict(status), stop
        self.parquet_path, self.csv_path = out / f"{name}.parquet", out / f"{name}.csv"
        self.status_path, self.reserve_path = out / f"{name}_run.json", out / f".{name}.run.reserve"
        self.names, self.csv_file, self.chunks, self.schema = None, None, 0, None
        self.csv_whole_bytes = 0   # the CSV's length up to its last whole row
        self.last_row, self.last_written, self.last_step = None, None, None
        self.recorded_until = None
        self.layout, self.layout_reason = "folder", None

    @property
    def taken_over(self) -> bool:
        return self.names is not None

    def shield(self):
        return self.stop.shield() if self.stop is not None else contextlib.nullcontext()

    def write_status(self, state: dict) -> None:
        """<name>_run.json: the run's status with the state of its files; the process's id while running."""
        self.last_state = dict(state)
        document = {**self.base_status, **state, "parquet_layout": self.layout}
        if self.layout_reason:
            document["parquet_layout_reason"] = self.layout_reason
        if document.get("status") == "running":
            document["pid"] = os.getpid()
        write_atomically(self.status_path, (json.dumps(document, indent=1) + "\n").encode())

    def take_over(self, names: list[str]) -> None:
        """The first chunk is here: _run.json says running, the earlier run's files go, the new ones start."""
        with folder_lock(self.out):
            check_no_collision(self.out, self.name)
            self.write_status({"status": "running", "partial": True, "recorded_until_s": None, "reason": None,
                               "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                               "files": [self.csv_path.name, self.parquet_path.name]})
        if self.stop is not None:
            self.stop.record_status_path = self.status_path
        for path in [self.parquet_path, self.csv_path] + [self.out / f"{self.name}{s}" for s in DERIVED_SUFFIXES]:
            remove_path(path)
        for stale in self.out.glob(f".{self.name}.parquet.*"):   # a killed run's merge
            remove_path(stale)
        self.reserve()
        self.parquet_path.mkdir()
        self.csv_file = open(self.csv_path, "wb", buffering=0)
        self.names = names
        self.write_csv(units.csv_header(names) + "\n")

    def reserve(self) -> None:
        try:
            with open(self.reserve_path, "wb") as file:
                if hasattr(os, "posix_fallocate"):
                    os.posix_fallocate(file.fileno(), 0, RESERVE_BYTES)
                else:
                    file.truncate(RESERVE_BYTES)
        except OSError:   # a disk already full: the run goes on without, as far as it can
            self.reserve_path.unlink(missing_ok=True)

    def write_csv(self, text: str) -> None:
        """Appends whole rows, or nothing: a failed write is cut back to the last whole row."""
        data, written = text.encode(), 0
        try:
            while written < len(data):
                written += self.csv_file.write(data[written:])
        except BaseException:
            with contextlib.suppress(OSError):
                os.ftruncate(self.csv_file.fileno(), self.csv_whole_bytes)
            raise
        self.csv_whole_bytes += len(data)

    def append(self, first: int, columns: dict, h: float) -> None:
        """A chunk of rows first .. first + count - 1: a Parquet file of its own in the folder, its rows at
        the output interval in the CSV, and _run.json's end of the record; all three or none (a chunk
        that cannot be written whole is taken back out of the files)."""
        with self.shield():
            if not self.taken_over:
                self.take_over(list(columns))
            csv_before, part = self.csv_whole_bytes, None
            try:
                part = self.write_chunk(columns)
                count = len(columns["time"])
                rows = np.flatnonzero(np.arange(first, first + count) % self.every == 0)
                # the CSV's rows and the chunk's last (the run's last row when it is the last chunk)
                picked = rows if rows.size and rows[-1] == count - 1 else np.r_[rows, count - 1]
                data = np.column_stack([np.asarray(columns[name], dtype=float)[picked] for name in self.names])
                if rows.size:
                    text = io.StringIO()
                    np.savetxt(text, data[:rows.size], delimiter=",", fmt="%.12g")
                    self.write_csv(text.getvalue())
                until = (first + count - 1) * h
                self.write_status({"status": "running", "partial": True, "recorded_until_s": until,
                                   "reason": None, "files": [self.csv_path.name, self.parquet_path.name]})
            except BaseException:
                if part is not None:
                    part.unlink(missing_ok=True)
                    self.chunks -= 1
                if self.csv_whole_bytes != csv_before:
                    with contextlib.suppress(OSError):
                        os.ftruncate(self.csv_file.fileno(), csv_before)
                    self.csv_whole_bytes = csv_before
                raise
            if rows.size:
                self.last_written = first + rows[-1]
            self.last_row, self.last_step, self.recorded_until = data[-1:].copy(), first + count - 1, until

    def write_chunk(self, columns: dict) -> pathlib.Path:
        """The chunk's Parquet file in the folder, whole: written under a hidden name, then renamed."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.table({name: columns[name] for name in self.names})
        if self.schema is None:
            self.schema = units.with_units(table.schema)
        table = pa.Table.from_arrays(table.columns, schema=self.schema)
        part = self.parquet_path / CHUNK_FILE.format(self.chunks)
        hidden = self.parquet_path / f".{part.name}.tmp"
        try:
            pq.write_table(table, hidden, use_dictionary=False, row_group_size=len(table))
            os.replace(hidden, part)
        except BaseException:
            hidden.unlink(missing_ok=True)
            raise
        self.chunks += 1
        return part

    def close(self, status: dict) -> None:
        """Ends the record: the CSV's last row (when the output interval skipped it), the chunks merged
        into one file (or left as the folder, said in `layout`), the reserve given back. _run.json is the
        caller's to write next (write_status), with the files it then has."""
        if not self.taken_over:
            return
        self.reserve_path.unlink(missing_ok=True)
        with self.shield():
            if self.last_written != self.last_step:
                text = io.StringIO()
                np.savetxt(text, self.last_row, delimiter=",", fmt="%.12g")
                with contextlib.suppress(OSError):   # a full disk: the CSV ends at its last whole row
                    self.write_csv(text.getvalue())
                    self.last_written = self.last_step
            self.csv_file.close()
        self.merge(status)

    def close_without_merge(self) -> None:
        """Ends the CSV and leaves the chunks' folder as the record (a signal came before the merge)."""
        self.layout_reason = "a signal ended the run before its chunks were merged into one file"
        self.reserve_path.unlink(missing_ok=True)
        with self.shield():
            self.csv_file.close()

    def merge(self, status: dict) -> None:
        """The folder of chunks as one Parquet file, a row group per chunk, with the run's status in its
        metadata; the folder stays where the disk has no room for the file beside it, or on a failure or
        a signal (a signal is raised again once the folder is whole and said to be the record)."""
        import pyarrow.parquet as pq

        chunk_bytes = sum(part.stat().st_size for part in self.parquet_path.glob("part-*.parquet"))
        if shutil.disk_usage(self.out).free < chunk_bytes + RESERVE_BYTES:
            self.layout_reason = (f"the disk under {self.out} has no room for the merged file "
                                  f"({chunk_bytes / 1e6:.3g} MB) beside the chunks")
            return
        merged = self.out / f".{self.name}.parquet.merging"
        writer = None
        try:
            for table in record_tables(self.parquet_path):
                if writer is None:
                    writer = pq.ParquetWriter(merged, table.schema, use_dictionary=False)
                writer.write_table(table, row_group_size=len(table))
            writer.add_key_value_metadata({"gimbal2axis.status": json.dumps(status)})
            writer.close()
            writer = None
            with self.shield():
                if exchange(merged, self.parquet_path):
                    remove_path(merged)   # now the folder
                else:
                    folder = self.out / f".{self.name}.parquet.chunks"
                    os.replace(self.parquet_path, folder)
                    os.replace(merged, self.parquet_path)
                    remove_path(folder)
                self.layout, self.layout_reason = "file", None
        except BaseException as exc:
            if writer is not None:
                with contextlib.suppress(Exception):
                    writer.close()
            merged.unlink(missing_ok=True)
            self.layout_reason = f"merging the chunks into one file failed: {type(exc).__name__}"
            if not isinstance(exc, Exception):   # a signal: the folder is the record, said by the caller
                self.pending_signal = exc
            elif not isinstance(exc, OSError):
                raise

    pending_signal = None
    last_state: dict = {}
