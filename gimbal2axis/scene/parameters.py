"""A parameter's value in a scene run on an FMU: what the scene sets, else the FMU's start value."""
from __future__ import annotations


def parameter_value(scene, fmu, name: str):
    """A parameter's value in this scene: the scene's, else the FMU's start value."""
    if name in scene.parameters:
        return scene.parameters[name]
    if name in scene.fidelity:
        return scene.fidelity[name]
    return fmu.start(name) if fmu.has(name) else None
