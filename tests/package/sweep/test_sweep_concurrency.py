"""Sweeps that share an output folder (gimbal2axis/sweep/store.py), run as a user runs them (gimbal2axis
sweep in subprocesses): two sweeps writing one table at once keep every row of both while a reader
polling the table never sees a torn file; a sweep over other parameters whose table would have the
same name is refused before any case runs; an --out that cannot be written is refused in one line,
exit status 2, before any case runs."""
import os
import pathlib
import subprocess
import sys
import threading

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

import pyarrow.csv as pcsv  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402

from gimbal2axis.sweep import store  # noqa: E402
from gimbal2axis.sweep.table import read_rows  # noqa: E402

SCENE = REPO / "scenes" / "ship_stabilization.toml"
SWEEP = [sys.executable, "-m", "gimbal2axis", "sweep"]
STEM = "shared__ship_stabilization"

# The sweep commands in processes of their own: under the preloaded AddressSanitizer runtime they
# test nothing the release pass does not (as in tests/package/sweep/test_sweep_messages.py).
pytestmark = [pytest.mark.dask_workers,
              pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                                 reason="sweep processes under AddressSanitizer test nothing more")]


def sweep_file(tmp_path, file_name, parameter, values):
    """A sweep named "shared" (so every such file writes the table shared__ship_stabilization) over one
    parameter of the ship loop, cases of 0.02 s."""
    path = tmp_path / f"{file_name}.toml"
    path.write_text(f'name = "shared"\nstop_time = 0.02\n[grid]\n"{parameter}" = {values!r}\n')
    return path


def command(fmu_path, sweep, out, *extra):
    return [*SWEEP, str(SCENE), str(sweep), "--fmu", str(fmu_path), "--out", str(out), *extra]


def read_parquet_once(path):
    """As a reader should (docs/sweeps.md): from one open file. pq.read_table(path) opens the path
    several times and mixes two versions of a file replaced in between, however it was written."""
    with open(path, "rb") as file:
        return pq.ParquetFile(file).read()


class TableReader(threading.Thread):
    """Reads the Parquet table and the CSV beside it over and over until stopped; records every read
    that fails to parse, and the row counts of those that parse."""

    def __init__(self, folder: pathlib.Path):
        super().__init__(daemon=True)
        self.parquet, self.csv = folder / f"{STEM}.parquet", folder / f"{STEM}.csv"
        self.stop = threading.Event()
        self.counts: list = []
        self.errors: list = []

    def run(self):
        while not self.stop.is_set():
            for path, read in ((self.parquet, read_parquet_once), (self.csv, pcsv.read_csv)):
                try:
                    self.counts.append(read(path).num_rows)
                except FileNotFoundError:
                    pass   # not written yet
                except Exception as exc:   # a torn or half-written file
                    self.errors.append(f"{path.name}: {type(exc).__name__}: {exc}")


