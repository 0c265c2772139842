"""The results table on disk, safe for several sweeps at once (two commands into one --out, a sweep
and a reader of its table).

- Every update of a table happens under an exclusive lock on the file `.<stem>.lock` beside it (an
  advisory flock, held only for the read-merge-write of one save, never while cases run).
- Each save re-reads the table under the lock and merges this sweep's rows into it (keyed by case_id:
  its parameter values, the scene's content, the stop time and the metrics window), so the rows that
  another sweep saved meanwhile stay.
- Each file (Parquet, CSV, the summary plot) is written to a temporary file of a unique name in the
  same folder and then renamed over the old one (os.replace, atomic on one file system): a reader sees
  the old table or the new one, never a torn file.
- A table belongs to one set of swept parameters (its columns), recorded in the Parquet metadata. A
  sweep over other parameters whose table would have the same name is refused before any case runs
  (rows of two different sweeps in one table would have the other sweep's parameters missing); the
  first sweep claims a table by writing it, empty, before its first case, which also proves that the
  output folder and its files can be written.
- A temporary file left by a writer that was killed (SIGKILL, out of memory) is removed by the next
  save or claim in that folder once it is provably nobody's: a temporary of the table's Parquet or CSV
  found while holding the table's lock (only lock holders write those), or any temporary whose name
  says it was made by a process of this host that no longer runs (`.<file>.<pid>@<host>.<token>.tmp`).
"""
from __future__ import annotations

import contextlib
import json
import os
import pathlib
import re
import secrets
import socket
import sys
from dataclasses import dataclass

from . import table
from .spec import SweepError

PARAMETERS_KEY = b"gimbal2axis.sweep.parameters"   # Parquet schema metadata: the swept parameters, a JSON list
# This machine in the names of the temporary files it writes: a pid says whether the writer still runs
# only on the host that gave it (an output folder may be shared by several machines).
HOST = re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:40] or "host"
# What follows `.<file>.` in the name of a temporary file of publish (or of an earlier version, without @host).
TEMPORARY_TAIL = re.compile(r"\d+(@[A-Za-z0-9-]+)?\.[0-9a-f]{12}\.tmp")
# The end of the name of any temporary file of publish: its writer's pid and host.
WRITER = re.compile(r"\.(?P<pid>\d+)@(?P<host>[A-Za-z0-9-]+)\.[0-9a-f]{12}\.tmp$")


@dataclass(frozen=True)
class TableFiles:
    """Where the table of a sweep lives: `<out>/<stem>.parquet`, `.csv`, `.png`, and its lock file."""
    parquet: pathlib.Path
    csv: pathlib.Path
    png: pathlib.Path
    lock: pathlib.Path

    @classmethod
    def of(cls, out_dir, stem: str) -> "TableFiles":
        out = pathlib.Path(out_dir)
        return cls(out / f"{stem}.parquet", out / f"{stem}.csv", out / f"{stem}.png", out / f".{stem}.lock")

    @property
    def folder(self) -> pathlib.Path:
        return self.parquet.parent


@contextlib.contextmanager
def locked(files: TableFiles):
    """Holds the table's lock (exclusive; blocks while another process holds it). The lock file stays:
    removing it would let a process that opened it before the removal lock a file nobody else sees."""
    handle = open(files.lock, "a+b")
    try:
        _lock(handle)
        try:
            yield
        finally:
            _unlock(handle)
    finally:
        handle.close()


if sys.platform == "win32":   # pragma: no cover - exercised on Windows only
    import msvcrt

    def _lock(handle) -> None:
        handle.seek(0)
        while True:
            try:   # LK_LOCK gives up after 10 s; waiting longer is right for a save of another sweep
                msvcrt.locking(handle.fileno(), msvcrt.LK_LOCK, 1)
                return
            except OSError:
                continue

    def _unlock(handle) -> None:
        handle.seek(0)
        msvcrt.locking(handle.fileno(), msvcrt.LK_UNLCK, 1)
else:
    import fcntl

    def _lock(handle) -> None:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX)

    def _unlock(handle) -> None:
        fcntl.flock(handle.fileno(), fcntl.LOCK_UN)


def publish(path: pathlib.Path, write) -> None:
    """Calls write(temporary path) for a new temporary file beside `path`, then renames it over `path`:
    readers see the old file or the new one, whole. The temporary file has a unique name, so writers
    never share one; it is removed if writing fails."""
    temporary = _new_file(path.parent, f".{path.name}.", ".tmp")
    try:
        write(temporary)
        with open(temporary, "rb") as written:   # on disk before the name points at it (a crash keeps a whole file)
            os.fsync(written.fileno())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _new_file(folder: pathlib.Path, prefix: str, suffix: str) -> pathlib.Path:
    """Creates an empty file of a name no other process uses (O_EXCL), with the permissions of any new
    file (0666 less the umask; tempfile.mkstemp would make it 0600, and the table private)."""
    while True:
        path = folder / f"{prefix}{os.getpid()}@{HOST}.{secrets.token_hex(6)}{suffix}"
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            return path
        except FileExistsError:
            continue


def remove_stale_temporaries(files: TableFiles) -> list[pathlib.Path]:
    """Removes the temporary files in the table's folder that no writer can still be writing (see the
    module's doc): those of the table's Parquet and CSV (call under the table's lock), and those of a
    process of this host that has ended. Returns the paths removed."""
    try:
        names = os.listdir(files.folder)
    except OSError:
        return []
    removed = []
    for name in names:
        if name.endswith(".tmp") and _stale(name, files):
            path = files.folder / name
            try:
                path.unlink()
            except FileNotFoundError:
                continue
            except OSError:   # not ours to remove (another user's folder entry): left as it is
                continue
            removed.append(path)
    return removed


