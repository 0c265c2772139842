"""Moving line-of-sight targets (issue 36): a point fixed on the Earth seen from a carrier that
sails, an aircraft's straight flyby, a recorded track (motion.py, read from the scene's [target]
by spec.py); the pointing command by inverse kinematics on the moving carrier with its rates and
accelerations (kinematics.py, pointing()); the tracking metrics (metrics.py). docs/targets.md."""
from __future__ import annotations

import numpy as np

from .kinematics import PointingCommand
from .motion import MovingTarget


def pointing(target: MovingTarget, times, attitude, rates, accelerations=None) -> PointingCommand:
    """The PointingCommand toward `target` at `times` for the base attitude, rates and accelerations
    ((n, 3) each, rows as the base inputs; accelerations None: zero, which leaves the angles and
    their rates exact and only the accelerations without the carrier's angular acceleration). The
    controller's command: the target seen from where its INS places the gimbal (known=True)."""
    u, u_dot, u_ddot, _, _ = target.kinematics(times, known=True)
    attitude = np.asarray(attitude, dtype=float).reshape(-1, 3).T
    rates = np.asarray(rates, dtype=float).reshape(-1, 3).T
    accelerations = np.zeros_like(rates) if accelerations is None else \
        np.asarray(accelerations, dtype=float).reshape(-1, 3).T
    return PointingCommand(u, u_dot, u_ddot, attitude, rates, accelerations)


__all__ = ["MovingTarget", "PointingCommand", "pointing"]
