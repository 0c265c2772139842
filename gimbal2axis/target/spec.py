"""The scene's [target] table of a moving target (docs/targets.md):

    [target]
    type = "earth_point"            # or "flyby", "track"; "direction" (the default): a fixed inertial direction
    latitude_deg = 59.91            # earth_point: geodetic (WGS 84) ...
    longitude_deg = 10.60
    altitude_m = 40.0
    # north_m, east_m, down_m       # ... or from the carrier's start, in its local north-east-down frame
    beam_width_mrad = 2.0           # on target: the error within half of it
    keyhole_deg = 10.0              # near the keyhole: the target within this of the azimuth axis
    start_on_target = true
    ins_position_error_m = [0.0, 0.0, 0.0]   # east, north, up: where the controller's INS is wrong

    [target.carrier]                # the carrier's gimbal on the Earth
    latitude_deg = 59.85
    longitude_deg = 10.55
    altitude_m = 15.0               # the gimbal's height above the ellipsoid
    course_deg = 20.0               # true course: G's y axis, the base motion's yaw is relative to it
    speed_m_s = 8.0                 # sailing a rhumb line; or track = "own_ship.csv", a recorded track

flyby: altitude_m (above the ellipsoid; the flat pass's height is altitude_m minus the carrier's),
speed_m_s, heading_deg (true), closest_approach_m (horizontal, > 0 to the right of the aircraft's
track), closest_approach_s (when). track: file = "boat.csv" (motion.Track), relative to the scene file.
"""
from __future__ import annotations

import math
import pathlib

import numpy as np

from ..errors import SceneError, boolean, check_keys, did_you_mean, positive, shown, within
from .motion import COORDINATE_RANGES, DIFFERENCE_STEP_S, FARTHEST_M, FASTEST_M_S, Carrier, EarthPoint, Flyby, \
    GimbalMotion, RecordedTarget, Track, enu_to_g

MOVING_KINDS = ("earth_point", "flyby", "track")
KINDS = ("direction",) + MOVING_KINDS
COMMON_KEYS = {"type", "start_on_target", "beam_width_mrad", "keyhole_deg", "carrier", "ins_position_error_m"}
KIND_KEYS = {
    "earth_point": {"latitude_deg", "longitude_deg", "altitude_m", "north_m", "east_m", "down_m"},
    "flyby": {"altitude_m", "speed_m_s", "heading_deg", "closest_approach_m", "closest_approach_s"},
    "track": {"file"},
}
CARRIER_KEYS = {"latitude_deg", "longitude_deg", "altitude_m", "course_deg", "speed_m_s", "track"}
DEFAULT_BEAM_WIDTH_MRAD = 1.0
DEFAULT_KEYHOLE_DEG = 10.0
# The FMU's default lever arm base.d_ab[1..3] [m] (model_core/include/gimbal/real_variables.def), for
# a scene that does not set it; tests/package/target/test_target_lever_arm.py holds them equal.
DEFAULT_LEVER_ARM_M = (0.0, 0.0, 0.25)
LEVER_ARM_PARAMETERS = ("base.d_ab[1]", "base.d_ab[2]", "base.d_ab[3]")
# The largest INS position error a scene may give [m] per component: larger is no navigation system.
LARGEST_INS_ERROR_M = 1e4
# The latest closest approach of a flyby from the run's start [s] (about 30 years): a larger number is a typo.
LATEST_S = 1e9
# Every number of [target] and [target.carrier] by key: (low, high), both included (docs/targets.md).
KEY_RANGES = {**COORDINATE_RANGES, "course_deg": (-360.0, 360.0), "heading_deg": (-360.0, 360.0),
              "speed_m_s": (0.0, FASTEST_M_S), "closest_approach_m": (-FARTHEST_M, FARTHEST_M),
              "closest_approach_s": (-LATEST_S, LATEST_S), "beam_width_mrad": (0.0, 2000.0 * math.pi)}


def within_range(where: str, key: str, value) -> float:
    """The finite number `value` of `key` (in table `where`) within KEY_RANGES[key]."""
    return within(f"{where}.{key}", value, *KEY_RANGES[key])


def kind_of(table: dict) -> str:
    kind = table.get("type", "direction")
    if not isinstance(kind, str) or kind not in KINDS:
        raise SceneError(f"target.type must be one of {list(KINDS)}, got {shown(kind)}{did_you_mean(kind, KINDS)}")
    return kind


def parse(table: dict) -> dict:
    """The validated [target] table of a moving target (numbers checked by key), as Scene.target_spec."""
    kind = kind_of(table)
    check_keys("target", table, COMMON_KEYS | KIND_KEYS[kind])
    spec = _common(table, kind)
    carrier = table.get("carrier", {})
    spec["carrier"] = _carrier(carrier)
    for key in KIND_KEYS[kind] - {"file"}:
        if key in table:
            spec[key] = within_range("target", key, table[key])
    _KIND_CHECKS[kind](table, carrier, spec)
    return spec


