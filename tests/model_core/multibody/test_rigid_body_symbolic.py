"""The C++ rigid-body core (J, f of docs/physics.md section 3) against an independent symbolic
Lagrange derivation (tests/support/symbolic/lagrange_reference.py), plus physics checks that hold
independently of any reference.

The reference itself is validated here too: its energies are checked against kinematics
obtained by finite differences of the rotation matrices, its J and f against Lagrange's
equations evaluated by finite differences along a trajectory on a moving base, and the motion
it predicts on a fixed base conserves K + U.
"""
import ctypes

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from support.symbolic import lagrange_reference as ref

pytestmark = pytest.mark.python_bound

N_RANDOM_STATES = 100
REL_TOL = 1e-10          # core vs reference
SYM_TOL = 1e-14          # symmetry of the core's J, relative


# --------------------------------------------------------------------------- the probe library
class GimbalProbeRigidBodyInput(ctypes.Structure):
    """Mirror of model_core/include/gimbal/probe_api.h (plain doubles, no padding)."""
    _fields_ = [
        ("mass", ctypes.c_double * 4),
        ("inertia", (ctypes.c_double * 6) * 4),
        ("com", (ctypes.c_double * 3) * 4),
        ("d_ab", ctypes.c_double * 3),
        ("g", ctypes.c_double),
        ("q", ctypes.c_double * 4),
        ("qd", ctypes.c_double * 4),
        ("attitude", ctypes.c_double * 3),
        ("attitude_rate", ctypes.c_double * 3),
        ("attitude_accel", ctypes.c_double * 3),
        ("v_a", ctypes.c_double * 3),
        ("a_a", ctypes.c_double * 3),
    ]


class CoreProbe:
    def __init__(self, path):
        self.lib = ctypes.CDLL(str(path))
        fn = self.lib.gimbal_probe_mass_matrix_and_bias
        fn.argtypes = [ctypes.POINTER(GimbalProbeRigidBodyInput), ctypes.POINTER(ctypes.c_double),
                       ctypes.POINTER(ctypes.c_double)]
        fn.restype = ctypes.c_int
        self.fn = fn

    def __call__(self, params, q, qd, base):
        s = GimbalProbeRigidBodyInput()
        mass = np.asarray(params["mass"], float)
        inertia = np.asarray(params["inertia"], float).reshape(4, 6)
        com = np.asarray(params["com"], float).reshape(4, 3)
        for k in range(4):
            s.mass[k] = mass[k]
            for j in range(6):
                s.inertia[k][j] = inertia[k, j]
            for j in range(3):
                s.com[k][j] = com[k, j]
        for j in range(3):
            s.d_ab[j] = float(params["d_ab"][j])
        s.g = float(params["g"])
        for j in range(4):
            s.q[j] = float(q[j])
            s.qd[j] = float(qd[j])
        for key in ("attitude", "attitude_rate", "attitude_accel", "v_a", "a_a"):
            vals = np.asarray(base.get(key, np.zeros(3)), float)
            arr = getattr(s, key)
            for j in range(3):
                arr[j] = vals[j]
        J = (ctypes.c_double * 16)()
        f = (ctypes.c_double * 4)()
        rc = self.fn(ctypes.byref(s), J, f)
        assert rc == 0, f"gimbal_probe_mass_matrix_and_bias returned {rc}"
        return np.array(J[:], float).reshape(4, 4), np.array(f[:], float)


@pytest.fixture(scope="session")
def core(probe_lib_path):
    return CoreProbe(probe_lib_path)


@pytest.fixture(scope="session")
def reference():
    ref.get_reference()          # derive once per session (also cached at module level)
    return ref.reference_mass_matrix_and_bias


@pytest.fixture(params=["reference", "core"])
def impl(request):
    """Physics checks run on both implementations: on the reference they validate it, on the
    core they catch sign errors without trusting the reference."""
    if request.param == "reference":
        return request.getfixturevalue("reference")
    return request.getfixturevalue("core")


# --------------------------------------------------------------------------- helpers
def _bias_scale(params, q, qd, base):
    """Size of the terms that make up f (see test_core_matches_reference_at_random_states)."""
    _, f = ref.reference_mass_matrix_and_bias(params, q, qd, base)
    dLdq, Cqd, Bbd = ref.reference_bias_parts(params, q, qd, base)
    return max(np.linalg.norm(f), np.linalg.norm(dLdq) + np.linalg.norm(Cqd) + np.linalg.norm(Bbd))


