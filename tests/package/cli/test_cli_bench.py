"""`gimbal2axis bench` says a cost per step that is a difference of two measured times only when it
stands out of the repeats' noise: never a negative cost (issue: "master's own -0.04 us per step")."""
import pytest

from gimbal2axis.cli.bench import cost_text

pytestmark = pytest.mark.python_bound


@pytest.mark.parametrize("cost, noise", [(-0.04, 0.0), (-0.04, 0.3), (0.2, 0.3), (0.0, 0.0)])
def test_a_cost_within_the_noise_is_said_to_be_so(cost, noise):
    text = cost_text(cost, noise)
    assert text.startswith("below the noise"), text
    assert f"{cost:+.2f} us per step measured" in text   # the measurement is kept, as what it is


def test_a_cost_above_the_noise_is_a_number_with_its_noise():
    assert cost_text(9.07, 0.5) == "9.07 us per step (+- 0.50)"


def test_a_scene_with_a_python_controller_is_measured_in_the_python_loop(fmu_path, tmp_path):
    """The README offers bench for "your scene and controller": a Python controller runs in the Python
    loop only (the compiled loop runs the built-in controllers), measured against the FMU alone (its
    commands replayed in the compiled loop), its master's own cost with the controller's in it."""
    import json
    import pathlib
    import subprocess
    import sys

    scene = pathlib.Path(__file__).resolve().parents[3] / "examples" / "user_controller.toml"
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "bench", str(scene), "--fmu", str(fmu_path),
                           "--stop-time", "0.2", "--repeat", "1", "--out", str(tmp_path / "bench.json")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    figures = json.loads((tmp_path / "bench.json").read_text())
    assert figures["controller"] == "python" and "compiled" not in figures
    python = figures["python"]
    assert python["loop_cpu_s"] > 0 and python["replay_cpu_s"] > 0 and figures["fmu_alone_cpu_s"] > 0
    assert "python loop" in done.stdout and "compiled loop" not in done.stdout
    assert "with the Python controller" in done.stdout, done.stdout