def _common(table: dict, kind: str) -> dict:
    """The keys every kind of target takes."""
    spec = {"type": kind, "start_on_target": boolean("target.start_on_target", table.get("start_on_target", False)),
            "beam_width_mrad": within_range("target", "beam_width_mrad",
                                            positive("target.beam_width_mrad", table.get("beam_width_mrad",
                                                                                         DEFAULT_BEAM_WIDTH_MRAD))),
            "keyhole_deg": positive("target.keyhole_deg", table.get("keyhole_deg", DEFAULT_KEYHOLE_DEG))}
    if spec["keyhole_deg"] >= 90.0:
        raise SceneError(f"target.keyhole_deg = {spec['keyhole_deg']:g} must be below 90 (degrees from the azimuth "
                         "axis)")
    if "ins_position_error_m" in table:
        spec["ins_position_error_m"] = ins_error(table["ins_position_error_m"])
    return spec


def _carrier(carrier) -> dict:
    """The validated [target.carrier] table."""
    if not isinstance(carrier, dict):
        raise SceneError(f"target.carrier must be a table ([target.carrier]), got {shown(carrier)}")
    check_keys("target.carrier", carrier, CARRIER_KEYS)
    spec = {key: within_range("target.carrier", key, value) for key, value in carrier.items() if key != "track"}
    if "track" in carrier:
        if not isinstance(carrier["track"], str):
            raise SceneError(f"target.carrier.track must be a file name, got {shown(carrier['track'])}")
        spec["track"] = carrier["track"]
    if "speed_m_s" in carrier and "track" in carrier:
        raise SceneError("target.carrier has both speed_m_s and track: the carrier sails at a speed or follows "
                         "its recorded track, not both")
    if abs(spec.get("latitude_deg", 0.0)) == 90.0 and spec.get("speed_m_s", 0.0) > 0.0:
        raise SceneError(f"target.carrier.latitude_deg = {spec['latitude_deg']:g}: a carrier at a pole has "
                         "no course to sail (target.carrier.speed_m_s must be 0 there)")
    return spec


def _check_earth_point(table: dict, carrier: dict, spec: dict) -> None:
    """A point given one way, geodetic or local, whole, and a geodetic one with the carrier's position."""
    geodetic = {"latitude_deg", "longitude_deg"} & set(table)
    local = {"north_m", "east_m", "down_m"} & set(table)
    if geodetic and local:
        raise SceneError("target: give the point by latitude_deg, longitude_deg (and altitude_m) or by north_m, "
                         "east_m, down_m from the carrier's start, not both")
    if len(geodetic) == 1:
        missing = ({"latitude_deg", "longitude_deg"} - geodetic).pop()
        raise SceneError(f"target: {geodetic.pop()} without {missing}")
    if not geodetic and not local:
        raise SceneError("target type 'earth_point' needs latitude_deg, longitude_deg (and altitude_m), or "
                         "north_m, east_m, down_m from the carrier's start")
    if local and "altitude_m" in table:
        raise SceneError("target: altitude_m is for a geodetic point; a local one gives down_m")
    if geodetic and not {"latitude_deg", "longitude_deg"} <= set(carrier) and "track" not in carrier:
        raise SceneError("target: a geodetic point needs the carrier's position: [target.carrier] latitude_deg "
                         "and longitude_deg (or track)")


def _check_flyby(table: dict, carrier: dict, spec: dict) -> None:
    """Every key given, a flat pass over a sailing carrier that does not go through the gimbal."""
    for key in ("altitude_m", "speed_m_s", "heading_deg", "closest_approach_m", "closest_approach_s"):
        if key not in table:
            raise SceneError(f"target type 'flyby' needs {key}")
    positive("target.speed_m_s", spec["speed_m_s"])
    if "track" in carrier:
        raise SceneError("target type 'flyby' is flat, on a carrier sailing at speed_m_s; a recorded carrier "
                         "track goes with earth_point or track targets")
    if spec["altitude_m"] - spec["carrier"].get("altitude_m", 0.0) == 0.0 and spec["closest_approach_m"] == 0.0:
        raise SceneError("target: a flyby at the gimbal's own altitude with closest_approach_m = 0 passes "
                         "through the gimbal")


def _check_track(table: dict, carrier: dict, spec: dict) -> None:
    """The recorded track's file name, into spec."""
    if not isinstance(table.get("file"), str):
        raise SceneError(f"target type 'track' needs file = \"<track>.csv\" (relative to the scene file), got "
                         f"{shown(table.get('file'))}")
    spec["file"] = table["file"]


_KIND_CHECKS = {"earth_point": _check_earth_point, "flyby": _check_flyby, "track": _check_track}


def ins_error(value) -> list:
    """[target] ins_position_error_m: three numbers (east, north, up) [m], each within +-LARGEST_INS_ERROR_M."""
    if not isinstance(value, list) or len(value) != 3:
        raise SceneError(f"target.ins_position_error_m must be three numbers [east, north, up] in metres, got "
                         f"{shown(value)}")
    return [within(f"target.ins_position_error_m[{i}]", x, -LARGEST_INS_ERROR_M, LARGEST_INS_ERROR_M)
            for i, x in enumerate(value)]