def _random_cases(seed, n):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        params = ref.random_params(rng)
        q, qd = ref.random_state(rng)
        base = ref.random_base(rng)
        yield params, q, qd, base


def _with(base, **kw):
    out = {k: np.array(v, float) for k, v in base.items()}
    for k, v in kw.items():
        out[k] = np.array(v, float)
    return out


def _only_body(params, k):
    p = {key: np.array(v, float) if key != "g" else v for key, v in params.items()}
    for j in range(4):
        if j != k:
            p["mass"][j] = 0.0
            p["inertia"][j] = 0.0
    return p


def _diagnose(core, params, q, qd, base):
    """Split a disagreement into terms: which body and which physical effect differ."""
    z = np.zeros(3)
    att = base["attitude"]
    level_rest = dict(attitude=z, attitude_rate=z, attitude_accel=z, v_a=z, a_a=z)
    tilted_rest = dict(attitude=att, attitude_rate=z, attitude_accel=z, v_a=z, a_a=z)
    g0 = dict(params, g=0.0)
    cases = [
        ("full state", params, q, qd, base),
        ("gravity only (qd=0, base at rest, tilted)", params, q, np.zeros(4), tilted_rest),
        ("joint-rate terms only (g=0, base at rest, level)", g0, q, qd, level_rest),
        ("joint-rate terms, tilted base at rest (g=0)", g0, q, qd, tilted_rest),
        ("base attitude-rate terms only (g=0, qd=0)", g0, q, np.zeros(4),
         _with(tilted_rest, attitude_rate=base["attitude_rate"])),
        ("base attitude-acceleration terms only (g=0, qd=0)", g0, q, np.zeros(4),
         _with(tilted_rest, attitude_accel=base["attitude_accel"])),
        ("a_a terms only (g=0, qd=0)", g0, q, np.zeros(4), _with(tilted_rest, a_a=base["a_a"])),
        ("joint rates x base rates (g=0)", g0, q, qd, _with(tilted_rest, attitude_rate=base["attitude_rate"])),
    ]
    lines = []
    for k, name in enumerate(ref.BODY_NAMES):
        cases.append((f"{name} only, full state", _only_body(params, k), q, qd, base))
    for name, p, qq, qqd, b in cases:
        Jr, fr = ref.reference_mass_matrix_and_bias(p, qq, qqd, b)
        Jc, fc = core(p, qq, qqd, b)
        dJ = np.max(np.abs(Jc - Jr))
        df = np.abs(fc - fr)
        lines.append(f"  {name}: max|dJ|={dJ:.3e} (|J|max={np.max(np.abs(Jr)):.3e}); "
                     f"|df|={np.array2string(df, precision=3)}; f_ref={np.array2string(fr, precision=6)}; "
                     f"f_core={np.array2string(fc, precision=6)}")
    return "\n".join(lines)


def _case_str(params, q, qd, base):
    return (f"params={ {k: np.asarray(v).tolist() for k, v in params.items()} }\n q={q.tolist()} qd={qd.tolist()}\n"
            f" base={ {k: np.asarray(v).tolist() for k, v in base.items()} }")


# --------------------------------------------------------------------------- the reference itself
def test_reference_derivation_time():
    t_derive, t_lambdify = ref.derivation_times()
    # Only a guard against the derivation blowing up the test time.
    assert t_derive + t_lambdify < 120.0


def _Rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _Ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _Rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class _SmoothMotion:
    """q(t), attitude(t), v_a(t) as sums of sines with analytic first and second derivatives."""

    def __init__(self, rng, n):
        self.A = rng.uniform(0.3, 1.5, (2, n))
        self.w = rng.uniform(0.5, 3.0, (2, n))
        self.ph = rng.uniform(-np.pi, np.pi, (2, n))
        self.c = rng.uniform(-np.pi, np.pi, n)

    def __call__(self, t, order=0):
        out = self.c.copy() if order == 0 else np.zeros_like(self.c)
        for k in range(2):
            a, w, ph = self.A[k], self.w[k], self.ph[k]
            x = w * t + ph
            out = out + [a * np.sin(x), a * w * np.cos(x), -a * w * w * np.sin(x)][order]
        return out


def _motion(seed):
    rng = np.random.default_rng(seed)
    return rng, _SmoothMotion(rng, 4), _SmoothMotion(rng, 3), _SmoothMotion(rng, 3)


