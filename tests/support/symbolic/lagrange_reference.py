"""Independent symbolic reference for the rigid-body dynamics of docs/physics.md sections 1-3.

The kinetic energy K and the potential energy U of the four moving bodies (azimuth housing 1,
rotor R1, elevation payload 2, rotor R2) are built with SymPy literally as docs/physics.md sections 1-3 write them,
and Lagrange's equations are formed by differentiating L = K - U:

    d/dt (dL/dqd) - dL/dq = Xi
    J = d2L/dqd2
    f = dL/dq - (d2L/dqd dq) qd - sum_b (d2L/dqd db) bdot          so that  J qdd = Xi + f

where the base variables b are delta, psi, gamma (bdot = their rates), their rates
(bdot = their accelerations) and the three components of v_a (bdot = a_a).  The position of
point a only adds a q-independent term to U and is dropped.

Nothing here is simplified symbolically (too slow); the expressions are turned into numeric
functions with ``sympy.lambdify(..., cse=True)``, built once per process on first use.

Numeric conventions follow ``model_core/include/gimbal/probe_api.h``:

params = dict(
    mass    = (4,)   body 1, rotor R1, body 2, rotor R2 (q order),
    inertia = (4, 6) I_xx, I_yy, I_zz, I_xy, I_xz, I_yz about the centre of mass, own frame,
    com     = (4, 3) d_bc (frame 1), d_be (frame R1), d_bd (frame 2), d_bf (frame R2),
    d_ab    = (3,)   frame 0,
    g       = float)
q, qd: (4,) [alpha, alpha_m, beta, beta_m] and rates
base = dict(attitude=(3,) [delta, psi, gamma], attitude_rate=(3,), attitude_accel=(3,),
            v_a=(3,) G coordinates, a_a=(3,) G coordinates)
"""
from __future__ import annotations

import threading
import time

import numpy as np
import sympy as sp

N_Q = 4
BODY_NAMES = ("body1", "rotorR1", "body2", "rotorR2")


