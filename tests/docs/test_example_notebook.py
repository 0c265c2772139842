"""The example notebook runs from top to bottom on the built FMU (executed with nbclient)."""
import os
import pathlib
import shutil

import pytest

pytestmark = pytest.mark.python_bound

REPO = pathlib.Path(__file__).resolve().parents[2]
NOTEBOOK = REPO / "examples" / "gimbal_notebook.ipynb"


@pytest.mark.skipif(os.environ.get("GIMBAL_SANITIZED") == "1",
                    reason="a Jupyter kernel under the preloaded AddressSanitizer runtime tests nothing more")
def test_the_example_notebook_runs(tmp_path, build_dir, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    # Run from a scratch folder, its figures into another: a notebook that wrote beside itself (into
    # examples/ of the checkout) would leave files there.
    shutil.copy(NOTEBOOK, tmp_path / NOTEBOOK.name)
    figures = tmp_path / "figures"
    monkeypatch.setenv("GIMBAL_REPO", str(REPO))
    monkeypatch.setenv("GIMBAL_BUILD_DIR", str(build_dir))
    monkeypatch.setenv("GIMBAL_RESULTS", str(figures))
    notebook = nbformat.read(tmp_path / "gimbal_notebook.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    printed = "".join(output.get("text", "") for cell in notebook.cells if cell.cell_type == "code"
                      for output in cell.outputs)
    assert "LOS error RMS" in printed and f"saved {figures / 'notebook_los_error.png'}" in printed
    assert (figures / "notebook_los_error.png").stat().st_size > 10_000
    assert "DC gain u_R1 -> alpha_dot" in printed and "linear vs simulated gain" in printed
    assert (figures / "notebook_bode.png").stat().st_size > 10_000
    assert "slowest closed-loop pole" in printed and f"saved {figures / 'notebook_isolation.png'}" in printed
    assert (figures / "notebook_isolation.png").stat().st_size > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures", NOTEBOOK.name], "written beside the notebook"


def test_the_notebook_writes_its_figures_under_results_by_default():
    """Run as the README says (from examples/, no environment variables), the figures go to
    results/notebook/ of the repository, which git ignores."""
    import json
    source = "".join("".join(cell["source"]) for cell in json.loads(NOTEBOOK.read_text())["cells"]
                     if cell["cell_type"] == "code")
    assert 'REPO / "results" / "notebook"' in source
    assert "savefig(\"" not in source and 'savefig("' not in source, "a figure saved relative to the working folder"
