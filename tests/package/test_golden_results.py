"""Bit-identical results across a restructuring: every scene, a sweep table and two linearizations
digested (tests/package/golden/digests.py) and compared with the digests recorded from main before the move
(tests/package/golden/digests.json). A difference names the scene and signal, the sweep column or the matrix.

The digests are of float64 bits, so they hold on machines that compute the same bits: the build's
flags (no -march=native, no FP contraction in the compiled loop) and the same libm. Record anew
(python tests/package/golden/digests.py record) only for a change that is meant to change results, and say
so in the commit."""
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "golden"))
import digests  # noqa: E402


def differences(recorded, computed, where=""):
    if isinstance(recorded, dict) and isinstance(computed, dict):
        out = []
        for key in sorted(set(recorded) | set(computed)):
            if key not in computed:
                out.append(f"{where}{key}: missing")
            elif key not in recorded:
                out.append(f"{where}{key}: not recorded")
            else:
                out += differences(recorded[key], computed[key], f"{where}{key}/")
        return out
    return [] if recorded == computed else [f"{where.rstrip('/')}: differs"]


def test_every_result_is_bit_identical_to_the_recorded_one(fmu_path, probe_lib_path, tmp_path):
    recorded = json.loads(digests.DIGEST_FILE.read_text())
    computed = digests.compute(fmu_path, tmp_path)
    found = differences(recorded, computed)
    assert not found, "results changed:\n" + "\n".join(found[:40])
