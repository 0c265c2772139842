"""The HTML pages the product writes (tune's report, report's comparison page) show every name a user
gave (a scene's file name, a title, a label, a description) as text, never as markup, and link their
figures by names that resolve to the files written beside them (issue 44, item 14)."""
import html.parser
import pathlib
import subprocess
import sys
import urllib.parse

import pytest

pytestmark = pytest.mark.python_bound

ROOT = pathlib.Path(__file__).resolve().parents[3]
HOSTILE = "a'><script>x"   # a file name: no '/' in it


class Page(html.parser.HTMLParser):
    """The tags of a page and the text of its elements, as a browser would take them."""

    def __init__(self, text: str):
        super().__init__()
        self.tags, self.images, self.text = [], [], []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "img":
            self.images.append(dict(attrs)["src"])

    def handle_data(self, data):
        self.text.append(data)


def assert_no_markup_from_names(page_text: str) -> Page:
    assert "<script" not in page_text
    page = Page(page_text)
    assert "script" not in page.tags
    return page


def test_the_tuning_report_of_a_scene_with_markup_in_its_file_name_shows_it_as_text(tmp_path):
    from test_sweep_failure_paths import write_scene

    scene = write_scene(tmp_path, options="{ gain = 0.0 }", name=HOSTILE)
    tuning = tmp_path / "gains.toml"
    tuning.write_text('description = "<script>alert(1)</script>"\nstop_time = 0.1\n[parameters]\n'
                      '"controller.options.gain" = { bounds = [0.0, 0.5] }\n'
                      '[optimizer]\nsampler = "random"\ntrials = 2\nbatch = 2\n')
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "gimbal2axis", "tune", str(scene), str(tuning), "--serial",
                           "--out", str(out), "--quiet"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    report = out / f"gains__{HOSTILE}_report.html"
    page = assert_no_markup_from_names(report.read_text(encoding="utf-8"))
    assert f"Tuning gains on {HOSTILE}" in "".join(page.text)
    assert "<script>alert(1)</script>" in "".join(page.text)
    assert page.images, "the report shows its figures"
    for source in page.images:   # each a link to a figure written beside the page
        assert (out / urllib.parse.unquote(source)).is_file(), source


def test_a_tuning_or_sweep_name_with_markup_is_refused(tmp_path):
    from gimbal2axis.sweep import SweepError, load_sweep
    from gimbal2axis.tune.spec import TuneError, load_tuning

    tuning, sweep = tmp_path / "tuning.toml", tmp_path / "sweep.toml"
    tuning.write_text(f'name = "{HOSTILE}"\n[parameters]\n"controller.azimuth.kp" = {{ bounds = [1.0, 2.0] }}\n')
    sweep.write_text(f'name = "{HOSTILE}"\n[grid]\n"body2.m" = [1.0]\n')
    with pytest.raises(TuneError, match="'name' must be a string of letters"):
        load_tuning(tuning)
    with pytest.raises(SweepError, match="'name' must be a string of letters"):
        load_sweep(sweep)


def test_the_comparison_page_shows_a_title_labels_and_a_scene_file_name_with_markup_as_text(tmp_path, fmu_path):
    from gimbal2axis import FMU
    from gimbal2axis.report import load_comparison, run_comparison, write_page
    from gimbal2axis.report.comparison import table_rows

    scene = tmp_path / f"{HOSTILE}.toml"
    scene.write_text((ROOT / "scenes" / "ship_stabilization.toml").read_text())
    comparison = tmp_path / f"{HOSTILE} page.toml"
    comparison.write_text(f'scene = "{HOSTILE}.toml"\ntitle = "<script>alert(1)</script>"\n'
                          "description = \"<img src=x onerror='alert(2)'>\"\nstop_time = 0.5\nschemes = [\"direct\"]\n"
                          '[grades.plain]\nlabel = "<script>alert(3)</script>"\n')
    loaded = load_comparison(comparison)
    with FMU(fmu_path) as fmu:
        results = run_comparison(loaded, fmu, progress=False)
    paths = write_page(loaded, results, table_rows(results), tmp_path / "out")
    page = assert_no_markup_from_names(paths["html"].read_text(encoding="utf-8"))
    text = "".join(page.text)
    for shown in ("<script>alert(1)</script>", "<img src=x onerror='alert(2)'>", "<script>alert(3)</script>, direct",
                  f"{HOSTILE}.toml"):
        assert shown in text, shown
    assert [source.startswith("data:image/png;base64,") for source in page.images] == [True]
