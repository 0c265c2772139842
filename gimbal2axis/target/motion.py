"""Where a moving target is, seen from the gimbal on a carrier that sails: the position p(t) of the
target relative to the gimbal in G [m] with its first two time derivatives, for the scene's
[target] kinds earth_point, flyby and track (spec.py reads them).

G is the carrier's local level frame: z_G up, y_G horizontal along the carrier's mean course (true
course, clockwise from north), x_G to starboard of it, as the recorded ship motions are fed
(docs/physics.md, section 7.1): with course 0, x_G is east and y_G north. The carrier's attitude
(the scene's base motion) is relative to this frame.

Geodesy is pymap3d's (WGS 84): the carrier sails a rhumb line (constant course,
pymap3d.lox.loxodrome_direct) or follows a recorded track; the target's position in the carrier's
local east-north-up frame at each instant is pymap3d.geodetic2enu, so the Earth's curvature (a point
10 km away lies 7.8 m below the carrier's horizon plane) and the turning of the local vertical along
the carrier's way are in it. Its derivatives are central differences over DIFFERENCE_STEP_S of
that position: the relative motion of a ship and a coastal point is smooth on that scale (the
error of the rate is (step^2 / 6) p''' and the rounding of the acceleration about 1e-9 m / step^2).

The flyby is flat: an aircraft on a straight line in the carrier's local level frame at its start,
exact derivatives (closed form).

[target.carrier] places the gimbal on the carrier at rest; the sea moves it from there (GimbalMotion:
the base motion's translation and the lever arm d_ab turned by the attitude). The truth (the record's
target signals and los_error) is the target seen from where the gimbal is; the controller's command
sees it from where its INS says the gimbal is (`relative(t, known=True)`: the INS position error of
[target] ins_position_error_m added). docs/targets.md, "Frames".
"""
from __future__ import annotations

import math
import pathlib

import numpy as np

from ..errors import SceneError, excerpt
from .kinematics import base_to_inertial, carrier_rate_and_acceleration, unit_and_derivatives

DIFFERENCE_STEP_S = 0.05
# The farthest a target or a carrier is taken from the ellipsoid or from the carrier's start [m]:
# beyond a geostationary orbit (3.6e7 m); a larger number is a typo, not a target.
FARTHEST_M = 1e8
# The fastest target or carrier [m/s]: beyond an orbital speed (7.8e3 m/s).
FASTEST_M_S = 1e4
# The range of each coordinate of a track (and of the [target] keys of the same name, spec.py).
COORDINATE_RANGES = {"latitude_deg": (-90.0, 90.0), "longitude_deg": (-180.0, 360.0),
                     "altitude_m": (-FARTHEST_M, FARTHEST_M), "north_m": (-FARTHEST_M, FARTHEST_M),
                     "east_m": (-FARTHEST_M, FARTHEST_M), "down_m": (-FARTHEST_M, FARTHEST_M)}


def enu_to_g(east, north, up, course):
    """G components of an east-north-up vector, G's y axis along the true course [rad]."""
    c, s = math.cos(course), math.sin(course)
    return np.array([c * east - s * north, s * east + c * north, up])


def g_to_enu(x, y, z, course):
    c, s = math.cos(course), math.sin(course)
    return np.array([c * x + s * y, -s * x + c * y, z])