def _stale(name: str, files: TableFiles) -> bool:
    for written_under_lock in (files.parquet, files.csv):
        prefix = f".{written_under_lock.name}."
        if name.startswith(prefix) and TEMPORARY_TAIL.fullmatch(name[len(prefix):]):
            return True
    writer = WRITER.search(name)
    return (name.startswith(".") and writer is not None and writer.group("host") == HOST
            and _process_ended(int(writer.group("pid"))))


def _process_ended(pid: int) -> bool:
    """Whether no process of this id runs on this host (a pid that was reused counts as running)."""
    if sys.platform == "win32" or pid <= 0:   # os.kill would end a process there, not probe it
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError):   # PermissionError: it runs, as another user
        return False
    return False


def check_folder(files: TableFiles, option: str = "--out") -> None:
    """Creates the output folder and checks that the table's files can be written there (none of them a
    directory, the folder writable); SweepError in one line otherwise. Runs before any case."""
    folder = files.folder
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise SweepError(f"{option} {folder}: exists and is not a directory") from None
    except NotADirectoryError:
        raise SweepError(f"{option} {folder}: a part of the path is a file, not a directory") from None
    except OSError as exc:
        raise SweepError(f"{option} {folder}: cannot create the directory ({exc.strerror or exc})") from None
    for target in (files.parquet, files.csv, files.png, files.lock):
        if target.is_dir():
            raise SweepError(f"{option} {folder}: {target.name} is a directory; the sweep writes a file of that name "
                             f"there (remove the directory, or choose another {option})")
    try:   # the lock file, which every save opens, and a new file (the temporary files of a save)
        files.lock.touch(exist_ok=True)
        _new_file(folder, ".write_test.", "").unlink()
    except OSError as exc:
        raise SweepError(f"{option} {folder}: cannot write there ({exc.strerror or exc})") from None


@dataclass
class StoredTable:
    rows: list
    parameters: list | None   # the swept parameters the table records; None: no table yet


def read(files: TableFiles) -> StoredTable:
    """The table's rows and its swept parameters (call under the lock for a consistent view)."""
    import pyarrow as pa

    try:
        with open(files.parquet, "rb") as file:
            stored = table.read_parquet(file)
    except FileNotFoundError:
        return StoredTable([], None)
    except (pa.ArrowException, OSError) as exc:
        reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise SweepError(f"{files.parquet} is not a readable sweep table ({reason}); move it away or choose another "
                         f"--out") from None
    metadata = stored.schema.metadata or {}
    if PARAMETERS_KEY in metadata:
        parameters = json.loads(metadata[PARAMETERS_KEY])
    else:   # a table written before the parameters were recorded: its columns that are neither metadata nor results
        parameters = [name for name in stored.column_names if not table.is_result_or_key(name)]
    return StoredTable(stored.to_pylist(), parameters)


def _comparable(parameters) -> set:
    """The parameters as a table's columns show them: a swept `stop_time`, say, shares its column with
    the case's stop time."""
    return {name for name in parameters if not table.is_result_or_key(name)}


def claim(files: TableFiles, parameters: list[str]) -> list[dict]:
    """Before any case runs: the table's rows, if the table exists and is one of a sweep over the same
    parameters (SweepError in one line if not), or a new empty table with these parameters, written so
    that a sweep over other parameters started meanwhile is refused, not mixed in."""
    check_folder(files)
    with locked(files):
        remove_stale_temporaries(files)
        stored = read(files)
        if stored.parameters is None:
            write(files, [], parameters)
            return []
        if _comparable(stored.parameters) != _comparable(parameters):
            raise SweepError(f"{files.parquet} is the table of a sweep over other parameters "
                             f"({', '.join(stored.parameters) or 'none'}; this sweep: {', '.join(parameters)}): "
                             f"give this sweep its own name (name = \"...\" in the sweep file) or another --out")
        return stored.rows


def save(files: TableFiles, rows: list[dict], parameters: list[str]) -> list[dict]:
    """Merges `rows` (this sweep's, replacing those of the same case_id) into the table as it is on
    disk now, under the lock, and writes it; returns the table's rows."""
    with locked(files):
        remove_stale_temporaries(files)
        stored = read(files)
        merged = table.merge(stored.rows, rows)
        recorded = list(parameters)
        if stored.parameters is not None and _comparable(stored.parameters) != _comparable(parameters):
            # Only if the claimed table was removed and another sweep claimed it while this one ran:
            # its rows and ours are both kept, under the union of the parameters.
            recorded = list(dict.fromkeys(list(stored.parameters) + recorded))
            print(f"sweep: warning: {files.parquet} was replaced by the table of a sweep over other parameters "
                  f"while this one ran; it now holds the rows of both", file=sys.stderr)
        write(files, merged, recorded)
        return merged


def write(files: TableFiles, rows: list[dict], parameters: list[str]) -> None:
    """Writes the Parquet table (the parameters in its metadata) and then the CSV, each published
    atomically. Call under the lock."""
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    arrow = table.to_arrow(rows, parameters)
    arrow = arrow.replace_schema_metadata({**(arrow.schema.metadata or {}),
                                           PARAMETERS_KEY: json.dumps(list(parameters)).encode()})
    publish(files.parquet, lambda path: pq.write_table(arrow, path))
    publish(files.csv, lambda path: pcsv.write_csv(arrow, path))
