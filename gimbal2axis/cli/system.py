"""Write a scene as a system of FMUs for other co-simulation engines.

The scene's sea state becomes the ship-motion FMU (with a moving target's position from the gimbal
as a table in its resources), its built-in controller (with its target and sensors) the controller FMU, and with the gimbal FMU they make one
system, written into the scene's own folder <out>/<scene>/ as an OSP system structure
(osp/OspSystemStructure.xml with the three FMUs and their OSP model descriptions: run it with libcosim
or the OSP tools) and as an SSP archive (<scene>.ssp: FMPy, OMSimulator). Each scene has its own folder
because the FMUs differ (a moving target's table is in the ship-motion FMU's resources); the folder
records the scene file it was written from (SOURCE_RECORD), and a scene file of the same name from
elsewhere is refused there rather than replacing the other's system. In either engine the voltage
computed at t_k acts over [t_k+1, t_k+2], the scene's delay_steps = 1. docs/systems.md says what each
engine gives and how it differs from `gimbal2axis run`.
"""
import pathlib

from ..errors import SceneError
from .failures import run_reporting_failures

SUMMARY = "write a scene as a system of FMUs: OSP system structure (libcosim) and SSP archive"
PROG = "gimbal2axis system"


def add_arguments(parser) -> None:
    parser.epilog = "Errors go to stderr, one line each."
    parser.add_argument("scene", help="the scene file (a sea state, a built-in controller, delay_steps = 1)")
    parser.add_argument("--build-dir", default=None,
                        help="where the three FMUs were built (default: the folder of the FMU that `run` finds: "
                             "$GIMBAL2AXIS_FMU, else the build that configured the package)")
    parser.add_argument("--out", default="results/systems",
                        help="directory to write into, the scene's system in <out>/<scene>/ (default: results/systems/)")


SOURCE_RECORD = "written_from.txt"   # in <out>/<scene>/: the scene file's resolved path


def claim_folder(folder: pathlib.Path, scene_file: pathlib.Path) -> None:
    """Makes `folder` the system folder of `scene_file`, or refuses: it holds the system of another scene
    file of the same name (its FMUs, structure and archive would be replaced without a word)."""
    record = folder / SOURCE_RECORD
    source = str(scene_file.resolve())
    if record.is_file():
        earlier = record.read_text(encoding="utf-8").strip()
        if earlier != source:
            raise SceneError(f"{folder} holds the system of another scene file, {earlier}; writing {source} there "
                             f"would replace it: give this one another --out")
    elif folder.is_dir() and any(folder.iterdir()):
        raise SceneError(f"{folder} is not empty and holds no system of gimbal2axis system ({SOURCE_RECORD}): "
                         f"give another --out")
    folder.mkdir(parents=True, exist_ok=True)
    record.write_text(source + "\n", encoding="utf-8")


def _write(args) -> int:
    # here, not at the top: `gimbal2axis --help` does without numpy and fmpy
    from ..scene import load_scene
    from ..system.from_scene import ship_system
    from ..system.osp import write_osp
    from ..system.ssp import write_ssp
    from ..locations import fmu_directory

    scene = load_scene(args.scene)
    system = ship_system(scene, fmu_directory(args.build_dir))
    folder = pathlib.Path(args.out) / scene.name
    claim_folder(folder, pathlib.Path(args.scene))
    try:
        structure = write_osp(system, folder / "osp")
        archive = write_ssp(system, folder / f"{scene.name}.ssp")
    except ValueError as exc:   # what libcosim cannot set; a component name an SSP importer would misread
        raise SceneError(str(exc)) from None
    print(f"wrote {structure} (with the FMUs and their OSP model descriptions) and {archive}")
    return 0


def execute(args) -> int:
    return run_reporting_failures(PROG, lambda: _write(args))
