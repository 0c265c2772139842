"""The scale that puts a sea-state run's isolation estimate (per payload axis) on an isolation dwell's
(per carrier axis): the projection of the dwell's carrier axis on each payload axis."""
from __future__ import annotations

import numpy as np

from ..errors import SceneError

CARRIER_AXES = {"roll": (0.0, 1.0, 0.0), "pitch": (1.0, 0.0, 0.0), "yaw": (0.0, 0.0, 1.0)}   # in frame 0, level


def dwell_scale(scene, axis: str) -> dict:
    """{payload axis: |component of the dwell's carrier axis along it|} with the gimbal on the scene's
    target on a level carrier: the dwell's ratio (LOS rate / carrier rate about one carrier axis) is the
    per-payload-axis ratio times this, while the axes do not couple."""
    from ..scene import geometry

    if scene.target is None:
        raise SceneError("--sea-estimate needs a scene with a [target] (the gimbal's pointing sets the scale)")
    alpha, beta = geometry.gimbal_angles_for(scene.target, 0.0, 0.0, 0.0)
    carrier_axis = np.array(CARRIER_AXES[axis])
    to_payload = (geometry.rz(alpha) @ geometry.rx(beta)).T   # frame 0 -> frame 2
    components = to_payload @ carrier_axis
    return {"elevation": abs(components[0]), "cross_elevation": abs(components[2])}
