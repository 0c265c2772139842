"""gimbal2axis: scenes, a co-simulation master, analyses and sweeps for the Gimbal2Axis FMU, and the
`gimbal2axis` command (subcommands run, sweep, tune, linearize, freqresp, report, system, bench; `python -m
gimbal2axis`).

    from gimbal2axis import FMU, load_scene, run
    with FMU("build/Gimbal2Axis.fmu") as fmu:
        result = run(load_scene("scenes/free_swing.toml"), fmu)

Layout, and the one direction imports go (tests/layout/test_package_layout.py refuses any other):

    cli                      the command and its subcommands, one module each
     -> tune                 tuning gains with Optuna over the sweep engine
     -> sweep | analysis     sweeps on Dask | linearization, frequency responses, isolation prediction
     -> master               the co-simulation loop (Python, compiled, lockstep), results, plots
     -> scene                scene files, base motion, references, controllers, sensors, geometry
     -> target               moving targets: geodesy (pymap3d), target and inverse kinematics, tracking metrics
     -> fmu                  the FMU wrapper, an FMU kept per worker
     -> errors, version, progress, native, locations    leaves: error types, the version, progress bars, the C kernels
                                               (the extension gimbal2axis.native._native, compiled from
                                               the repository's c_kernel/),
                                               where the build is

A module imports from its own subpackage and from the layers below it, never from above or from its
sibling (sweep and analysis do not import each other); this file imports only the public API below, and
all but the leaves (errors, version) on first use, so that a subcommand imports only what it needs.

Where the FMU and libgimbal_probe.so (the linearization's library) are: `--fmu` (linearize:
`--build-dir`), else $GIMBAL2AXIS_FMU and $GIMBAL2AXIS_PROBE_LIBRARY, else gimbal2axis/build_locations.json,
which configuring the repository's CMake build writes; nothing is found by looking around the source
tree (gimbal2axis.locations says more). Default files of the commands (a scene, an output directory)
are paths relative to the current directory, as in the repository's root: `gimbal2axis run` runs
scenes/free_swing.toml there and writes results/.
"""
from .errors import SceneError
from .version import __version__

__all__ = ["__version__", "SceneError", "FMU", "Scene", "load_scene", "check_against_fmu", "run", "run_scene_file"]


def __getattr__(name: str):
    """The public API's heavier names (numpy, fmpy and the C kernels behind them), imported on first
    use: `gimbal2axis --help` and `--version` import this package too, and answer without them."""
    if name == "FMU":
        from .fmu import FMU as found
    elif name in ("run", "run_scene_file"):
        from . import master
        found = getattr(master, name)
    elif name in ("Scene", "check_against_fmu", "load_scene"):
        from . import scene
        found = getattr(scene, name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = found   # the next look-up is an ordinary one
    return found


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