def _state_at(t, qm, am, vm):
    q, qd, qdd = qm(t), qm(t, 1), qm(t, 2)
    base = dict(attitude=am(t), attitude_rate=am(t, 1), attitude_accel=am(t, 2), v_a=vm(t), a_a=vm(t, 1))
    return q, qd, qdd, base


def _d_dt(fun, t, h):
    """Five-point central difference."""
    return (-fun(t + 2 * h) + 8 * fun(t + h) - 8 * fun(t - h) + fun(t - 2 * h)) / (12 * h)


def test_reference_energy_matches_finite_difference_kinematics():
    """K of the reference equals the kinetic energy computed from the rotation matrices alone:
    body angular velocities from skew(w_k) = R_Gk^T dR_Gk/dt and centre-of-mass velocities from
    d/dt of the positions in G, both by finite differences along a moving-base trajectory.
    This checks (2.13) and the composition of angular velocities and velocities of section 2
    against the rotation conventions of section 1, independently of the symbolic algebra."""
    for seed in range(5):
        rng, qm, am, vm = _motion(100 + seed)
        params = ref.random_params(rng)
        I = [ref.inertia_matrix(params["inertia"][k]) for k in range(4)]

        def poses(t):
            a, am_, b, bm = qm(t)
            d, p, g = am(t)
            G0 = _Rx(d) @ _Rz(p) @ _Ry(g)
            R = [G0 @ _Rz(a), G0 @ _Rz(am_), G0 @ _Rz(a) @ _Rx(b), G0 @ _Rz(a) @ _Rx(bm)]
            return G0, R

        def positions(t):
            # position of each centre of mass relative to point a, G coordinates
            G0, R = poses(t)
            return np.array([G0 @ params["d_ab"] + R[k] @ params["com"][k] for k in range(4)])

        for t in (0.0, 0.37, 1.3):
            h = 1e-4
            q, qd, _, base = _state_at(t, qm, am, vm)
            _, R = poses(t)
            dR = _d_dt(lambda s: np.array(poses(s)[1]), t, h)
            v = _d_dt(positions, t, h) + base["v_a"]
            K = 0.0
            U = 0.0
            P = positions(t)
            for k in range(4):
                W = R[k].T @ dR[k]
                assert np.max(np.abs(W + W.T)) < 1e-8
                w = np.array([W[2, 1], W[0, 2], W[1, 0]])
                K += 0.5 * params["mass"][k] * v[k] @ v[k] + 0.5 * w @ I[k] @ w
                U += params["mass"][k] * params["g"] * P[k][2]
            K_ref, U_ref = ref.reference_energy(params, q, qd, base)
            assert abs(K_ref - K) <= 1e-8 * abs(K), (K_ref, K)
            assert abs(U_ref - U) <= 1e-12 * (abs(U) + 1.0), (U_ref, U)


def test_reference_satisfies_lagrange_by_finite_differences():
    """Along a smooth trajectory on a moving base (attitude and v_a changing), J qdd - f equals
    d/dt(dL/dqd) - dL/dq with the time derivative taken by finite differences of dL/dqd.
    This checks the assembly of J and f (the d2L/dqd dq and d2L/dqd db bdot terms).
    dL/dqd and dL/dq are themselves checked by finite differences of L."""
    for seed in range(5):
        rng, qm, am, vm = _motion(200 + seed)
        params = ref.random_params(rng)
        for t in (0.0, 0.61, 2.2):
            q, qd, qdd, base = _state_at(t, qm, am, vm)
            J, f = ref.reference_mass_matrix_and_bias(params, q, qd, base)

            def p_of(s):
                qs, qds, _, bs = _state_at(s, qm, am, vm)
                return ref.reference_momentum_and_dLdq(params, qs, qds, bs)[0]

            p, dLdq = ref.reference_momentum_and_dLdq(params, q, qd, base)
            dpdt = _d_dt(p_of, t, 1e-3)
            lhs = J @ qdd - f
            rhs = dpdt - dLdq
            scale = _bias_scale(params, q, qd, base) + np.linalg.norm(J) * np.linalg.norm(qdd)
            assert np.linalg.norm(lhs - rhs) <= 1e-8 * scale, (lhs, rhs)

            # dL/dqd, dL/dq against central differences of L
            h = 1e-5
            for i in range(4):
                e = np.zeros(4)
                e[i] = h
                L = lambda qq, qqd: ref.reference_lagrangian(params, qq, qqd, base)
                fd_p = (L(q, qd + e) - L(q, qd - e)) / (2 * h)
                fd_q = (L(q + e, qd) - L(q - e, qd)) / (2 * h)
                assert abs(fd_p - p[i]) <= 1e-7 * (np.linalg.norm(p) + 1.0)
                assert abs(fd_q - dLdq[i]) <= 1e-7 * (np.linalg.norm(dLdq) + 1.0)


