"""The C kernel (the repository's c_kernel/src/*.c, built by `pip install -e .` with module.c as the
extension gimbal2axis.native._native), loaded once through ctypes: the built-in controllers (scene/controllers.py)
and their set points toward a target (scene/setpoints.py), the sensors (scene/sensors.py), the sums of
sinusoids of the base motions, the sea state's components and the recorded motion's splines
(scene/base_motion.py) and the compiled
communication loop (master/compiled_loop.py). The structs they share with Python are built here from
the kernel's own layout table (`struct`), never copied. `why_not()` says why the kernel is missing."""
from __future__ import annotations

import ctypes

_library = None
_why_not = None
_structs: dict = {}


def library():
    """The loaded kernel, or None (then why_not() says why)."""
    global _library, _why_not
    if _library is None and _why_not is None:
        try:
            from . import _native
            loaded = ctypes.CDLL(_native.__file__)
            _declare(loaded)
            _library = loaded
        except (ImportError, OSError, AttributeError) as exc:
            _why_not = f"the compiled kernel is not available ({exc}; build it: pip install -e .)"
    return _library


def why_not() -> str | None:
    library()
    return _why_not


def kernel():
    """The loaded kernel; an ImportError saying why when it was not built."""
    loaded = library()
    if loaded is None:
        raise ImportError(_why_not)
    return loaded


def _declare(loaded) -> None:
    pointer, long, double, integer, text = ctypes.c_void_p, ctypes.c_long, ctypes.c_double, ctypes.c_int, ctypes.c_char_p
    signatures = {
        "gimbal_master_loop": ([pointer, long, long], integer),
        "gimbal_master_loop_call_name": ([integer], text),
        "gimbal_controller_kind": ([text], integer),
        "gimbal_controller_step": ([pointer, long, double, pointer, pointer, pointer, pointer], None),
        "gimbal_target_direction": ([double, double, pointer], None),
        "gimbal_target_set_points": ([long, pointer, pointer, pointer, pointer, pointer], None),
        "gimbal_angle_nearest_turn": ([double, double], double),
        "gimbal_pointing_command": ([pointer] * 7, integer),
        "gimbal_sensors_measure": ([pointer, long, pointer], None),
        "gimbal_gyro_measure": ([pointer, long, pointer, pointer], None),
        "gimbal_gyro_series": ([pointer, long, pointer, pointer], None),
        "gimbal_sum_of_sines_weights": ([long, pointer, pointer, pointer], None),
        "gimbal_sum_of_sines": ([long, double, double, long] + [pointer] * 6, integer),
        "gimbal_pairwise_sum": ([pointer, long], double),
        "gimbal_random_uniform": ([pointer, long, long, double, double, pointer], None),
        "gimbal_sea_state_components": ([pointer, long, double, double, double, long, double, double] + [pointer] * 3,
                                        integer),
        "gimbal_cubic_spline_coefficient_count": ([long], long),
        "gimbal_cubic_spline_fit": ([long, pointer, pointer, pointer], integer),
        "gimbal_cubic_spline_evaluate": ([long, pointer, pointer, double, integer], double),
        "gimbal_recorded_motion_read": ([text, ctypes.c_size_t, ctypes.POINTER(pointer), text, ctypes.c_size_t], integer),
        "gimbal_recorded_motion_free": ([pointer], None),
        "gimbal_recorded_motion_start": ([pointer], double),
        "gimbal_recorded_motion_end": ([pointer], double),
        "gimbal_recorded_motion_sample": ([pointer, long, pointer, pointer], None),
        "gimbal_recorded_motion_position": ([pointer, long, pointer, pointer], None),
        "gimbal_layout_field_count": ([], long),
        "gimbal_layout_field": ([long] + [ctypes.POINTER(text)] * 2 + [ctypes.POINTER(long), ctypes.POINTER(text),
                                                                        ctypes.POINTER(long)], integer),
        "gimbal_layout_size": ([text], long),
    }
    for name, (arguments, result) in signatures.items():
        function = getattr(loaded, name)
        function.argtypes, function.restype = arguments, result


_SCALARS = {"double": ctypes.c_double, "long": ctypes.c_long, "int": ctypes.c_int, "pointer": ctypes.c_void_p}


def _layout_rows(loaded) -> dict:
    """{struct name: [(field, offset, kind, count), ...]} from the kernel's layout table."""
    rows: dict = {}
    structure, field, kind = ctypes.c_char_p(), ctypes.c_char_p(), ctypes.c_char_p()
    offset, count = ctypes.c_long(), ctypes.c_long()
    for index in range(loaded.gimbal_layout_field_count()):
        loaded.gimbal_layout_field(index, ctypes.byref(structure), ctypes.byref(field), ctypes.byref(offset),
                                   ctypes.byref(kind), ctypes.byref(count))
        rows.setdefault(structure.value.decode(), []).append(
            (field.value.decode(), offset.value, kind.value.decode(), count.value))
    return rows


def struct(name: str) -> type:
    """The ctypes Structure of the kernel's struct `name` (e.g. "GimbalMasterLoop"): its fields at the
    offsets the compiled kernel reports, padded to its sizeof; nested structs likewise."""
    if name in _structs:
        return _structs[name]
    loaded = kernel()
    rows = _layout_rows(loaded)
    if name not in rows:
        raise KeyError(f"the kernel's layout table has no struct {name!r}")
    fields, end = [], 0
    for field, offset, kind, count in sorted(rows[name], key=lambda row: row[1]):
        element = _SCALARS.get(kind) or struct(kind)
        if offset > end:   # the C compiler's padding, as reported
            fields.append((f"_padding_{end}", ctypes.c_char * (offset - end)))
        field_type = element if count == 1 else element * count
        fields.append((field, field_type))
        end = offset + ctypes.sizeof(field_type)
    size = loaded.gimbal_layout_size(name.encode())
    if size > end:
        fields.append((f"_padding_{end}", ctypes.c_char * (size - end)))
    built = type(name, (ctypes.Structure,), {"_fields_": fields})
    for field, offset, _, _ in rows[name]:
        if getattr(built, field).offset != offset:
            raise ImportError(f"{name}.{field}: ctypes placed it at {getattr(built, field).offset}, the kernel at {offset}")
    if ctypes.sizeof(built) != size:
        raise ImportError(f"{name}: ctypes makes it {ctypes.sizeof(built)} bytes, the kernel {size}")
    _structs[name] = built
    return built
