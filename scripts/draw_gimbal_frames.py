"""Draws the figures of docs/physics.md and the FMU's icon from the model's own conventions.

    .venv/bin/python scripts/draw_gimbal_frames.py [--out docs/figures]

writes
  gimbal_frames.png  the bodies, joints, points and frames (3-D schematic, base tilted and turned)
  drive_train.png    one drive axis: armature circuit, rotor, gear, compliant shaft, backlash, load
  model.png          the 256 x 256 icon the build puts at the root of the FMU archive

The geometry follows the FMU: G_T_0 = Rx(delta) Rz(psi) Ry(gamma) (z_G up), frame 1 = frame 0 turned
by alpha about z_0, frame 2 = frame 1 turned by beta about x_1, line of sight along y_2. The drawing
is a schematic: sizes are not the FMU's parameters.
"""
from __future__ import annotations

import argparse
import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from gimbal2axis.scene.geometry import rx, ry, rz  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]
# No software version or date in the files: rerunning with another matplotlib changes fewer bytes.
PNG_METADATA = {"Software": None}

AXIS_COLOURS = {"x": "#c0392b", "y": "#1e8449", "z": "#1f4e99"}


class Pose:
    """Where the drawing puts each frame: rotation into G and the origin of the drawn frame in G."""

    def __init__(self, delta, psi, gamma, alpha, beta, d_ab, r_a=(0.0, 0.0, 0.0)):
        self.G0 = rx(delta) @ rz(psi) @ ry(gamma)          # frame 0 -> G
        self.G1 = self.G0 @ rz(alpha)                       # frame 1 -> G
        self.G2 = self.G1 @ rx(beta)                        # frame 2 -> G
        self.a = np.asarray(r_a, dtype=float)
        self.b = self.a + self.G0 @ np.asarray(d_ab, dtype=float)

    def in0(self, p):  # frame-0 coordinates of a point relative to a
        return self.a + self.G0 @ np.asarray(p, dtype=float)

    def in1(self, p):  # frame-1 coordinates relative to b
        return self.b + self.G1 @ np.asarray(p, dtype=float)

    def in2(self, p):  # frame-2 coordinates relative to b
        return self.b + self.G2 @ np.asarray(p, dtype=float)


# ---------------------------------------------------------------------------------------------------
# 3-D primitives

