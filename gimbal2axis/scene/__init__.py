"""Scenes: a scene file read and validated against the FMU (scene.py), the carrier's motion
(base_motion.py), angle references and set points (references.py, setpoints.py), the built-in and user
controllers (controllers.py), the sensors (sensors.py) and the line-of-sight geometry (geometry.py)."""
from .scene import Scene, check_against_fmu, load_scene, parameter_value, start_values

__all__ = ["Scene", "check_against_fmu", "load_scene", "parameter_value", "start_values"]
