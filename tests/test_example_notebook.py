"""The example notebook runs from top to bottom on the built FMU (executed with nbclient)."""
import os
import pathlib
import shutil

import pytest

REPO = pathlib.Path(__file__).resolve().parents[1]
NOTEBOOK = REPO / "examples" / "gimbal_notebook.ipynb"


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="a Jupyter kernel under the preloaded AddressSanitizer runtime tests nothing more")
def test_the_example_notebook_runs(tmp_path, build_dir, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    # In a scratch folder: the notebook saves its figure where it runs.
    shutil.copy(NOTEBOOK, tmp_path / NOTEBOOK.name)
    monkeypatch.setenv("GIMBAL_REPO", str(REPO))
    monkeypatch.setenv("GIMBAL_BUILD_DIR", str(build_dir))
    notebook = nbformat.read(tmp_path / "gimbal_notebook.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    printed = "".join(output.get("text", "") for cell in notebook.cells if cell.cell_type == "code"
                      for output in cell.outputs)
    assert "LOS error RMS" in printed and "saved notebook_los_error.png" in printed
    assert (tmp_path / "notebook_los_error.png").stat().st_size > 10_000
    assert "DC gain u_R1 -> alpha_dot" in printed and "linear vs simulated gain" in printed
    assert (tmp_path / "notebook_bode.png").stat().st_size > 10_000
    assert "slowest closed-loop pole" in printed and "saved notebook_isolation.png" in printed
    assert (tmp_path / "notebook_isolation.png").stat().st_size > 10_000