def box_faces(centre, half, to_g):
    """Faces of a box given in a body frame (centre, half sizes), mapped to G by to_g."""
    cx, cy, cz = centre
    hx, hy, hz = half
    corners = np.array([[cx + sx * hx, cy + sy * hy, cz + sz * hz]
                        for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    g = np.array([to_g(p) for p in corners])
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    return [g[list(q)] for q in quads]


def cylinder_faces(axis: str, start: float, end: float, radius: float, to_g, offset=(0.0, 0.0, 0.0), n=24):
    """Side quads and the two caps of a cylinder along a body axis ('x' or 'z')."""
    faces = []
    t = np.linspace(0.0, 2.0 * math.pi, n + 1)
    off = np.asarray(offset, dtype=float)

    def point(s, angle):
        u, v = radius * math.cos(angle), radius * math.sin(angle)
        p = np.array([s, u, v]) if axis == "x" else np.array([u, v, s])
        return to_g(p + off)

    for k in range(n):
        faces.append(np.array([point(start, t[k]), point(start, t[k + 1]), point(end, t[k + 1]), point(end, t[k])]))
    for s in (start, end):
        faces.append(np.array([point(s, angle) for angle in t[:-1]]))
    return faces


def add_faces(ax, faces, colour, alpha=1.0, edge="#333333", lw=0.3):
    ax.add_collection3d(Poly3DCollection(faces, facecolors=colour, edgecolors=edge, linewidths=lw, alpha=alpha))


def arrow3d(ax, start, vector, colour, lw=1.8, head=0.12):
    """A line with a small two-stroke head (3-D quiver heads are poor at this scale)."""
    start, vector = np.asarray(start, float), np.asarray(vector, float)
    end = start + vector
    ax.plot(*zip(start, end), color=colour, lw=lw, solid_capstyle="round")
    length = np.linalg.norm(vector)
    d = vector / length
    side = np.cross(d, [0.0, 0.0, 1.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.cross(d, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    h = head * length
    for sign in (-1, 1):
        ax.plot(*zip(end, end - h * d + sign * 0.45 * h * side), color=colour, lw=lw)


def frame3d(ax, origin, rotation, length, labels, offset=1.12, lw=1.8, fontsize=11, which="xyz"):
    for k, name in enumerate("xyz"):
        if name not in which:
            continue
        v = rotation[:, k] * length
        arrow3d(ax, origin, v, AXIS_COLOURS[name], lw=lw)
        ax.text(*(np.asarray(origin) + offset * v), labels[k], color=AXIS_COLOURS[name], fontsize=fontsize,
                ha="center", va="center")


def arc3d(ax, centre, u, v, angle, radius, colour, label, label_at=0.55, fontsize=12):
    """Arc from direction u towards v (orthonormal) over `angle`, with an arrow head and a label."""
    t = np.linspace(0.0, angle, 40)
    pts = np.array([centre + radius * (math.cos(s) * u + math.sin(s) * v) for s in t])
    ax.plot(*pts.T, color=colour, lw=1.6)
    tip, before = pts[-1], pts[-6]
    d = tip - before
    d /= np.linalg.norm(d)
    normal = np.cross(u, v)
    side = np.cross(normal, d)
    h = 0.035
    for sign in (-1, 1):
        ax.plot(*zip(tip, tip - h * d + sign * 0.5 * h * side), color=colour, lw=1.6)
    mid = centre + 1.18 * radius * (math.cos(label_at * angle) * u + math.sin(label_at * angle) * v)
    ax.text(*mid, label, color=colour, fontsize=fontsize, ha="center", va="center")


def callout(ax, anchor, text_at, text, colour="#333333", ha="left"):
    """A label away from the drawing, with a thin leader line to the part it names."""
    ax.plot(*zip(anchor, text_at), color="#888888", lw=0.7)
    ax.text(*text_at, text, color=colour, fontsize=10, ha=ha, va="center")


def draw_frames(path: pathlib.Path, azim: float = -20.0, elev: float = 18.0) -> None:
    deg = math.radians
    alpha, beta = deg(35.0), deg(25.0)
    pose = Pose(delta=deg(7.0), psi=deg(-15.0), gamma=deg(-10.0), alpha=alpha, beta=beta,
                d_ab=(0.18, 0.22, 0.34))
    fig = plt.figure(figsize=(9.0, 6.4))
    ax = fig.add_axes([-0.08, -0.16, 1.16, 1.26], projection="3d")
    ax.set_axis_off()
    _inertial_frame_and_carrier(ax, pose)
    deck_z = _drives_and_yoke(ax, pose)
    _payload(ax, pose)
    _joint_frames_and_angles(ax, pose, deck_z, alpha, beta)
    ax.set_xlim(-0.45, 0.45)
    ax.set_ylim(-0.62, 0.68)
    ax.set_zlim(-0.35, 0.70)
    ax.set_box_aspect((0.9, 1.3, 1.05), zoom=1.0)
    ax.view_init(elev=elev, azim=azim)
    fig.text(0.02, 0.015,
             "Carrier at pitch 7, yaw -15, roll -10 deg; gimbal at alpha = 35, beta = 25 deg; joint axes "
             "dash-dotted.\nFrames 1 and 2 drawn at b, where the azimuth and elevation axes meet; the rotors "
             "R1, R2 turn about these axes.",
             fontsize=9, color="#333333")
    fig.savefig(path, dpi=110, metadata=PNG_METADATA)
    plt.close(fig)


def _inertial_frame_and_carrier(ax, pose: Pose) -> None:
    # Inertial frame G, away from the carrier (its origin does not matter), and gravity.
    g_origin = np.array([0.0, -0.62, -0.10])
    frame3d(ax, g_origin, np.eye(3), 0.20, ["$x_G$", "$y_G$", "$z_G$ (up)"], offset=1.3)
    arrow3d(ax, g_origin + np.array([0.0, -0.10, 0.20]), [0.0, 0.0, -0.20], "#555555", lw=1.6)
    ax.text(*(g_origin + np.array([0.0, -0.16, 0.08])), "$g$", color="#555555", fontsize=13)
    ax.text(*(g_origin + np.array([0.0, 0.05, -0.16])), "inertial frame $G$", color="#555555", fontsize=10)

    # Carrier (body 0): a deck plate; point a is the origin of frame 0.
    deck = [pose.in0(p) for p in [(-0.25, -0.25, 0.0), (0.60, -0.25, 0.0), (0.60, 0.75, 0.0), (-0.25, 0.75, 0.0)]]
    add_faces(ax, [np.array(deck)], "#b9c3cc", alpha=0.55, edge="#59636b", lw=0.8)
    ax.text(*pose.in0((0.45, -0.22, 0.0)), "carrier (body 0)", color="#3b4650", fontsize=10)
    frame3d(ax, pose.a, pose.G0, 0.20, ["$x_0$", "$y_0$", "$z_0$"], offset=1.3)
    ax.scatter(*pose.a, color="k", s=14, depthshade=False)
    ax.text(*(pose.a + pose.G0 @ np.array([0.02, -0.07, -0.02])), "$a$", fontsize=13)

    # d_ab from a to b.
    arrow3d(ax, pose.a, pose.b - pose.a, "#7d3c98", lw=1.4, head=0.08)
    ax.text(*(0.5 * (pose.a + pose.b) + pose.G0 @ np.array([0.0, -0.16, -0.03])), r"$d_{ab}$", color="#7d3c98",
            fontsize=12)


def _drives_and_yoke(ax, pose: Pose) -> float:
    """The joint axes, the two motors and body 1; the deck's height below b in frame-1 z."""
    # Azimuth axis (z_0 through b) and elevation axis (x_1 through b), dash-dotted.
    ax.plot(*zip(pose.in1((0, 0, -0.36)), pose.in1((0, 0, 0.46))), color="#1f4e99", lw=1.0, ls="-.")
    ax.plot(*zip(pose.in1((-0.40, 0, 0)), pose.in1((0.44, 0, 0))), color="#c0392b", lw=1.0, ls="-.")
    ax.text(*pose.in1((0.0, 0.0, 0.50)), "azimuth axis", color="#1f4e99", fontsize=9, ha="center")

    # Rotor R1 with its motor housing on the deck, coaxial with the azimuth axis.
    deck_z = -pose.G0[:, 2] @ (pose.b - pose.a)  # the deck below b, in frame-1 z (frame 1 z = frame 0 z)
    add_faces(ax, cylinder_faces("z", deck_z, deck_z + 0.10, 0.065, pose.in1), "#8e9aa6", alpha=0.9)
    callout(ax, pose.in1((0.0, 0.06, deck_z + 0.05)), pose.b + np.array([0.0, 0.44, -0.48]),
            "motor 1 (on body 0):\nrotor $R1$, $\\alpha_m$")
    # Body 1: turntable and the two arms of the yoke.
    add_faces(ax, cylinder_faces("z", deck_z + 0.11, deck_z + 0.14, 0.16, pose.in1), "#e0b25c", alpha=0.9)
    for side in (-1, 1):
        add_faces(ax, box_faces((side * 0.17, 0.0, (deck_z + 0.14 + 0.05) / 2),
                                (0.018, 0.05, (0.05 - deck_z - 0.14) / 2), pose.in1), "#e0b25c", alpha=0.9)
    callout(ax, pose.in1((-0.17, -0.05, deck_z + 0.2)), pose.b + np.array([0.0, -0.55, -0.12]),
            "azimuth housing (body 1)", colour="#7a5410", ha="right")
    # Rotor R2 with its motor housing on the yoke arm, coaxial with the elevation axis.
    add_faces(ax, cylinder_faces("x", 0.19, 0.28, 0.045, pose.in1), "#8e9aa6", alpha=0.9)
    callout(ax, pose.in1((0.28, 0.0, -0.045)), pose.b + np.array([0.0, 0.44, -0.28]),
            "motor 2 (on body 1):\nrotor $R2$, $\\beta_m$")
    return deck_z


def _payload(ax, pose: Pose) -> None:
    # Body 2: the payload, line of sight along y_2.
    add_faces(ax, box_faces((0.0, 0.03, 0.0), (0.10, 0.16, 0.07), pose.in2), "#5d8aa8", alpha=0.35)
    add_faces(ax, cylinder_faces("x", -0.02, 0.02, 0.05, lambda p: pose.in2(np.array([p[1], p[0], p[2]])),
                                 offset=(0.19, 0.0, 0.0)), "#2c3e50", alpha=0.9)
    ax.plot(*zip(pose.in2((0, 0.21, 0)), pose.in2((0, 0.66, 0))), color="#1e8449", lw=1.2, ls="--")
    ax.text(*pose.in2((0.0, 0.70, 0.02)), "line of sight", color="#1e8449", fontsize=10)
    callout(ax, pose.in2((-0.10, -0.05, 0.07)), pose.b + np.array([0.0, -0.48, 0.30]), "payload (body 2)",
            colour="#1b4f72", ha="right")


def _joint_frames_and_angles(ax, pose: Pose, deck_z: float, alpha: float, beta: float) -> None:
    # Frames 1 and 2 drawn at b (only their orientation matters).
    ax.scatter(*pose.b, color="k", s=14, depthshade=False)
    ax.text(*pose.in1((0.0, -0.07, 0.04)), "$b$", fontsize=13)
    frame3d(ax, pose.b, pose.G1, 0.32, ["", "", "$z_1$"], offset=1.12, lw=1.2, which="z")
    frame3d(ax, pose.b, pose.G2, 0.44, ["$x_1 = x_2$", "$y_2$", "$z_2$"], offset=1.14, lw=2.0)
    # alpha: from y_0 to y_1 about the azimuth axis, in the plane of the turntable.
    ring = deck_z + 0.145
    centre = pose.in1((0.0, 0.0, ring))
    y0_dir, y1_dir = pose.G0[:, 1], pose.G1[:, 1]
    ax.plot(*zip(centre, centre + 0.34 * y0_dir), color=AXIS_COLOURS["y"], lw=1.0, ls=":")
    ax.text(*(centre + 0.38 * y0_dir), "$y_0$", color=AXIS_COLOURS["y"], fontsize=10)
    arrow3d(ax, centre, 0.34 * y1_dir, AXIS_COLOURS["y"], lw=1.2)
    ax.text(*(centre + 0.40 * y1_dir), "$y_1$", color=AXIS_COLOURS["y"], fontsize=10)
    arc3d(ax, centre, y0_dir, -pose.G0[:, 0], alpha, 0.28, "#111111", r"$\alpha$")
    # beta: from y_1 to y_2 about the elevation axis.
    ax.plot(*zip(pose.b, pose.b + 0.30 * y1_dir), color=AXIS_COLOURS["y"], lw=1.0, ls=":")
    arc3d(ax, pose.b, y1_dir, pose.G1[:, 2], beta, 0.36, "#111111", r"$\beta$")


# ---------------------------------------------------------------------------------------------------
# 2-D drive-train schematic

def zigzag(x0, x1, y, amplitude=0.18, teeth=5):
    xs = np.linspace(x0, x1, 2 * teeth + 1)
    ys = [y] + [y + (amplitude if k % 2 else -amplitude) for k in range(1, 2 * teeth)] + [y]
    return xs, ys


def draw_drive_train(path: pathlib.Path) -> None:
    fig, ax = plt.subplots(figsize=(11.0, 4.6))
    ax.set_xlim(-0.3, 16.3)
    ax.set_ylim(-0.2, 6.2)
    ax.set_aspect("equal")
    ax.axis("off")
    k = dict(color="#222222", lw=1.4)
    right = _armature_circuit(ax, k)
    _rotor_and_gear(ax, right)
    _shaft(ax, k)
    _backlash_and_load(ax)
    ax.text(8.0, 5.6, "one drive axis:  $j = 1$: $q_m = \\alpha_m$, $q_l = \\alpha$;   "
            "$j = 2$: $q_m = \\beta_m$, $q_l = \\beta$;   $\\theta_d = q_m/N - q_l$",
            ha="center", fontsize=11)
    fig.savefig(path, dpi=110, bbox_inches="tight", metadata=PNG_METADATA)
    plt.close(fig)


def _armature_circuit(ax, k: dict) -> float:
    """The circuit's drawing; the x of its right side (the motor)."""
    # Armature circuit: source u, resistor R, inductor L, back-emf.
    left, right, bottom, top = 0.3, 3.9, 1.6, 4.4
    ax.plot([left, left], [bottom, 2.6], **k)
    ax.plot([left, left], [3.4, top], **k)
    ax.add_patch(plt.Circle((left, 3.0), 0.4, fill=False, **k))
    ax.text(left, 3.12, "+", ha="center", va="center", fontsize=10)
    ax.text(left, 2.82, "\u2212", ha="center", va="center", fontsize=10)
    ax.text(left - 0.5, 3.0, "$u$", ha="right", va="center", fontsize=13)
    ax.plot([left, 0.9], [top, top], **k)
    xs, ys = zigzag(0.9, 1.9, top, 0.15, 4)
    ax.plot(xs, ys, **k)
    ax.text(1.4, top + 0.35, "$R$", ha="center", fontsize=13)
    ax.plot([1.9, 2.2], [top, top], **k)
    t = np.linspace(0.0, math.pi, 20)
    for n in range(4):
        cx = 2.32 + 0.24 * n
        ax.plot(cx + 0.12 * np.cos(t[::-1]), top + 0.18 * np.sin(t[::-1]), **k)
    ax.text(2.68, top + 0.45, "$L$", ha="center", fontsize=13)
    ax.plot([3.16, right], [top, top], **k)
    ax.plot([right, right], [top, 3.45], **k)
    ax.plot([right, right], [2.55, bottom], **k)
    ax.plot([left, right], [bottom, bottom], **k)
    ax.add_patch(plt.Circle((right, 3.0), 0.45, fill=False, **k))
    ax.text(right, 3.0, "M", ha="center", va="center", fontsize=12, weight="bold")
    ax.text(right - 0.65, 3.0, "$k_{emf}\\,\\dot q_m$", ha="right", va="center", fontsize=11)
    ax.annotate("", xy=(1.9, top - 0.35), xytext=(1.0, top - 0.35),
                arrowprops=dict(arrowstyle="->", color="#1f4e99", lw=1.4))
    ax.text(1.45, top - 0.7, "$i$,  $|i| \\leq i_L$", ha="center", color="#1f4e99", fontsize=11)
    ax.text(2.1, 0.85, "$|u| \\leq U_L$ (clamped)\n$L\\,di/dt = u - R\\,i - k_{emf}\\,\\dot q_m$",
            ha="center", fontsize=10, color="#333333")
    return right


def _rotor_and_gear(ax, right: float) -> None:
    # Rotor: shaft from the motor to the rotor inertia, torque k_torque i.
    ax.plot([right + 0.45, 5.0], [3.0, 3.0], color="#222222", lw=3)
    ax.add_patch(plt.Rectangle((5.0, 2.2), 1.1, 1.6, facecolor="#8e9aa6", edgecolor="#222222", lw=1.4))
    ax.text(5.55, 4.05, "rotor $R_j$\n$q_m$", ha="center", va="bottom", fontsize=11)
    ax.text(5.55, 1.85, "$T_{ele}$", ha="center", va="top", fontsize=10)
    ax.text(5.55, 1.35, "$= k_{torque}\\, i$", ha="center", va="top", fontsize=10)
    ax.text(5.55, 0.75, "friction\n$T_{as}, T_{av}$", ha="center", va="top", fontsize=9, color="#555555")

    # Gear pair, ratio N.
    ax.plot([6.1, 6.9], [3.0, 3.0], color="#222222", lw=3)
    ax.add_patch(plt.Circle((7.15, 3.0), 0.28, facecolor="#d5d8dc", edgecolor="#222222", lw=1.4))
    ax.add_patch(plt.Circle((7.15, 1.95), 0.78, facecolor="#d5d8dc", edgecolor="#222222", lw=1.4))
    ax.text(7.15, 4.05, "gear $N$\n$\\theta_1 = q_m / N$", ha="center", va="bottom", fontsize=11)
    ax.plot([7.93, 8.6], [1.95, 1.95], color="#222222", lw=3)


def _shaft(ax, k: dict) -> None:
    # Massless shaft E: spring k_s parallel to damper c_s.
    ax.plot([8.6, 8.6], [1.45, 2.45], **k)
    ax.plot([8.6, 8.9], [2.45, 2.45], **k)
    xs, ys = zigzag(8.9, 10.1, 2.45, 0.15, 5)
    ax.plot(xs, ys, **k)
    ax.plot([10.1, 10.4], [2.45, 2.45], **k)
    ax.text(9.5, 2.78, "$k_s$", ha="center", fontsize=12)
    ax.plot([8.6, 9.2], [1.45, 1.45], **k)
    ax.plot([9.2, 9.2, 9.9, 9.9, 9.2, 9.2], [1.25, 1.65, 1.65, 1.25, 1.25, 1.25], **k)  # dashpot cylinder
    ax.plot([9.55, 9.55], [1.3, 1.6], color="#222222", lw=2.2)
    ax.plot([9.55, 10.4], [1.45, 1.45], **k)
    ax.text(9.5, 0.85, "$c_s$", ha="center", fontsize=12)
    ax.plot([10.4, 10.4], [1.45, 2.45], **k)
    ax.text(9.3, 3.45, "shaft $E$: $T_E = k_s(\\theta_d-\\theta_b) + c_s(\\dot\\theta_d-\\dot\\theta_b)$",
            ha="center", fontsize=10)


def _backlash_and_load(ax) -> None:
    # Backlash: a tooth on the shaft end theta_2 moving in a slot of the load, free travel +-eta.
    ax.plot([10.4, 10.75, 10.75, 11.7, 11.7], [1.95, 1.95, 2.85, 2.85, 2.15], color="#222222", lw=3)
    ax.add_patch(plt.Rectangle((11.55, 1.75), 0.3, 0.4, facecolor="#222222"))
    slot_x0, slot_x1 = 11.1, 12.3
    ax.plot([slot_x0, slot_x0, slot_x1, slot_x1], [2.5, 1.4, 1.4, 2.5], color="#7a5410", lw=2.2)
    ax.plot([slot_x1, 12.9], [1.95, 1.95], color="#7a5410", lw=3)
    ax.annotate("", xy=(slot_x0, 1.95), xytext=(11.55, 1.95), arrowprops=dict(arrowstyle="<->", lw=0.9))
    ax.annotate("", xy=(slot_x1, 1.95), xytext=(11.85, 1.95), arrowprops=dict(arrowstyle="<->", lw=0.9))
    ax.text(11.7, 1.25, "gap $\\pm\\eta$ ($2\\eta$ in all)\n$\\theta_b = \\theta_2 - q_l$", ha="center", va="top",
            fontsize=10)
    ax.text(10.5, 2.9, "$\\theta_2$", ha="center", va="bottom", fontsize=11)
    ax.text(11.7, 3.0, "backlash", ha="center", fontsize=10)

    # Load: body 1 or 2.
    ax.add_patch(plt.Rectangle((12.9, 1.0), 1.8, 1.9, facecolor="#e0b25c", edgecolor="#222222", lw=1.4))
    ax.text(13.8, 1.95, "load\nbody 1 / 2\n$q_l$", ha="center", va="center", fontsize=11)
    ax.text(13.8, 3.05, "$+T_E$ on the load\n$-T_E/N$ on the rotor", ha="center", va="bottom", fontsize=10)
    ax.text(13.8, 0.85, "friction\n$T_{as}, T_{av}$", ha="center", va="top", fontsize=9, color="#555555")


# ---------------------------------------------------------------------------------------------------
# Icon

def draw_icon(path: pathlib.Path, size_px: int = 256) -> None:
    """A pedestal on a wave with its line of sight: readable at 64 px, exactly size_px square."""
    fig = plt.figure(figsize=(size_px / 100.0, size_px / 100.0), dpi=100)
    ax = fig.add_axes([0.0, 0.0, 1.0, 1.0])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.axis("off")
    ax.add_patch(plt.Rectangle((0, 0), 1, 1, facecolor="#eaf2f8", edgecolor="none"))
    x = np.linspace(0, 1, 200)
    wave = 0.17 + 0.035 * np.sin(2 * math.pi * 2.0 * x + 0.6)
    ax.fill_between(x, 0, wave, color="#2e86c1")
    # Tilted deck and pedestal (the carrier rolls, the line of sight does not).
    roll = math.radians(-9.0)
    c, s = math.cos(roll), math.sin(roll)

    def on_deck(px, py):
        return (0.5 + c * (px - 0.5) - s * (py - 0.3), 0.3 + s * (px - 0.5) + c * (py - 0.3))

    deck = [on_deck(0.12, 0.24), on_deck(0.88, 0.24), on_deck(0.88, 0.30), on_deck(0.12, 0.30)]
    ax.add_patch(plt.Polygon(deck, facecolor="#5d6d7e", edgecolor="#2c3e50", lw=1.5))
    yoke = [on_deck(0.36, 0.30), on_deck(0.64, 0.30), on_deck(0.64, 0.58), on_deck(0.59, 0.58),
            on_deck(0.59, 0.36), on_deck(0.41, 0.36), on_deck(0.41, 0.58), on_deck(0.36, 0.58)]
    ax.add_patch(plt.Polygon(yoke, facecolor="#e0b25c", edgecolor="#7a5410", lw=1.5))
    pivot = on_deck(0.5, 0.55)
    elevation = math.radians(18.0)   # in G: the payload holds its aim whatever the roll
    ce, se = math.cos(elevation), math.sin(elevation)

    def on_payload(px, py):
        return (pivot[0] + ce * px - se * py, pivot[1] + se * px + ce * py)

    body = [on_payload(-0.13, -0.07), on_payload(0.17, -0.07), on_payload(0.17, 0.07), on_payload(-0.13, 0.07)]
    ax.add_patch(plt.Polygon(body, facecolor="#1f4e79", edgecolor="#0b2540", lw=1.5))
    lens = [on_payload(0.17, -0.05), on_payload(0.22, -0.06), on_payload(0.22, 0.06), on_payload(0.17, 0.05)]
    ax.add_patch(plt.Polygon(lens, facecolor="#0b2540", edgecolor="#0b2540"))
    start, end = on_payload(0.23, 0.0), on_payload(0.62, 0.0)
    ax.plot([start[0], end[0]], [start[1], end[1]], color="#c0392b", lw=2.2, ls=(0, (3, 2)))
    ax.add_patch(plt.Circle(pivot, 0.025, facecolor="#f4d03f", edgecolor="#7a5410", lw=1.2))
    fig.savefig(path, dpi=100, metadata=PNG_METADATA)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "docs" / "figures",
                        help="output directory (default: docs/figures)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    draw_frames(args.out / "gimbal_frames.png")
    draw_drive_train(args.out / "drive_train.png")
    draw_icon(args.out / "model.png")
    for name in ("gimbal_frames.png", "drive_train.png", "model.png"):
        print(args.out / name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
