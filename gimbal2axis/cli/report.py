"""Compare gyro grades and stabilization schemes on one scene, in one page.

Reads a comparison file (reports/*.toml: a scene, gyro datasheets as [grades.<name>] tables, the
schemes direct and/or indirect, shared [sensors] and [analysis] bands), runs every grade under every
scheme with the same sea and encoders (each case `repeats` times, with its sensor noise drawn anew), and
writes <out>/<name>.html (the table of line-of-sight
RMS, total, per axis and per band, and the figure: the error over time of each case, the PSD and the
cumulative RMS per axis), <out>/<name>.png (the figure) and <out>/<name>.csv (the table).
"""
import pathlib

from ..locations import fmu_path
from .defaults import scene_file
from .failures import run_reporting_failures
from .run import check_output_directory

SUMMARY = "compare gyro grades and direct/indirect stabilization on a scene: one HTML page"
PROG = "gimbal2axis report"
DEFAULT_COMPARISON = pathlib.Path("reports", "gyro_grades_and_schemes.toml")


def add_arguments(parser) -> None:
    parser.epilog = "Errors go to stderr, one line each."
    parser.add_argument("comparison", nargs="?", default=None,
                        help=f"the comparison file (default: {DEFAULT_COMPARISON} in the current directory)")
    parser.add_argument("--fmu", default=None,
                        help="the FMU (default: $GIMBAL2AXIS_FMU, else the build the package was configured with)")
    parser.add_argument("--out", default="results", help="directory for the page, created if missing (default: results/)")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors and warnings (no progress bars, table or list of files)")


def execute(args) -> int:
    return run_reporting_failures(PROG, lambda: _report(args))


def _report(args) -> int:
    # here, not at the top: `gimbal2axis --help` does without numpy, fmpy and matplotlib
    from ..fmu import FMU
    from ..report import load_comparison, run_comparison, write_page
    from ..report.comparison import table_rows

    comparison = load_comparison(scene_file(args.comparison, DEFAULT_COMPARISON,
                                            "the comparison file: gimbal2axis report FILE.toml"))
    out = pathlib.Path(args.out)
    check_output_directory(out, comparison.path.stem)
    with FMU(fmu_path(args.fmu)) as fmu:
        results = run_comparison(comparison, fmu, progress=not args.quiet)
    rows = table_rows(results)
    paths = write_page(comparison, results, rows, out)
    if args.quiet:
        return 0
    for row in rows:
        spread = f" +- {row['los_rms_spread_mrad']:.2g}" if row["runs"] > 1 else ""
        print(f"{row['case']}: LOS error RMS {row['los_rms_mrad']:.4g}{spread} mrad over {row['runs']} run(s), "
              f"max {row['los_max_mrad']:.4g} mrad")
    print(f"wrote {paths['html']}, {paths['png']} and {paths['csv']}")
    return 0