# --------------------------------------------------------------------------- rotations
def Rx(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class _Symbols:
    """All symbols of the problem, in the flat argument order of the lambdified functions."""

    def __init__(self):
        self.m = list(sp.symbols("m1 mR1 m2 mR2", real=True))
        # inertia[k] = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) of body k
        self.inertia = [list(sp.symbols(f"Ixx_{n} Iyy_{n} Izz_{n} Ixy_{n} Ixz_{n} Iyz_{n}", real=True))
                        for n in ("1", "R1", "2", "R2")]
        self.com = [list(sp.symbols(f"r{n}_x r{n}_y r{n}_z", real=True)) for n in ("1", "R1", "2", "R2")]
        self.d_ab = list(sp.symbols("dab_x dab_y dab_z", real=True))
        self.g = sp.Symbol("g", real=True)
        self.q = list(sp.symbols("alpha alpha_m beta beta_m", real=True))
        self.qd = list(sp.symbols("dalpha dalpha_m dbeta dbeta_m", real=True))
        self.att = list(sp.symbols("delta psi gamma", real=True))
        self.att_rate = list(sp.symbols("ddelta dpsi dgamma", real=True))
        self.att_acc = list(sp.symbols("dddelta ddpsi ddgamma", real=True))
        self.v_a = list(sp.symbols("va_x va_y va_z", real=True))
        self.a_a = list(sp.symbols("aa_x aa_y aa_z", real=True))

    def params_list(self):
        out = list(self.m)
        for k in range(4):
            out += self.inertia[k]
        for k in range(4):
            out += self.com[k]
        return out + self.d_ab + [self.g]

    def args(self):
        return (self.params_list() + self.q + self.qd + self.att + self.att_rate + self.att_acc
                + self.v_a + self.a_a)


def _inertia_matrix(Ixx, Iyy, Izz, Ixy, Ixz, Iyz):
    # docs/physics.md section 3.2: the product of inertia is the tensor element itself.
    return sp.Matrix([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])


def build_energies(S: _Symbols):
    """Return (K, U) as SymPy expressions, built literally from docs/physics.md sections 1-3."""
    alpha, alpha_m, beta, beta_m = S.q
    dalpha, dalpha_m, dbeta, dbeta_m = S.qd
    delta, psi, gamma = S.att
    ddelta, dpsi, dgamma = S.att_rate

    # frame maps: jTi maps coordinates in frame i to frame j
    T10 = Rz(alpha).T
    TR10 = Rz(alpha_m).T
    T21 = Rx(beta).T
    TR21 = Rx(beta_m).T
    TG0 = Rx(delta) * Rz(psi) * Ry(gamma)
    T0G = TG0.T

    # (2.13) base angular velocity in frame 0
    w0 = sp.Matrix([
        ddelta * sp.cos(psi) * sp.cos(gamma) - dpsi * sp.sin(gamma),
        -ddelta * sp.sin(psi) + dgamma,
        ddelta * sp.cos(psi) * sp.sin(gamma) + dpsi * sp.cos(gamma),
    ])
    w1 = T10 * w0 + sp.Matrix([0, 0, dalpha])
    wR1 = TR10 * w0 + sp.Matrix([0, 0, dalpha_m])
    w2 = T21 * w1 + sp.Matrix([dbeta, 0, 0])
    wR2 = TR21 * w1 + sp.Matrix([dbeta_m, 0, 0])

    d_ab = sp.Matrix(S.d_ab)
    v_a = sp.Matrix(S.v_a)
    d_bc, d_be, d_bd, d_bf = (sp.Matrix(c) for c in S.com)

    v_b = T0G * v_a + w0.cross(d_ab)                     # frame 0 (2.18)
    v_c = T10 * v_b + w1.cross(d_bc)                     # frame 1
    v_e = TR10 * v_b + wR1.cross(d_be)                   # frame R1
    v_d = T21 * T10 * v_b + w2.cross(d_bd)               # frame 2
    v_f = TR21 * T10 * v_b + wR2.cross(d_bf)             # frame R2

    bodies = [  # (mass, inertia, v of com in own frame, w in own frame, rotation own->0, com vector)
        (S.m[0], _inertia_matrix(*S.inertia[0]), v_c, w1, T10.T, d_bc),
        (S.m[1], _inertia_matrix(*S.inertia[1]), v_e, wR1, TR10.T, d_be),
        (S.m[2], _inertia_matrix(*S.inertia[2]), v_d, w2, (T21 * T10).T, d_bd),
        (S.m[3], _inertia_matrix(*S.inertia[3]), v_f, wR2, (TR21 * T10).T, d_bf),
    ]
    K = sp.Integer(0)
    U = sp.Integer(0)
    for m, I, v, w, R_to0, d in bodies:
        K += sp.Rational(1, 2) * m * (v.T * v)[0, 0] + sp.Rational(1, 2) * (w.T * I * w)[0, 0]
        # height (z_G, up) of the centre of mass relative to point a: z_G of GT0 (d_ab + 0T_body d)
        r_G = TG0 * (d_ab + R_to0 * d)
        U += m * S.g * r_G[2]
    return K, U


class _Reference:
    def __init__(self):
        t0 = time.perf_counter()
        S = _Symbols()
        self.S = S
        K, U = build_energies(S)
        L = K - U
        q, qd = S.q, S.qd
        # base variables and their time derivatives
        base_vars = S.att + S.att_rate + S.v_a
        base_dots = S.att_rate + S.att_acc + S.a_a

        p = [sp.diff(L, v) for v in qd]                       # dL/dqd
        dLdq = [sp.diff(L, v) for v in q]                     # dL/dq
        J = sp.Matrix(N_Q, N_Q, lambda i, j: sp.diff(p[i], qd[j]))
        Cqd = [sum(sp.diff(p[i], q[j]) * qd[j] for j in range(N_Q)) for i in range(N_Q)]
        Bbd = [sum(sp.diff(p[i], b) * bd for b, bd in zip(base_vars, base_dots)) for i in range(N_Q)]
        f = [dLdq[i] - Cqd[i] - Bbd[i] for i in range(N_Q)]
        self.t_derive = time.perf_counter() - t0

        t1 = time.perf_counter()
        args = S.args()
        # one function returning J (16), f (4), and the three parts of f (for error scaling)
        outs = list(J) + f + dLdq + Cqd + Bbd
        self._fn = sp.lambdify(args, outs, modules="math", cse=True)
        self._energy_fn = sp.lambdify(args, [K, U], modules="math", cse=True)
        self._p_fn = sp.lambdify(args, p + dLdq, modules="math", cse=True)
        self._L_fn = sp.lambdify(args, L, modules="math", cse=True)
        self.t_lambdify = time.perf_counter() - t1
        self.K, self.U = K, U


_REF: _Reference | None = None
_LOCK = threading.Lock()


def get_reference() -> _Reference:
    """Build (once per process) and return the lambdified reference."""
    global _REF
    with _LOCK:
        if _REF is None:
            _REF = _Reference()
        return _REF


def derivation_times():
    r = get_reference()
    return r.t_derive, r.t_lambdify


# --------------------------------------------------------------------------- numeric API
def _flat_args(params, q, qd, base):
    vals = list(np.asarray(params["mass"], float).reshape(4))
    vals += list(np.asarray(params["inertia"], float).reshape(24))
    vals += list(np.asarray(params["com"], float).reshape(12))
    vals += list(np.asarray(params["d_ab"], float).reshape(3))
    vals += [float(params["g"])]
    vals += list(np.asarray(q, float).reshape(4)) + list(np.asarray(qd, float).reshape(4))
    for key in ("attitude", "attitude_rate", "attitude_accel", "v_a", "a_a"):
        vals += list(np.asarray(base.get(key, np.zeros(3)), float).reshape(3))
    return [float(v) for v in vals]


def reference_mass_matrix_and_bias(params, q, qd, base):
    """J (4x4) and f (4) with J qdd = Xi + f, from the symbolic Lagrangian."""
    out = get_reference()._fn(*_flat_args(params, q, qd, base))
    return np.array(out[:16], float).reshape(4, 4), np.array(out[16:20], float)


def reference_bias_parts(params, q, qd, base):
    """The three parts of f: dL/dq, (d2L/dqd dq) qd and sum_b (d2L/dqd db) bdot (f = a - b - c)."""
    out = np.array(get_reference()._fn(*_flat_args(params, q, qd, base)), float)
    return out[20:24], out[24:28], out[28:32]


def reference_energy(params, q, qd, base):
    """(K, U) of the four bodies (U relative to the height of point a)."""
    K, U = get_reference()._energy_fn(*_flat_args(params, q, qd, base))
    return float(K), float(U)


def reference_momentum_and_dLdq(params, q, qd, base):
    """(dL/dqd, dL/dq), each (4,)."""
    out = np.array(get_reference()._p_fn(*_flat_args(params, q, qd, base)), float)
    return out[:4], out[4:]


def reference_lagrangian(params, q, qd, base):
    return float(get_reference()._L_fn(*_flat_args(params, q, qd, base)))


# --------------------------------------------------------------------------- random draws
def random_rotation(rng):
    """Uniformly random rotation matrix (QR of a Gaussian matrix, det fixed to +1)."""
    A = rng.standard_normal((3, 3))
    Q, R = np.linalg.qr(A)
    Q = Q * np.sign(np.diag(R))
    if np.linalg.det(Q) < 0:
        Q[:, 0] = -Q[:, 0]
    return Q


def random_inertia(rng, scale=1.0):
    """Random physically valid inertia tensor (I_xx, I_yy, I_zz, I_xy, I_xz, I_yz).

    Built from a random non-negative mass distribution's second moments: principal moments
    A = b + c, B = a + c, C = a + b with a, b, c > 0 satisfy the triangle inequality strictly;
    then rotated by a random rotation, which gives nonzero products of inertia.
    """
    abc = rng.uniform(0.1, 1.0, 3) * scale
    principal = np.array([abc[1] + abc[2], abc[0] + abc[2], abc[0] + abc[1]])
    R = random_rotation(rng)
    I = R @ np.diag(principal) @ R.T
    I = 0.5 * (I + I.T)
    return np.array([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])


def inertia_matrix(six):
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = six
    return np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])


