"""The scene runner's C kernels (gimbal2axis/native/*.c, built by `pip install -e .` as the extension
gimbal2axis.native._native), loaded once through ctypes: the compiled communication loop (master/compiled_loop.py)
and the base motion's sums of sinusoids (scene/base_motion.py). Without them the Python versions run:
`why_not()` says why."""
from __future__ import annotations

import ctypes

_library = None
_why_not = None


def library():
    """The loaded kernels, or None (then why_not() says why)."""
    global _library, _why_not
    if _library is None and _why_not is None:
        try:
            from . import _native
            loaded = ctypes.CDLL(_native.__file__)
            pointer, long, double = ctypes.c_void_p, ctypes.c_long, ctypes.c_double
            loaded.gimbal_master_loop.argtypes = [pointer, long, long]
            loaded.gimbal_master_loop.restype = ctypes.c_int
            loaded.gimbal_master_loop_struct_size.restype = long
            loaded.gimbal_sum_of_sines.argtypes = [long, double, double, long] + [pointer] * 3 + [long] + [pointer] * 4
            loaded.gimbal_sum_of_sines.restype = None
            _library = loaded
        except (ImportError, OSError, AttributeError) as exc:
            _why_not = f"the compiled kernels are not available ({exc}; build them: pip install -e .)"
    return _library


def why_not() -> str | None:
    library()
    return _why_not
