"""A case gives the same bits wherever it runs: in a serial sweep, on a Dask worker (which runs BLAS
single-threaded), on a machine with more cores."""
import os
import pathlib
import subprocess
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]

SAMPLE = """
import sys, numpy as np
sys.path.insert(0, {scripts!r})
from scene_lib import load_scene
motion = load_scene({scene!r}).base_motion()
np.save(sys.argv[1], motion.sample(np.arange(20001) * 1e-3))
"""


def test_the_base_motion_does_not_depend_on_the_blas_thread_count(tmp_path):
    code = SAMPLE.format(scripts=str(REPO / "scripts"), scene=str(REPO / "scenes" / "ship_stabilization.toml"))
    samples = []
    for threads in ("1", "2", "4"):
        out = tmp_path / f"threads{threads}.npy"
        environment = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads,
                       "MKL_NUM_THREADS": threads}
        subprocess.run([sys.executable, "-c", code, str(out)], check=True, env=environment)
        samples.append(np.load(out))
    assert all(np.array_equal(samples[0], other) for other in samples[1:])