def random_params(rng, g=9.81):
    mass = rng.uniform(0.2, 5.0, 4)
    inertia = np.array([random_inertia(rng, scale=rng.uniform(1e-3, 5e-2)) for _ in range(4)])
    com = rng.uniform(-0.1, 0.1, (4, 3))
    d_ab = rng.uniform(-0.5, 0.5, 3)
    return dict(mass=mass, inertia=inertia, com=com, d_ab=d_ab, g=float(g))


def random_state(rng):
    q = rng.uniform(-np.pi, np.pi, 4)
    qd = rng.standard_normal(4)
    return q, qd


def random_base(rng):
    return dict(
        attitude=rng.uniform(-np.pi, np.pi, 3),
        attitude_rate=rng.standard_normal(3),
        attitude_accel=rng.standard_normal(3),
        v_a=rng.normal(0.0, 2.0, 3),
        a_a=rng.normal(0.0, 2.0, 3),
    )


def fixed_base(attitude=(0.0, 0.0, 0.0), v_a=(0.0, 0.0, 0.0)):
    return dict(attitude=np.array(attitude, float), attitude_rate=np.zeros(3), attitude_accel=np.zeros(3),
                v_a=np.array(v_a, float), a_a=np.zeros(3))


if __name__ == "__main__":
    t = time.perf_counter()
    r = get_reference()
    print(f"derive {r.t_derive:.2f} s, lambdify {r.t_lambdify:.2f} s, total {time.perf_counter() - t:.2f} s")
    rng = np.random.default_rng(1)
    P = random_params(rng)
    q, qd = random_state(rng)
    b = random_base(rng)
    t = time.perf_counter()
    for _ in range(100):
        J, f = reference_mass_matrix_and_bias(P, q, qd, b)
    print(f"eval {1e3 * (time.perf_counter() - t) / 100:.3f} ms")
    print(J)
    print(f)