class Track:
    """A recorded track: a comma-separated file with a header row (`#` starts a comment line), a
    `time` column [s] and either latitude_deg, longitude_deg, altitude_m (geodetic, WGS 84) or
    north_m, east_m, down_m (from `origin`, the carrier's start: pymap3d.ned2geodetic). Each
    coordinate is a C2 cubic spline through the samples (scipy's CubicSpline, not-a-knot ends, as
    the recorded ship motions). Read by their reader (native/csv_table.py), so checked like them: a
    header with a time column and no name twice, numbers in every cell, at least 4 rows, time
    strictly increasing, a UTF-8 byte-order mark skipped; refusals name the file, line and column.
    Each coordinate within COORDINATE_RANGES."""

    GEODETIC = ("latitude_deg", "longitude_deg", "altitude_m")
    LOCAL = ("north_m", "east_m", "down_m")

    def __init__(self, where: str, path: pathlib.Path, origin=None):
        self.path = path
        names, table = self._read(where, path)
        for kind in (self.GEODETIC, self.LOCAL):
            if set(kind) <= set(names):
                self.columns = kind
                break
        else:
            raise SceneError(f"{where}: {path}: the header has columns {excerpt(', '.join(names))}; a track needs "
                             f"time and either {', '.join(self.GEODETIC)} or {', '.join(self.LOCAL)}")
        extra = sorted(set(names) - {"time", *self.columns})
        if extra:
            raise SceneError(f"{where}: {path}: unknown column(s) {excerpt(', '.join(extra))} (a track has time and "
                             f"{', '.join(self.columns)})")
        t = table[:, names.index("time")]
        for name in self.columns:
            self._check_range(where, path, name, table[:, names.index(name)])
        self.time = t
        self.t_start, self.t_end = float(t[0]), float(t[-1])
        coordinates = [table[:, names.index(c)] for c in self.columns]
        if self.columns == self.GEODETIC:
            # a track across the antimeridian stays continuous for the spline
            coordinates[1] = np.degrees(np.unwrap(np.radians(coordinates[1])))
        elif origin is not None:
            import pymap3d
            coordinates = list(pymap3d.ned2geodetic(*coordinates, *origin))
        else:
            raise SceneError(f"{where}: {path}: a track in north_m, east_m, down_m is relative to the carrier's "
                             "start, which needs a geodetic [target.carrier] position")
        from scipy.interpolate import CubicSpline   # here: a scene without a track imports no scipy

        self.splines = [CubicSpline(t, c, bc_type="not-a-knot") for c in coordinates]

    @staticmethod
    def _read(where: str, path: pathlib.Path):
        """(column names, values) of the file, read by the kernel's reader of recorded tables (the
        ship-motion recordings' own)."""
        from ..limits import MAX_RECORDING_BYTES, TooLarge, read_bounded
        from ..native.csv_table import TableRefused, read_table

        try:
            text = read_bounded(path, MAX_RECORDING_BYTES, "a recorded track")
        except OSError as exc:
            raise SceneError(f"{where}: recorded track {path}: cannot read it: {exc.strerror or exc}") from None
        except TooLarge as exc:
            raise SceneError(f"{where}: recorded track {exc}") from None
        try:
            return read_table(text)
        except TableRefused as exc:
            reason = str(exc)
            if reason.startswith(("not a recorded motion", "the file is empty")):   # the reader's words for a recording
                raise SceneError(f"{where}: {path} is not a recorded track: its header (the first line that is not a "
                                 "comment) has no 'time' column (expected a header such as 'time,latitude_deg,"
                                 "longitude_deg,altitude_m', then rows of numbers)") from None
            raise SceneError(f"{where}: {path}: {reason}") from None

    @staticmethod
    def _check_range(where: str, path: pathlib.Path, name: str, values: np.ndarray) -> None:
        low, high = COORDINATE_RANGES[name]
        outside = np.flatnonzero((values < low) | (values > high))
        if outside.size:
            row = int(outside[0]) + 1
            raise SceneError(f"{where}: {path}: data row {row}: {name} {values[row - 1]:g} is outside "
                             f"[{low:g}, {high:g}]")

    def check_covers(self, where: str, stop_time: float) -> None:
        # the differences reach DIFFERENCE_STEP_S beyond the run's ends
        if self.t_start > -DIFFERENCE_STEP_S or self.t_end < stop_time + DIFFERENCE_STEP_S:
            raise SceneError(f"{where}: the track {self.path} covers [{self.t_start:g}, {self.t_end:g}] s, not "
                             f"[{-DIFFERENCE_STEP_S:g}, {stop_time + DIFFERENCE_STEP_S:g}] s (the run and "
                             f"{DIFFERENCE_STEP_S:g} s either side for the rates)")

    def geodetic(self, t):
        return tuple(spline(t) for spline in self.splines)