def test_two_sweeps_into_one_table_at_once_keep_every_row_while_a_reader_polls_it(tmp_path, fmu_path):
    out = tmp_path / "out"
    # Two sweep files that name the same table: 16 cases each, 6 of them the same (same values, same
    # scene: the same case ids), so the table must end with the 26 distinct cases of both.
    first = [100.0 + 50.0 * k for k in range(16)]
    second = first[10:] + [2000.0 + 50.0 * k for k in range(10)]
    sweeps = [sweep_file(tmp_path, "first", "controller.azimuth.kp", first),
              sweep_file(tmp_path, "second", "controller.azimuth.kp", second)]
    reader = TableReader(out)
    reader.start()
    # Serial sweeps that save after every case: two writers of one table as often as they can be.
    processes = [subprocess.Popen(command(fmu_path, sweep, out, "--serial", "--save-every", "0"),   # the summary
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
                 for sweep in sweeps]
    try:
        results = [p.communicate(timeout=300) for p in processes]
    finally:
        for p in processes:
            if p.poll() is None:
                p.kill()
        reader.stop.set()
        reader.join(timeout=30)
    for p, (stdout, stderr) in zip(processes, results):
        assert p.returncode == 0, stderr
        assert "16 cases (16 run, 0 already done): 16 ok" in stdout, stdout
    assert reader.errors == [], reader.errors[:3]
    assert max(reader.counts) == 26 and len(set(reader.counts)) > 2   # it saw the table grow, never torn
    rows = read_rows(out / f"{STEM}.parquet")
    assert sorted(r["controller.azimuth.kp"] for r in rows) == sorted(set(first) | set(second))
    assert len({r["case_id"] for r in rows}) == 26 and all(r["status"] == "ok" for r in rows)
    assert pcsv.read_csv(out / f"{STEM}.csv").num_rows == 26
    # no temporary file left behind: only the table, its plot and the lock file
    assert sorted(p.name for p in out.iterdir()) == sorted([f".{STEM}.lock", f"{STEM}.csv", f"{STEM}.parquet",
                                                            f"{STEM}.png"])
    # the same command again finds every case of its sweep done, the other sweep's rows kept
    again = subprocess.run(command(fmu_path, sweeps[0], out, "--serial"), capture_output=True, text=True,
                           cwd=tmp_path, timeout=120)
    assert again.returncode == 0 and "16 cases (0 run, 16 already done)" in again.stdout, again.stderr
    assert len(read_rows(out / f"{STEM}.parquet")) == 26


def test_a_sweep_over_other_parameters_into_the_same_table_is_refused_before_any_case_runs(tmp_path, fmu_path):
    out = tmp_path / "out"
    done = subprocess.run(command(fmu_path, sweep_file(tmp_path, "gains", "controller.azimuth.kp", [200.0, 400.0]),
                                  out, "--serial", "--quiet"), capture_output=True, text=True, cwd=tmp_path,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    before = (out / f"{STEM}.parquet").read_bytes()
    other = sweep_file(tmp_path, "masses", "body2.m", [1.5, 2.5])
    refused = subprocess.run(command(fmu_path, other, out, "--serial"), capture_output=True, text=True, cwd=tmp_path,
                             timeout=120)
    assert refused.returncode == 2
    assert refused.stderr.splitlines() == [
        f"gimbal2axis sweep: error: {out / STEM}.parquet is the table of a sweep over other parameters "
        f"(controller.azimuth.kp; this sweep: body2.m): give this sweep its own name (name = \"...\" in the sweep "
        f"file) or another --out"], refused.stderr
    assert (out / f"{STEM}.parquet").read_bytes() == before


def test_the_claimed_empty_table_refuses_a_sweep_over_other_parameters_started_meanwhile(tmp_path):
    # A sweep claims its table before its first case, so a second one started before any case of
    # the first finished is refused too, not mixed in.
    files = store.TableFiles.of(tmp_path / "out", STEM)
    assert store.claim(files, ["controller.azimuth.kp"]) == []
    assert read_rows(files.parquet) == [] and files.csv.is_file()
    with pytest.raises(store.SweepError, match="sweep over other parameters"):
        store.claim(files, ["body2.m"])
    assert store.claim(files, ["controller.azimuth.kp"]) == []   # the same parameters share it


@pytest.mark.parametrize("where, said", [
    ("under_a_file/out", "a part of the path is a file, not a directory"),
    ("a_file", "exists and is not a directory"),
    ("target_is_a_directory", f"{STEM}.parquet is a directory"),
])
def test_an_out_that_cannot_be_written_is_refused_in_one_line_before_any_case_runs(tmp_path, fmu_path, where, said):
    # Tests may run as root, which writes through any permission bits: paths that no user can write.
    (tmp_path / "under_a_file").write_text("a regular file\n")
    (tmp_path / "a_file").write_text("a regular file\n")
    (tmp_path / "target_is_a_directory" / f"{STEM}.parquet").mkdir(parents=True)
    out = tmp_path / where
    # 400 cases of 60 s: were the folder checked only after the cases, the timeout would end the test
    long_sweep = tmp_path / "long.toml"
    long_sweep.write_text('name = "shared"\nstop_time = 60.0\nsamples = 400\n'
                          '[random]\n"controller.azimuth.kp" = { uniform = [100.0, 1600.0] }\n')
    done = subprocess.run(command(fmu_path, long_sweep, out, "--workers", "2"), capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)
    assert done.returncode == 2
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"gimbal2axis sweep: error: --out {out}: "), done.stderr
    assert said in lines[0] and done.stdout == ""


def test_a_failed_write_leaves_the_published_file_whole_and_no_temporary_file(tmp_path):
    target = tmp_path / "table.csv"
    target.write_text("old\n")

    def half_written_then_failing(path):
        path.write_text("new, but not fin")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        store.publish(target, half_written_then_failing)
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["table.csv"]
    store.publish(target, lambda path: path.write_text("new\n"))
    assert target.read_text() == "new\n" and [p.name for p in tmp_path.iterdir()] == ["table.csv"]
