"""The gimbal among other FMUs: a system of FMUs (a ship-motion FMU, the gimbal FMU, a controller
FMU) described once (structure.py) and written for the engines that run it: an OSP system structure
for libcosim (osp.py) and an SSP archive (ssp.py)."""
from .structure import Component, Connection, System

__all__ = ["Component", "Connection", "System"]
