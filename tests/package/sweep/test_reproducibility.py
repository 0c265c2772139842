"""A case gives the same bits wherever it runs: in a serial sweep, on a Dask worker (which runs BLAS
single-threaded), on a machine with more cores."""
import os
import pathlib
import subprocess
import sys

import numpy as np

from gimbal2axis import load_scene

REPO = pathlib.Path(__file__).resolve().parents[3]

SAMPLE = """
import sys, numpy as np
from gimbal2axis import load_scene
motion = load_scene({scene!r}).base_motion()
np.save(sys.argv[1], motion.sample(np.arange(20001) * 1e-3))
"""


def test_the_base_motion_does_not_depend_on_the_blas_thread_count(tmp_path):
    code = SAMPLE.format(scene=str(REPO / "scenes" / "ship_stabilization.toml"))
    samples = []
    for threads in ("1", "2", "4"):
        out = tmp_path / f"threads{threads}.npy"
        environment = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads,
                       "MKL_NUM_THREADS": threads}
        subprocess.run([sys.executable, "-c", code, str(out)], check=True, env=environment)
        samples.append(np.load(out))
    assert all(np.array_equal(samples[0], other) for other in samples[1:])


def test_the_blockwise_sum_of_sines_matches_the_direct_formula():
    """On a uniform grid the sea state is evaluated block by block (rotations of each block's start);
    anywhere else with sin and cos of every entry. The two agree to round-off."""
    motion = load_scene(REPO / "scenes" / "ship_stabilization.toml").base_motion()
    grid = np.arange(30001) * 1e-3
    irregular = grid.copy()
    irregular[-1] += 1e-9   # no longer uniform: the direct formula
    blockwise, direct = motion.sample(grid)[:-1], motion.sample(irregular)[:-1]
    scale = np.max(np.abs(direct), axis=0)
    moving = scale > 0
    assert np.all(np.max(np.abs(blockwise - direct), axis=0)[moving] <= 1e-13 * scale[moving])
    assert not np.array_equal(blockwise, direct)   # the two paths really differ


def test_a_shortened_run_sees_the_same_base_motion_bits():
    motion = load_scene(REPO / "scenes" / "ship_stabilization.toml").base_motion()
    full = motion.sample(np.arange(60001) * 1e-3)
    for rows in (2, 100, 129, 3001, 8193):
        assert np.array_equal(motion.sample(np.arange(rows) * 1e-3), full[:rows]), rows