class Carrier:
    """The carrier's gimbal on the Earth: sailing a rhumb line at speed_m_s along course from a
    start position, or a recorded Track; G's y axis along `course` [rad] (the mean course, the
    frame the base motion's yaw is relative to)."""

    def __init__(self, latitude_deg, longitude_deg, altitude_m, course, speed_m_s, track: Track | None = None):
        self.latitude_deg, self.longitude_deg, self.altitude_m = latitude_deg, longitude_deg, altitude_m
        self.course, self.speed, self.track = course, speed_m_s, track

    def geodetic(self, t):
        t = np.asarray(t, dtype=float)
        if self.track is not None:
            return self.track.geodetic(t)
        distance = self.speed * t
        if self.speed == 0.0:
            lat, lon = np.full(t.shape, self.latitude_deg), np.full(t.shape, self.longitude_deg)
        else:
            from pymap3d.lox import loxodrome_direct
            # loxodrome_direct takes a non-negative range: a time before the start sails the reciprocal course
            lat, lon = loxodrome_direct(self.latitude_deg, self.longitude_deg, np.abs(distance),
                                        np.where(distance >= 0, math.degrees(self.course),
                                                 math.degrees(self.course) + 180.0))
            # (it returns a 0-d array for a single time)
            lat, lon = (np.broadcast_to(np.asarray(x, dtype=float), t.shape).copy() for x in (lat, lon))
        return lat, lon, np.full(t.shape, float(self.altitude_m))

    def flat_position(self, t):
        """Position in G relative to the start, on a flat Earth (for the flyby): course along y_G."""
        t = np.asarray(t, dtype=float)
        return np.array([np.zeros_like(t), self.speed * t, np.zeros_like(t)])


class GimbalMotion:
    """Where the gimbal (point b, where its axes cross) is from where [target.carrier] places it, in G
    with its velocity and acceleration (exact, from the base motion's): the base motion's translation
    of point a from its start less its constant velocity (the carrier's sailing, which the carrier's
    rhumb line or track gives already), plus the lever arm d_ab (frame 0) turned by the carrier's
    attitude less the same arm on the level carrier, (GT0 - I) d_ab (docs/physics.md (2.18))."""

    def __init__(self, motion, lever_arm, step_size: float):
        self.motion, self.step = motion, float(step_size)
        self.lever_arm = np.asarray(lever_arm, dtype=float).reshape(3, 1)
        self.drift = np.asarray(getattr(motion, "velocity", np.zeros(3)), dtype=float).reshape(3, 1)

    def _base(self, t):
        """The base inputs (n, 15) and point a's position (n, 3) at t: on the run's grid t_k = k h the
        rows of the grid (the bits the run sets, whole or chunk by chunk), elsewhere sampled at t."""
        if len(t) > 1:
            first = int(round(t[0] / self.step))
            if np.array_equal(t, np.arange(first, first + len(t)) * self.step):
                return (self.motion.sample_rows(first, len(t), self.step),
                        self.motion.position_rows(first, len(t), self.step))
        return self.motion.sample(t), self.motion.position(t)

    def displacement(self, t):
        base, position = self._base(np.atleast_1d(np.asarray(t, dtype=float)))
        attitude = base[:, 0:3].T
        w, w_dot = carrier_rate_and_acceleration(attitude, base[:, 3:6].T, base[:, 6:9].T)
        d = np.broadcast_to(self.lever_arm, w.shape)
        w_d = np.cross(w, d, axis=0)
        arm = base_to_inertial(d, attitude) - d
        arm_dot = base_to_inertial(w_d, attitude)
        arm_ddot = base_to_inertial(np.cross(w_dot, d, axis=0) + np.cross(w, w_d, axis=0), attitude)
        p = position.T - self.drift * t + arm
        return p, base[:, 9:12].T - self.drift + arm_dot, base[:, 12:15].T + arm_ddot


class MovingTarget:
    """Base of the moving targets: `relative(t)` -> p, p', p'' ((3, n) in G, metres) of the target
    from the gimbal; `direction(t)` the unit vector; `kinematics(t)` u, u', u'', range, range rate.
    `known=True`: from where the controller's INS places the gimbal (ins_error, in G)."""
    kind = "?"
    gimbal: GimbalMotion | None = None   # None: the gimbal stays where [target.carrier] places it
    ins_error = np.zeros((3, 1))

    def __init__(self, carrier: Carrier):
        self.carrier = carrier

    def relative_to_carrier(self, t):
        """p, p', p'' of the target from where [target.carrier] places the gimbal (the carrier at rest)."""
        raise NotImplementedError

    def relative(self, t, known: bool = False):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        p, p_dot, p_ddot = self.relative_to_carrier(t)
        if self.gimbal is not None:
            d, d_dot, d_ddot = self.gimbal.displacement(t)
            p, p_dot, p_ddot = p - d, p_dot - d_dot, p_ddot - d_ddot
        return (p - self.ins_error if known else p), p_dot, p_ddot

    def kinematics(self, t, known: bool = False):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        with np.errstate(all="ignore"):   # a range of 0 or a position that is not finite: refused below
            kinematics = unit_and_derivatives(*self.relative(t, known))
        r = kinematics[3]
        bad = np.flatnonzero(~(np.isfinite(r) & (r > 0.0)))
        if bad.size:
            at = float(t[bad[0]])
            raise SceneError(f"target: at t = {at:g} s the {self.kind} target is "
                             + ("at the gimbal (range 0)" if r[bad[0]] == 0.0 else f"at range {r[bad[0]]:g} m")
                             + ": the line of sight has no direction")
        return kinematics

    def direction(self, t):
        return self.kinematics(t)[0]