def _energy_drift(mass_matrix_and_bias, seed, T=2.0):
    """Integrate J qdd = f on a fixed (tilted, v_a = 0) base with Xi = 0 and return the largest
    relative change of K + U (K, U from the reference energy, i.e. docs/physics.md section 3.2)."""
    rng = np.random.default_rng(seed)
    params = ref.random_params(rng)
    q0, qd0 = ref.random_state(rng)
    base = ref.fixed_base(attitude=rng.uniform(-np.pi, np.pi, 3))

    def rhs(t, y):
        J, f = mass_matrix_and_bias(params, y[:4], y[4:], base)
        return np.concatenate([y[4:], np.linalg.solve(J, f)])

    sol = solve_ivp(rhs, (0.0, T), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-12, atol=1e-12,
                    dense_output=False, t_eval=np.linspace(0.0, T, 41))
    assert sol.success, sol.message
    E = []
    scale = 0.0
    for y in sol.y.T:
        K, U = ref.reference_energy(params, y[:4], y[4:], base)
        E.append(K + U)
        scale = max(scale, abs(K), abs(U))
    E = np.array(E)
    return np.max(np.abs(E - E[0])) / scale


def test_reference_conserves_energy_on_fixed_base():
    for seed in (1, 2, 3):
        drift = _energy_drift(ref.reference_mass_matrix_and_bias, seed)
        assert drift < 1e-9, f"seed {seed}: relative energy drift {drift:.3e}"


# --------------------------------------------------------------------------- core vs reference
def test_core_matches_reference_at_random_states(core, reference):
    """J and f of the core agree with the symbolic reference to REL_TOL, relative.

    Relative measures:
    - J: Frobenius norm of the difference over the Frobenius norm of the reference J.
    - f: f is a sum of terms of different origin (gravity, joint-rate products, base-rate
      products, base and point-a accelerations) that can cancel, so |f| alone can be much
      smaller than the terms a correct double-precision implementation adds up; its rounding
      error scales with the terms.  The scale is max(|f|, |dL/dq| + |(d2L/dqd dq) qd| +
      |sum_b (d2L/dqd db) bdot|), the three parts of f as the reference computes them.  This is
      the size of the terms, not a loosened tolerance: a missing or wrong-signed term of any
      physically relevant size changes f by far more than 1e-10 of it.
    """
    failures = []
    for n, (params, q, qd, base) in enumerate(_random_cases(12345, N_RANDOM_STATES)):
        Jr, fr = reference(params, q, qd, base)
        Jc, fc = core(params, q, qd, base)
        eJ = np.linalg.norm(Jc - Jr) / np.linalg.norm(Jr)
        ef = np.linalg.norm(fc - fr) / _bias_scale(params, q, qd, base)
        if not (eJ <= REL_TOL and ef <= REL_TOL):
            failures.append((n, eJ, ef, params, q, qd, base))
    if failures:
        n, eJ, ef, params, q, qd, base = failures[0]
        pytest.fail(
            f"{len(failures)}/{N_RANDOM_STATES} states disagree; worst relative errors "
            f"J {max(x[1] for x in failures):.3e}, f {max(x[2] for x in failures):.3e}.\n"
            f"First failing state #{n} (eJ={eJ:.3e}, ef={ef:.3e}):\n{_case_str(params, q, qd, base)}\n"
            f"Breakdown by term:\n{_diagnose(core, params, q, qd, base)}")


def test_core_mass_matrix_symmetric_positive_definite(core):
    for n, (params, q, qd, base) in enumerate(_random_cases(777, N_RANDOM_STATES)):
        J, _ = core(params, q, qd, base)
        asym = np.max(np.abs(J - J.T)) / np.max(np.abs(J))
        assert asym <= SYM_TOL, f"state {n}: J not symmetric, relative asymmetry {asym:.3e}\n{J}"
        try:
            np.linalg.cholesky(0.5 * (J + J.T))
        except np.linalg.LinAlgError:
            pytest.fail(f"state {n}: J not positive definite, eigenvalues {np.linalg.eigvalsh(J)}")


def test_reference_mass_matrix_symmetric_positive_definite(reference):
    for params, q, qd, base in _random_cases(777, 20):
        J, _ = reference(params, q, qd, base)
        assert np.max(np.abs(J - J.T)) <= SYM_TOL * np.max(np.abs(J))
        np.linalg.cholesky(J)


