"""A scene with a sea state and a built-in controller as a system of three FMUs: the ship-motion FMU
(the scene's sea state, and a moving target's position from the gimbal as a table in its resources),
the gimbal FMU (the scene's fidelity, parameters and start values, as the
scene runner sets them) and the controller FMU (the scene's controller, target and sensors), each
input connected to the output of the same name, and the OSP variable groups connected group to
group. In an engine that steps every FMU from the values of the communication point before (Jacobi:
libcosim, FMPy), the voltage computed at t_k acts over [t_k+1, t_k+2]: the scene's delay_steps = 1."""
from __future__ import annotations

import pathlib

import numpy as np

from ..errors import SceneError
from ..scene.drives import scene_drives
from ..fmu import FMU
from ..scene import parameter_value, start_values
from ..scene.controller_fmu import controller_fmu_parameters
from ..scene.ship_motion_fmu import TARGET_TABLE, ship_motion_fmu_parameters, target_table
from .structure import Component, Connection, System


def component_name(role: str) -> str:
    """A component's name in the system: its role and `_unit`, a word no variable of the three FMUs
    has in its name, so no importer takes a segment of a bound name for the component
    (structure.naming_conflicts says why that matters; write_ssp checks it)."""
    return f"{role}_unit"


SHIP, GIMBAL, CONTROLLER = (component_name(role) for role in ("ship_motion", "gimbal", "controller"))
FMUS = {SHIP: "Gimbal2Axis-ShipMotion.fmu", GIMBAL: "Gimbal2Axis.fmu", CONTROLLER: "Gimbal2Axis-Controller.fmu"}
CARRIER_GROUPS = ["carrier_attitude", "carrier_attitude_rate", "carrier_attitude_acceleration", "carrier_velocity",
                  "carrier_acceleration"]
GROUPS = [(SHIP, g, GIMBAL, g) for g in CARRIER_GROUPS] + \
    [(SHIP, g, CONTROLLER, g) for g in ("carrier_attitude", "carrier_attitude_rate",
                                             "carrier_attitude_acceleration", "target_position", "target_velocity",
                                             "target_acceleration")] + \
    [(GIMBAL, g, CONTROLLER, g) for g in ("gimbal_angles", "gimbal_rates", "line_of_sight_rate")] + \
    [(CONTROLLER, f"motor{j}_voltage", GIMBAL, f"motor{j}_voltage") for j in (1, 2)]


def _description(fmu_path: pathlib.Path, fmu: FMU) -> pathlib.Path | None:
    """<modelName>_OspModelDescription.xml beside the FMU (where the build puts it), if there."""
    path = fmu_path.parent / f"{fmu.model_description.modelName}_OspModelDescription.xml"
    return path if path.is_file() else None


# The gimbal's current commands act only with motor<j>.drive = current; the controller FMU commands
# voltages, so a system of these FMUs drives the motors by voltage and leaves them at their start.
VOLTAGE_DRIVE_UNUSED = {(GIMBAL, "i_R1_cmd"), (GIMBAL, "i_R2_cmd")}


def _connections(fmus: dict) -> list[Connection]:
    """Every input of the gimbal and the controller from the output of the same name (the ship's
    first, then the gimbal's, then the controller's); an input nobody gives is refused."""
    outputs = {name: [v.name for v in fmu.model_description.modelVariables if v.causality == "output"]
               for name, fmu in fmus.items()}
    connections = []
    for target in (GIMBAL, CONTROLLER):
        for variable in fmus[target].model_description.modelVariables:
            if variable.causality != "input" or (target, variable.name) in VOLTAGE_DRIVE_UNUSED:
                continue
            source = next((s for s in (SHIP, GIMBAL, CONTROLLER) if s != target and variable.name in outputs[s]),
                          None)
            if source is None:
                raise SceneError(f"the system has no output for the {target}'s input {variable.name}")
            connections.append(Connection(source, variable.name, target, variable.name))
    return connections


def ship_system(scene, fmu_dir: pathlib.Path, stop_time: float | None = None) -> System:
    """The system of `scene` with the FMUs of `fmu_dir` (the build directory)."""
    if scene.delay_steps != 1:
        raise SceneError(f"a co-simulation engine applies the voltage one step later (delay_steps = 1); the scene "
                         f"has delay_steps = {scene.delay_steps}")
    paths = {name: pathlib.Path(fmu_dir) / file for name, file in FMUS.items()}
    missing = [str(p) for p in paths.values() if not p.is_file()]
    if missing:
        raise SceneError(f"missing FMU(s): {', '.join(missing)} (build them: cmake --build build)")
    stop_time = scene.stop_time if stop_time is None else stop_time
    fmus = {name: FMU(path) for name, path in paths.items()}
    try:
        _check_voltage_drives(scene, fmus[GIMBAL])
        values, resources = _start_values(scene, fmus[GIMBAL], stop_time)
        components = [Component(name, paths[name], values[name], _description(paths[name], fmus[name]),
                                resources[name]) for name in FMUS]
        connections = _connections(fmus)
    finally:
        for fmu in fmus.values():
            fmu.close()
    described = all(c.osp_description is not None for c in components)
    return System(scene.name, scene.step_size, stop_time, components, connections, GROUPS if described else [])


def _check_voltage_drives(scene, gimbal) -> None:
    current = [drive.motor for drive in scene_drives(scene, gimbal) if drive.kind == "current"]
    if current:
        # (and libcosim, the engine of the OSP structure, sets no FMI 2.0 Enumeration such as motor<j>.drive)
        raise SceneError(f"{scene.name}: motor{current[0]}.drive = current, but the controller FMU commands "
                         f"voltages (u_R1, u_R2): a system of these FMUs runs voltage-driven motors only; run "
                         f"the scene with `gimbal2axis run`")


def _start_values(scene, gimbal, stop_time: float) -> tuple:
    """({component: {variable: start value}}, {component: {resource file: bytes}})."""
    motion = scene.base_motion()
    base = motion.sample(np.array([0.0, 1e-6]))
    gimbal_values = start_values(scene, gimbal, base[0], base[1])
    u_limit = tuple(float(parameter_value(scene, gimbal, f"motor{j}.U_L")) for j in (1, 2))
    values = {SHIP: ship_motion_fmu_parameters(scene), GIMBAL: gimbal_values,
              CONTROLLER: controller_fmu_parameters(scene, u_limit)}
    resources = {name: {} for name in FMUS}
    if scene.moving_target is not None:
        # the target's position from the gimbal, tabulated for the run, in the ship-motion FMU's
        # resources: its target outputs feed the controller's target inputs
        values[SHIP]["target"] = 1
        resources[SHIP][TARGET_TABLE] = target_table(scene, stop_time, scene.step_size)
    return values, resources