def lever_arm(parameters: dict) -> tuple:
    """The lever arm d_ab [m] (frame 0) from the carrier's point a to the gimbal: the scene's
    [parameters] base.d_ab[1..3], else the FMU's defaults."""
    return tuple(float(parameters.get(name, default)) for name, default in zip(LEVER_ARM_PARAMETERS,
                                                                               DEFAULT_LEVER_ARM_M))


def build(spec: dict, base_dir: pathlib.Path, base_motion=None, parameters: dict | None = None,
          step_size: float = 1e-3):
    """The motion.MovingTarget of a parsed spec; files relative to base_dir (the scene's folder). With
    the scene's base_motion (and its [parameters], for the lever arm d_ab; step_size, its grid), the
    gimbal moves with the carrier (motion.GimbalMotion); without, it stays where the carrier is."""
    target = _build(spec, base_dir)
    if base_motion is not None:
        target.gimbal = GimbalMotion(base_motion, lever_arm(parameters or {}), step_size)
    error = spec.get("ins_position_error_m")
    if error is not None:
        target.ins_error = enu_to_g(*error, target.carrier.course).reshape(3, 1)
    return target


def _build(spec: dict, base_dir: pathlib.Path):
    c = spec["carrier"]
    origin = (c.get("latitude_deg", 0.0), c.get("longitude_deg", 0.0), c.get("altitude_m", 0.0))
    carrier_track = None
    if "track" in c:
        carrier_track = Track("target.carrier.track", base_dir / c["track"], origin if "latitude_deg" in c else None)
    carrier = Carrier(*origin, math.radians(c.get("course_deg", 0.0)), c.get("speed_m_s", 0.0), carrier_track)
    kind = spec["type"]
    if kind == "earth_point":
        if "latitude_deg" in spec:
            point = (spec["latitude_deg"], spec["longitude_deg"], spec.get("altitude_m", 0.0))
        else:
            import pymap3d
            point = pymap3d.ned2geodetic(spec.get("north_m", 0.0), spec.get("east_m", 0.0), spec.get("down_m", 0.0),
                                         *origin)
        return EarthPoint(carrier, *(float(v) for v in point))
    if kind == "flyby":
        return Flyby(carrier, spec["altitude_m"] - origin[2], spec["speed_m_s"], math.radians(spec["heading_deg"]),
                     spec["closest_approach_m"], spec["closest_approach_s"])
    return RecordedTarget(carrier, Track("target.file", base_dir / spec["file"], origin))


def check_run(target, stop_time: float) -> None:
    """Refuses recorded tracks that do not cover the run (with the margin the rates need), a carrier
    that sails onto a pole during the run and a target where the gimbal is at the start."""
    if getattr(target, "track", None) is not None:
        target.track.check_covers("target.file", stop_time)
    if target.carrier.track is not None:
        target.carrier.track.check_covers("target.carrier.track", stop_time)
    check_off_the_poles(target.carrier, stop_time)
    check_apart(target)


# The nearest a target may be to the gimbal at the start [m]: nearer, its direction is rounding noise.
NEAREST_M = 1e-3


def check_off_the_poles(carrier: Carrier, stop_time: float) -> None:
    """Refuses a carrier whose rhumb line reaches a pole within the run (and the differences' margin):
    there its course, the frame G, is undefined (pymap3d gives latitudes beyond 90 degrees)."""
    if carrier.track is not None or carrier.speed == 0.0:
        return
    with np.errstate(all="ignore"):
        latitude = carrier.geodetic(np.array([-DIFFERENCE_STEP_S, stop_time + DIFFERENCE_STEP_S]))[0]
    if not np.all(np.abs(latitude) < 90.0):
        raise SceneError(f"target.carrier: sailing course_deg = {math.degrees(carrier.course):g} at speed_m_s = "
                         f"{carrier.speed:g} from latitude_deg = {carrier.latitude_deg!r}, it reaches a pole before "
                         f"the run ends ({stop_time:g} s), where a course has no meaning")


def check_apart(target) -> None:
    """Refuses a target at the gimbal at the start (range below NEAREST_M): the line of sight has no
    direction there."""
    with np.errstate(all="ignore"):
        p = target.relative(np.array([0.0]))[0]
    distance = float(np.sqrt(np.sum(p * p)))
    if not distance >= NEAREST_M:
        keys = {"earth_point": "latitude_deg, longitude_deg, altitude_m or north_m, east_m, down_m",
                "track": "file", "flyby": "closest_approach_m, altitude_m"}.get(target.kind, "type")
        raise SceneError(f"target: the target ({keys}) is {distance:g} m from the gimbal at t = 0 s: the line of "
                         f"sight has no direction; a target is at least {NEAREST_M:g} m away")