def test_core_conserves_energy_on_fixed_base(core):
    """Physics check of the core on its own: the motion its J and f predict on a fixed base
    keeps K + U constant (the energies of docs/physics.md section 3.2)."""
    for seed in (1, 2):
        drift = _energy_drift(core, seed)
        assert drift < 1e-9, f"seed {seed}: relative energy drift {drift:.3e}"


# --------------------------------------------------------------------------- sign-sensitive spot checks
def _spot_params(m2=2.0, d_bd=(0.0, 0.0, 0.0), I2=(0.03, 0.05, 0.07, 0.0, 0.0, 0.0), g=9.81):
    """Bodies with their centres of mass on the axis point b (except the payload's)."""
    inertia = np.array([[0.2, 0.3, 0.4, 0.0, 0.0, 0.0],
                        [1e-3, 1e-3, 2e-3, 0.0, 0.0, 0.0],
                        list(I2),
                        [2e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0]])
    return dict(mass=np.array([3.0, 0.2, m2, 0.1]), inertia=inertia, com=np.array([[0, 0, 0], [0, 0, 0],
                list(d_bd), [0, 0, 0]], float), d_ab=np.array([0.1, -0.2, 0.3]), g=g)


def test_gravity_torque_sign(impl):
    """Payload centre of mass at d_bd = [0, 0, r] (frame 2), r > 0, level fixed base, at rest.

    Position of d in frame 0: 0T2 d_bd = Rz(alpha) Rx(beta) [0, 0, r] = Rz(alpha) [0, -r sin(beta),
    r cos(beta)], so its height is r cos(beta): the centre of mass is straight above the elevation
    axis at beta = 0 (unstable equilibrium) and drops for either sign of beta.
    U = m g r cos(beta), hence f_beta = -dU/dbeta = +m g r sin(beta): zero at beta = 0 and, for a
    small positive beta, positive, i.e. gravity pushes beta further positive (the payload falls
    over).  Nothing else depends on beta or on height, so f_alpha = f_alpha_m = f_beta_m = 0.
    """
    m2, r, g = 2.0, 0.05, 9.81
    params = _spot_params(m2=m2, d_bd=(0.0, 0.0, r), g=g)
    base = ref.fixed_base()
    for alpha, alpha_m, beta_m in [(0.0, 0.0, 0.0), (0.7, -2.1, 1.3)]:
        _, f = impl(params, np.array([alpha, alpha_m, 0.0, beta_m]), np.zeros(4), base)
        assert np.max(np.abs(f)) <= 1e-13, f
        for beta in (0.01, 0.3, -0.2):
            _, f = impl(params, np.array([alpha, alpha_m, beta, beta_m]), np.zeros(4), base)
            expected = m2 * g * r * np.sin(beta)
            assert np.sign(f[2]) == np.sign(beta), f"gravity must push beta away from 0, got f={f}"
            assert abs(f[2] - expected) <= 1e-12 * abs(expected), (f[2], expected)
            assert np.max(np.abs(f[[0, 1, 3]])) <= 1e-13, f


def test_centrifugal_torque_sign(impl):
    """Level fixed base, azimuth spinning at d_alpha = W, payload at rest in elevation, centre of
    mass on the line of sight d_bd = [0, r, 0], diagonal payload inertia.

    Position of d in frame 0: Rz(alpha) [0, r cos(beta), r sin(beta)]: distance r cos(beta) from the
    spin axis, height r sin(beta).  w2 = Rx(beta)^T [0, 0, W] + [d_beta, 0, 0]
    = [d_beta, W sin(beta), W cos(beta)].  Hence the beta-dependent part of L is
    1/2 W^2 (m r^2 cos^2 + Iyy sin^2 + Izz cos^2)(beta) - m g r sin(beta), and with d_beta = 0
    f_beta = dL/dbeta = W^2 sin(beta) cos(beta) (Iyy - Izz - m r^2) - m g r cos(beta).
    With Izz + m r^2 > Iyy the spin pulls the centre of mass back to the largest radius
    (f_beta < 0 at small beta > 0 from the spin part).  The alpha equation: dL/d(d_alpha)
    is constant in time at this state and L does not depend on alpha, so f_alpha = 0.
    """
    m2, r, g, W = 2.0, 0.08, 9.81, 3.0
    I2 = (0.03, 0.05, 0.07, 0.0, 0.0, 0.0)
    params = _spot_params(m2=m2, d_bd=(0.0, r, 0.0), I2=I2, g=g)
    base = ref.fixed_base()
    for beta in (0.2, -0.4, 1.1):
        _, f = impl(params, np.array([0.3, -1.0, beta, 0.5]), np.array([W, 0.0, 0.0, 0.0]), base)
        spin = W ** 2 * np.sin(beta) * np.cos(beta) * (I2[1] - I2[2] - m2 * r ** 2)
        expected = spin - m2 * g * r * np.cos(beta)
        assert abs(f[2] - expected) <= 1e-12 * (abs(spin) + m2 * g * r), (f[2], expected)
        assert abs(f[0]) <= 1e-12, f
    # spin part alone (g = 0): sign opposite to beta
    params0 = dict(params, g=0.0)
    _, f = impl(params0, np.array([0.3, -1.0, 0.1, 0.5]), np.array([W, 0.0, 0.0, 0.0]), base)
    assert f[2] < 0, f


