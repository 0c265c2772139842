"""The FMU as the master sees it: extracted once, variables by name (the model description is the
truth: names it does not have are refused), typed setters, a fresh FMU2Slave per run."""
from __future__ import annotations

import math
import pathlib
import shutil
import tempfile

from .errors import SceneError

FIDELITY = ["gear1.model", "gear2.model", "motor1.model", "motor2.model", "dry_friction", "base.fixed"]
STATES = ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot",
          "i_R1", "i_R2", "theta_b1", "theta_b2"]


class FMU:
    def __init__(self, path: pathlib.Path | str, workdir: pathlib.Path | str | None = None):
        from fmpy import extract, read_model_description

        self.path = pathlib.Path(path)
        if not self.path.is_file():
            raise SceneError(f"{self.path}: no such FMU (build it: cmake --build build, or bash scripts/setup.sh)")
        self.md = read_model_description(str(self.path))
        self.unzipdir = extract(str(self.path), unzipdir=tempfile.mkdtemp(prefix="gimbal_scene_", dir=workdir))
        self.variables = {v.name: v for v in self.md.modelVariables}

    def close(self) -> None:
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def vr(self, name: str) -> int:
        return self.variables[name].valueReference

    def start(self, name: str):
        v = self.variables[name]
        if v.start is None:
            return None
        return {"Real": float, "Integer": int, "Boolean": lambda s: str(s).lower() in ("true", "1")}[v.type](v.start)

    def has(self, name: str) -> bool:
        return name in self.variables

    def check(self, where: str, values: dict, causalities: set) -> None:
        """Refuses names the FMU does not have, of the wrong causality, or values of the wrong type."""
        for name, value in values.items():
            v = self.variables.get(name)
            if v is None:
                raise SceneError(f"[{where}] '{name}' is not a variable of {self.path} (its modelDescription.xml "
                                 f"is the truth; is the FMU older than the scene?)")
            if v.causality not in causalities:
                raise SceneError(f"[{where}] '{name}' has causality '{v.causality}', expected {sorted(causalities)}")
            if v.type == "Real":
                ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            elif v.type == "Integer":
                ok = isinstance(value, int) and not isinstance(value, bool)
            elif v.type == "Boolean":
                ok = isinstance(value, bool)
            else:
                ok = False
            if not ok:
                raise SceneError(f"[{where}] '{name}' is {v.type} in the FMU; got {value!r}")

    def set(self, slave, values: dict) -> None:
        """Sets Real, Integer and Boolean variables by name with the setter of their type."""
        groups = {"Real": ([], [], slave.setReal, float), "Integer": ([], [], slave.setInteger, int),
                  "Boolean": ([], [], slave.setBoolean, bool)}
        for name, value in values.items():
            refs, vals, _, cast = groups[self.variables[name].type]
            refs.append(self.vr(name))
            vals.append(cast(value))
        for refs, vals, setter, _ in groups.values():
            if refs:
                setter(refs, vals)

    def instantiate(self, name: str = "scene", log: list | None = None):
        from fmpy import fmi2
        from fmpy.fmi2 import FMU2Slave

        slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                          modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        callbacks = None
        if log is not None:
            def logger(env, instance, status, category, message):
                log.append(f"[{category.decode()}] {message.decode().replace('%%', '%')}")
            callbacks = fmi2.fmi2CallbackFunctions()
            callbacks.logger = fmi2.fmi2CallbackLoggerTYPE(logger)
            callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
            callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
            slave._scene_callbacks = callbacks   # must outlive the instance
        slave.instantiate(callbacks=callbacks)
        return slave
