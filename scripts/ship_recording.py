#!/usr/bin/env python3
"""Writes the ship-motion FMU's example recording, fmu_src/ship_motion/resources/ship_recording.csv:

    .venv/bin/python scripts/ship_recording.py

The sea state of scenes/ship_stabilization.toml sampled at 20 Hz over the FMU's default experiment
(0-60 s): pitch, yaw, roll in degrees and heave z in metres, 9 significant digits, the way a motion
reference unit's log would give them. With motion = 1 the FMU splines it (rates and accelerations
from the spline), so it shows a recorded motion without a file of one's own."""
import pathlib

import numpy as np

from gimbal2axis import load_scene

REPO = pathlib.Path(__file__).resolve().parents[1]
OUTPUT = REPO / "fmu_src" / "ship_motion" / "resources" / "ship_recording.csv"
SAMPLE_INTERVAL_S, DURATION_S = 0.05, 60.0


def main() -> None:
    motion = load_scene(REPO / "scenes" / "ship_stabilization.toml").base_motion()
    t = np.arange(int(round(DURATION_S / SAMPLE_INTERVAL_S)) + 1) * SAMPLE_INTERVAL_S
    inputs = motion.sample(t)
    heave = motion.position(t)[:, 2]
    lines = ["# The sea state of scenes/ship_stabilization.toml at 20 Hz (scripts/ship_recording.py)",
             "time,pitch_deg,yaw_deg,roll_deg,z"]
    for k in range(len(t)):
        angles = np.degrees(inputs[k, :3])
        lines.append(",".join(f"{value:.9g}" for value in (t[k], *angles, heave[k])))
    OUTPUT.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