def test_base_yaw_acceleration_reaction(impl):
    """Level base (delta = psi = gamma = 0), at rest, starting to yaw with d2psi/dt2 = A, point b
    at point a (d_ab = 0), no gravity, joints at rest.  Then w0 = [0, 0, d_psi] and every body's
    velocity depends on d_psi only through d_alpha + d_psi (bodies 1, 2, R2) or
    d_alpha_m + d_psi (R1), so dL/d(d_psi) = p_alpha + p_alpha_m and
    f = -(J[:, 0] + J[:, 1]) * A.  In particular f_alpha = -(J_aa + J_a,am) A < 0 for A > 0:
    the free housing lags behind the accelerating base."""
    rng = np.random.default_rng(5)
    for _ in range(5):
        params = ref.random_params(rng, g=0.0)
        params["d_ab"] = np.zeros(3)
        q = rng.uniform(-np.pi, np.pi, 4)
        A = 1.7
        base = ref.fixed_base()
        base["attitude_accel"] = np.array([0.0, A, 0.0])   # [delta, psi, gamma]
        J, f = impl(params, q, np.zeros(4), base)
        expected = -(J[:, 0] + J[:, 1]) * A
        assert np.max(np.abs(f - expected)) <= 1e-12 * np.max(np.abs(expected)), (f, expected)
        assert f[0] < 0 and f[1] < 0, f


def test_constant_base_velocity_changes_nothing(impl):
    """Galilean invariance: a constant v_a (a_a unchanged) leaves J and f unchanged, on an
    arbitrarily rotating and accelerating base."""
    for params, q, qd, base in _random_cases(31, 20):
        J0, f0 = impl(params, q, qd, _with(base, v_a=np.zeros(3)))
        J1, f1 = impl(params, q, qd, base)
        J2, f2 = impl(params, q, qd, _with(base, v_a=100.0 * base["v_a"]))
        scale = _bias_scale(params, q, qd, _with(base, v_a=np.zeros(3)))
        assert np.max(np.abs(J1 - J0)) <= 1e-14 * np.max(np.abs(J0))
        assert np.linalg.norm(f1 - f0) <= 1e-12 * scale, (f0, f1)
        # a large velocity: the v_a terms cancel exactly in exact arithmetic; allow rounding of
        # terms of size |v_a| * |base rate| * m * |d|
        assert np.linalg.norm(f2 - f0) <= 1e-11 * max(scale, 100.0 * np.linalg.norm(base["v_a"]) *
                                                      np.sum(params["mass"])), (f0, f2)


def test_upward_acceleration_equals_doubled_gravity(impl):
    """Equivalence principle: point a accelerating upward at a_a = +g z_G is the same as gravity
    2 g (z_G points up, gravity is -g z_G)."""
    for params, q, qd, base in _random_cases(47, 20):
        g = params["g"]
        Ja, fa = impl(params, q, qd, _with(base, a_a=[0.0, 0.0, g]))
        Jb, fb = impl(dict(params, g=2.0 * g), q, qd, _with(base, a_a=np.zeros(3)))
        assert np.max(np.abs(Ja - Jb)) <= 1e-14 * np.max(np.abs(Ja))
        assert np.linalg.norm(fa - fb) <= 1e-12 * _bias_scale(params, q, qd, base), (fa, fb)
        # and it does matter: no acceleration, single g, differs
        _, fc = impl(params, q, qd, _with(base, a_a=np.zeros(3)))
        assert np.linalg.norm(fa - fc) > 1e-6 * np.linalg.norm(fa)