class GeodeticTarget(MovingTarget):
    """A target whose geodetic position is known at any time (`position(t)` -> lat, lon, alt): the
    relative position is pymap3d.geodetic2enu from the carrier's position at that instant, turned
    into G; its rates by central differences."""

    def position(self, t):
        raise NotImplementedError

    def _offset(self, t):
        import pymap3d   # here: pymap3d is imported by the scenes with a geodetic target only

        lat, lon, alt = self.position(t)
        lat0, lon0, alt0 = self.carrier.geodetic(t)
        east, north, up = pymap3d.geodetic2enu(lat, lon, alt, lat0, lon0, alt0)
        return enu_to_g(np.asarray(east), np.asarray(north), np.asarray(up), self.carrier.course)

    def relative_to_carrier(self, t):
        step = DIFFERENCE_STEP_S
        p, ahead, behind = (self._offset(t + shift) for shift in (0.0, step, -step))
        return p, (ahead - behind) / (2.0 * step), (ahead - 2.0 * p + behind) / (step * step)


class EarthPoint(GeodeticTarget):
    """A point fixed on the Earth (a coastal landmark, a buoy): latitude, longitude [deg], altitude [m]."""
    kind = "earth_point"

    def __init__(self, carrier: Carrier, latitude_deg, longitude_deg, altitude_m):
        super().__init__(carrier)
        self.point = (latitude_deg, longitude_deg, altitude_m)

    def position(self, t):
        shape = np.shape(t)
        return tuple(np.full(shape, float(value)) for value in self.point)


class RecordedTarget(GeodeticTarget):
    """A target on a recorded Track (a boat's AIS track, a recorded flight)."""
    kind = "track"

    def __init__(self, carrier: Carrier, track: Track):
        super().__init__(carrier)
        self.track = track

    def position(self, t):
        return self.track.geodetic(t)


class Flyby(MovingTarget):
    """An aircraft on a straight line at constant speed and altitude: heading (true, clockwise from
    north), speed, height above the gimbal, and its closest approach: at time t_ca it passes
    `closest_approach` metres (horizontally) from where the carrier then is; > 0: its track lies to
    the right of the carrier, seen along its heading. On a carrier that stands still the ground
    range is smallest there, the slant range hypot(closest_approach, height) and the line of sight's
    rate v / hypot(...), so the azimuth rate is v / (slant range cos(elevation)) = v /
    closest_approach. Flat Earth: the few kilometres of a pass bend the horizon by a few metres at
    most (docs/targets.md)."""
    kind = "flyby"

    def __init__(self, carrier: Carrier, height_m, speed_m_s, heading, closest_approach_m, closest_approach_s):
        super().__init__(carrier)
        self.height, self.speed, self.heading = height_m, speed_m_s, heading
        self.closest_approach, self.t_ca = closest_approach_m, closest_approach_s
        # in G: the heading relative to the carrier's course, clockwise from y_G; right of the track is
        # the heading turned 90 degrees clockwise
        relative_heading = heading - carrier.course
        self.velocity = np.array([math.sin(relative_heading), math.cos(relative_heading), 0.0]) * speed_m_s
        right = np.array([math.cos(relative_heading), -math.sin(relative_heading), 0.0])
        self.closest_point = carrier.flat_position(closest_approach_s) + right * closest_approach_m
        self.closest_point[2] = height_m

    def relative_to_carrier(self, t):
        aircraft = self.closest_point[:, None] + self.velocity[:, None] * (t - self.t_ca)
        p = aircraft - self.carrier.flat_position(t)
        carrier_velocity = np.array([0.0, self.carrier.speed, 0.0])
        p_dot = np.broadcast_to((self.velocity - carrier_velocity)[:, None], p.shape).copy()
        return p, p_dot, np.zeros_like(p)
