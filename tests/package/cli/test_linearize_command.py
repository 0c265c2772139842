"""gimbal2axis linearize: the files it writes, a scene's point at a time of its run, and its refusals."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[3]


def linearize(build_dir, *args):
    return subprocess.run([sys.executable, "-m", "gimbal2axis", "linearize", "--build-dir", str(build_dir), *args],
                          capture_output=True, text=True, timeout=300)


def test_writes_the_matrices_and_a_bode_plot(build_dir, tmp_path):
    out = linearize(build_dir, "--set", "gear1.model=0", "--set", "motor1.model=0", "--set", "dry_friction=false",
                    "--set", "base.fixed=true", "--out", str(tmp_path / "azimuth.npz"), "--bode", "u_R1:alpha_dot",
                    "--bode", "u_R2:los.omega[1]")
    assert out.returncode == 0, out.stderr
    assert "poles [1/s]" in out.stdout and "states: alpha, beta" in out.stdout
    with np.load(tmp_path / "azimuth.npz") as data:
        n = len(data["states"])
        assert data["A"].shape == (n, n) and data["B"].shape == (n, 17) and data["C"].shape == (17, n)
        assert "alpha_m" not in data["states"].tolist()
    bode = (tmp_path / "azimuth_bode.csv").read_text().splitlines()
    assert bode[0] == "input,output,frequency_hz,gain,gain_db,phase_deg" and len(bode) == 1 + 2 * 400
    assert (tmp_path / "azimuth_bode.png").stat().st_size > 10_000


def test_a_scene_is_linearized_where_its_run_is(build_dir, fmu_path, tmp_path):
    out = linearize(build_dir, "--scene", str(REPO / "scenes" / "ship_stabilization.toml"), "--at-time", "0.05",
                    "--fmu", str(fmu_path), "--out", str(tmp_path / "ship.mat"))
    assert out.returncode == 0, out.stderr
    assert "linear model at t = 0.05 s: 12 states" in out.stdout
    from scipy.io import loadmat

    mat = loadmat(tmp_path / "ship.mat")
    assert mat["A"].shape == (12, 12) and abs(float(mat["time"].squeeze()) - 0.05) < 1e-12


def test_refusals_name_the_culprit_without_a_traceback(build_dir, fmu_path, tmp_path):
    cases = [
        (["--set", "motor1.R=-1"], "motor1.R"),
        (["--set", "motor1.R"], "expected NAME=VALUE"),
        (["--at-time", "1"], "--at-time needs --scene"),
        (["--scene", str(REPO / "scenes" / "ship_stabilization.toml"), "--at-time", "0.01", "--fmu", str(fmu_path),
          "--set", "motor1.R=3"], "only inputs can be changed"),
        (["--out", str(tmp_path / "m.txt")], "write .npz or .mat"),
        (["--bode", "u_R1:nothing"], "--bode 'u_R1:nothing'"),
        (["--bode", "u_R1"], "expected INPUT:OUTPUT"),
        (["--bode", "u_R1:alpha_dot", "--fmin", "0"], "need 0 < fmin <= fmax"),
        (["--scene", str(REPO / "scenes" / "ship_stabilization.toml"), "--at-time", "0.0005", "--fmu",
          str(fmu_path)], "--at-time 0.0005: not a whole number"),
        (["--scene", str(REPO / "scenes" / "ship_stabilization.toml"), "--at-time", "-1"], "need a positive time"),
        (["--set", "gear1.model=1.5"], "is not a whole number"),
        (["--set", "motor1.RR=3"], "--set: 'motor1.RR' is not a variable of the gimbal model (did you mean 'motor1.R'"),
        (["--scene", str(REPO / "scenes" / "ship_stabilization.toml"), "--at-time", "0.01", "--fmu", str(fmu_path),
          "--set", "u_R11=3"], "(did you mean 'u_R1'"),
    ]
    for args, message in cases:
        out = linearize(build_dir, *args)
        assert out.returncode == 2, args
        assert message in out.stderr and "Traceback" not in out.stderr, (args, out.stderr)
        assert "linearize: linearize:" not in out.stderr and out.stderr.startswith("gimbal2axis linearize: error: ")
        assert len(out.stderr.splitlines()) == 1, out.stderr
    assert not (tmp_path / "m.txt").exists()
