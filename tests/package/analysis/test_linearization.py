"""The linear model A, B, C, D (gimbal2axis.analysis.linearization, through libgimbal_probe.so) against the FMU itself,
and against the textbook transfer function of a single rigid axis with a quasi-static motor."""
import math

import numpy as np
import pytest
from scipy.linalg import expm

from gimbal2axis.analysis import linearization
from gimbal2axis.errors import SceneError

H = 5e-4   # the step over which the FMU's flow is differenced

# A point away from every switching surface that exercises all the terms: a moving, tilted carrier,
# both gears in backlash contact (theta_b = +eta), inductive motors, dry friction slipping, rates and
# voltages non-zero, the payload off its balance point.
RICH_POINT = {
    "solver.rtol": 1e-11, "solver.atol": 1e-13,
    "alpha": 0.3, "beta": -0.4, "alpha_dot": 0.8, "beta_dot": -0.5,
    "alpha_m_dot": 0.8 * 100 + 2.0, "beta_m_dot": -0.5 * 100 + 3.0,
    "i_R1": 0.4, "i_R2": -0.3,
    "u_R1": 3.0, "u_R2": -2.0,
    "base.delta": 0.05, "base.psi": 0.2, "base.gamma": -0.1,
    "base.delta_dot": 0.1, "base.psi_dot": -0.2, "base.gamma_dot": 0.3,
    "base.delta_ddot": 0.5, "base.psi_ddot": 0.4, "base.gamma_ddot": -0.6,
    "base.v_a[1]": 2.0, "base.v_a[2]": -1.0, "base.v_a[3]": 0.5,
    "base.a_a[1]": 0.3, "base.a_a[2]": -0.2, "base.a_a[3]": 0.7,
}

# Rigid gears and quasi-static motors: the currents and shaft torques depend on the inputs directly (D).
RIGID_POINT = {
    "solver.rtol": 1e-11, "solver.atol": 1e-13,
    "gear1.model": 0, "gear2.model": 0, "motor1.model": 0, "motor2.model": 0, "dry_friction": False,
    "alpha": -0.2, "beta": 0.6, "alpha_dot": 0.3, "beta_dot": 0.2, "u_R1": 1.5, "u_R2": 2.5,
    "base.gamma": 0.1, "base.gamma_dot": 0.2, "base.delta_ddot": -0.3, "base.a_a[3]": 1.0,
}


# Both rotors stuck by dry friction (the hold mode: numerical damping keeps them still within +-w_min,
# the friction torque cancels the others), both gears in their backlash gap, a small running current.
STUCK_POINT = {
    "solver.rtol": 1e-11, "solver.atol": 1e-13, "base.fixed": True,
    "body2.d_bd[2]": 0.0, "body2.d_bd[3]": 0.0,
    "u_R1": 0.02, "u_R2": -0.02, "i_R1": 0.01, "i_R2": -0.01, "alpha_dot": 0.01, "beta_dot": -0.02,
    "gear1.start": 2, "gear2.start": 2,  # as_given: the rotors at rest (stuck), not in mesh with the loads
}


def with_contact(fmu, point):
    """The rich point with both backlash positions at their +eta flank."""
    values = dict(point)
    for axis, load in ((1, "alpha"), (2, "beta")):
        eta, ratio = float(fmu.start(f"gear{axis}.eta")), float(fmu.start(f"gear{axis}.N"))
        values[f"theta_b{axis}"] = eta
        values[load + "_m"] = ratio * (values[load] + eta + 1e-3)   # the shaft twisted into the flank
    return values


def split(fmu, values):
    inputs = {k: v for k, v in values.items() if fmu.variable(k).causality == "input"}
    return {k: v for k, v in values.items() if k not in inputs}, inputs


def start(fmu, slave, values):
    """Fresh initialization of `slave` at `values` (start values and parameters, inputs set in
    initialization mode)."""
    before, inputs = split(fmu, values)
    slave.reset()
    slave.setupExperiment(startTime=0.0)
    fmu.set_values(slave, before)
    slave.enterInitializationMode()
    fmu.set_values(slave, inputs)
    slave.exitInitializationMode()


def chain_matrix(inputs):
    """d(u)/dt within a step: the base angles move with their rates, the rates with the accelerations,
    point a's velocity with its acceleration (the within-step semantics of docs/model_overview.md); voltages are held."""
    M = np.zeros((len(inputs), len(inputs)))
    for k, name in enumerate(inputs):
        for low, high in (("", "_dot"), ("_dot", "_ddot")):
            for angle in ("base.delta", "base.psi", "base.gamma"):
                if name == angle + high:
                    M[inputs.index(angle + low), k] = 1.0
        if name.startswith("base.a_a["):
            M[inputs.index(name.replace("a_a", "v_a")), k] = 1.0
    return M


def flow_differences(fmu, slave, values, model):
    """Central differences of the FMU over one step of H, per unit of perturbation: the change of the states
    and outputs at the end of the step, and the outputs at t = 0.
    - a state: its start value moved by +-d, the instance initialized afresh;
    - an input: the instance set back to the initialized point (fmi2SetFMUstate) and the input set +-d
      before the step (for the outputs at t = 0: set +-d in initialization mode)."""
    states, inputs, outputs = model.states, model.inputs, model.outputs
    measured = {}
    start(fmu, slave, values)
    initialized = slave.getFMUstate()
    # At a flank (contact) theta_b cannot move either way without leaving the mode: not perturbed.
    # On a fixed base the FMU refuses carrier inputs (their columns are 0, checked by the caller).
    moved_inputs = [u for u in inputs if not (values.get("base.fixed") and u.startswith("base."))]
    for name in [s for s in states if not (s.startswith("theta_b") and model.modes[f"gear{s[-1]}.contact"] != 0)] + moved_inputs:
        d = 1e-5 * max(1.0, abs(values.get(name, 0.0)))
        ends, starts = [], []
        for sign in (1, -1):
            shifted = dict(values)
            shifted[name] = values.get(name, 0.0) + sign * d
            start(fmu, slave, shifted)
            starts.append(np.array(fmu.get_values(slave, outputs)))
            if name in inputs:
                slave.setFMUstate(initialized)
                fmu.set_values(slave, {name: shifted[name]})
            slave.doStep(0.0, H)
            ends.append(np.array(fmu.get_values(slave, states + outputs)))
        measured[name] = ((ends[0] - ends[1]) / (2 * d), (starts[0] - starts[1]) / (2 * d))
    slave.freeFMUstate(initialized)
    return measured


def advanced_inputs(values, inputs, elapsed):
    """The inputs as they stand `elapsed` seconds into a step that started with `values`."""
    u = np.array([values.get(name, 0.0) for name in inputs])
    M = chain_matrix(inputs)
    return dict(zip(inputs, expm(M * elapsed) @ u))


def predicted(start_model, end_model, name):
    """The linear models' change of (states, outputs) at the end of a step of H per unit perturbation of the
    state or input `name`, with the inputs moving within the step as the FMU moves them. The variational
    equation along the step has A(t), B(t) varying with the trajectory: their mean over the two ends makes
    the prediction second-order in H (a single model at the start would be off by ~ |dx/dt| H, 1e-3 here).
    The outputs at the end use the end's C and D."""
    n, m = len(start_model.states), len(start_model.inputs)
    block = np.zeros((n + m, n + m))
    block[:n, :n] = (start_model.A + end_model.A) / 2
    block[:n, n:] = (start_model.B + end_model.B) / 2
    block[n:, n:] = chain_matrix(start_model.inputs)
    z0 = np.zeros(n + m)
    z0[start_model.states.index(name) if name in start_model.states else n + start_model.inputs.index(name)] = 1.0
    z = expm(block * H) @ z0
    dx, du = z[:n], z[n:]
    return np.concatenate([dx, end_model.C @ dx + end_model.D @ du])


@pytest.mark.parametrize("point", ["rich", "rigid", "stuck"])
def test_matrices_match_central_differences_of_the_fmu(gimbal_fmu, point):
    """A and B: the FMU's state after one step from perturbed start values / inputs against exp of the linear
    model over the step (the inputs' within-step motion included), compared on the change (x(H) - x(0)),
    whose size is A H: a wrong entry of A or B of relative size 1e-3 would show. C and D: the outputs right
    after initialization at perturbed start values / inputs (the FMU evaluates them at the start point)."""
    fmu = gimbal_fmu
    values = {"rich": with_contact(fmu, RICH_POINT), "rigid": dict(RIGID_POINT), "stuck": dict(STUCK_POINT)}[point]
    model = linearization.linearize(values)
    assert model.time == 0.0
    if point == "rich":
        assert model.modes["gear1.contact"] == 1 and model.modes["gear2.contact"] == 1
        assert model.modes["rotor1.friction"] == "slipping +" and model.modes["rotor2.friction"] == "slipping -"
        assert len(model.states) == 12
    elif point == "rigid":
        assert model.states == ["alpha", "beta", "alpha_dot", "beta_dot"]
    else:
        assert model.modes["rotor1.friction"] == "stuck" and model.modes["rotor2.friction"] == "stuck"
        assert model.modes["gear1.contact"] == 0 and model.modes["gear2.contact"] == 0
        carrier = [k for k, u in enumerate(model.inputs) if u.startswith("base.")]
        assert np.all(model.B[:, carrier] == 0) and np.all(model.D[:, carrier] == 0)
    slave = fmu.instantiate("linearization")
    try:
        start(fmu, slave, values)
        slave.doStep(0.0, H)
        assert fmu.get_values(slave, ["events.total"]) == [0.0], "the step must stay within the modes"
        end_model = linearization.linearize_instance(fmu, slave, advanced_inputs(values, model.inputs, H))
        assert end_model.time == H and end_model.modes == model.modes
        measured = flow_differences(fmu, slave, values, model)
    finally:
        slave.freeInstance()
    errors: dict = {}
    n = len(model.states)
    for name, (end, at_start) in measured.items():
        expected = predicted(model, end_model, name)
        if name in model.states:
            k = model.states.index(name)
            # the perturbation itself (and the outputs' direct response to it) is not what is tested
            unchanged = np.concatenate([np.eye(n)[k], model.C[:, k]])
            direct = model.C[:, k]
        else:
            unchanged = np.zeros(n + len(model.outputs))
            direct = model.D[:, model.inputs.index(name)]
        scale = max(np.max(np.abs(expected - unchanged)), 1e-12)
        err = np.max(np.abs(end - expected)) / scale
        errors.setdefault("flow", []).append((err, name))
        dscale = max(np.max(np.abs(direct)), 1.0)
        derr = np.max(np.abs(at_start - direct)) / dscale
        errors.setdefault("direct", []).append((derr, name))
    worst_flow, worst_direct = max(errors["flow"]), max(errors["direct"])
    # The measurement's own noise is a few 1e-4 in the shaft torques (k times a deflection that is a small
    # difference of integrated angles); everything else agrees to ~1e-6.
    assert worst_flow[0] < 2e-3, f"{worst_flow[1]}: the flow over one step differs by {worst_flow[0]:.2e} of its change"
    assert worst_direct[0] < 1e-6, f"{worst_direct[1]}: the outputs at the start point differ by {worst_direct[0]:.2e}"


SINGLE_AXIS = {
    "gear1.model": 0, "motor1.model": 0, "dry_friction": False, "base.fixed": True,
    # the payload's centre of mass on the elevation axis: the elevation axis is at rest at beta = 0
    "body2.d_bd[2]": 0.0, "body2.d_bd[3]": 0.0,
}


def reflected_inertia_and_damping(fmu, values):
    """J = J11 + N^2 J_R1 and c = c_1 + N^2 c_R1 of the azimuth axis at alpha = beta = 0 (docs/physics.md
    section 6; tests/package/analysis/test_frequency_response.py derives them)."""
    v = lambda name: float(values.get(name, fmu.start(name)))
    N = v("gear1.N")
    J11 = (v("body1.I_zz") + v("body1.m") * (v("body1.d_bc[1]") ** 2 + v("body1.d_bc[2]") ** 2)
           + v("body2.I_zz") + v("body2.m") * (v("body2.d_bd[1]") ** 2 + v("body2.d_bd[2]") ** 2)
           + v("rotor2.I_zz") + v("rotor2.m") * (v("rotor2.d_bf[1]") ** 2 + v("rotor2.d_bf[2]") ** 2))
    J = J11 + N ** 2 * (v("rotor1.I_zz") + v("rotor1.m") * (v("rotor1.d_be[1]") ** 2 + v("rotor1.d_be[2]") ** 2))
    c = v("body1.c_visc") + N ** 2 * v("rotor1.c_visc")
    return J, c, N, v("motor1.R"), v("motor1.k_torque"), v("motor1.k_emf")


def test_single_rigid_axis_has_the_textbook_transfer_function(gimbal_fmu):
    """A rigid azimuth gear, a quasi-static motor, a fixed base: from u_R1 to alpha_dot
        G(s) = (N k_t / R) / (J s + c + N^2 k_t k_e / R),
    a pole at -(c + N^2 k_t k_e / R) / J, and the current i = (u - k_e N alpha_dot) / R read off C and D.
    The products of inertia of the elevation side couple the two axes (J13 != 0); they are set to 0 here
    so that the azimuth is exactly first order (the sine-dwell test keeps them: they act at second order)."""
    values = dict(SINGLE_AXIS)
    for body in ("body2", "rotor2"):
        for product in ("I_xy", "I_xz", "I_yz"):
            values[f"{body}.{product}"] = 0.0
    model = linearization.linearize(values)
    J, c, N, R, kt, ke = reflected_inertia_and_damping(gimbal_fmu, values)
    assert "alpha_m" not in model.states and "i_R1" not in model.states
    pole = -(c + N ** 2 * kt * ke / R) / J
    poles = model.poles()
    assert np.min(np.abs(poles - pole)) < 1e-7 * abs(pole)
    for f in (0.01, 0.3, 1.0, 10.0, 100.0, 1000.0):
        s = 2j * math.pi * f
        textbook = (N * kt / R) / (J * s + c + N ** 2 * kt * ke / R)
        G = model.frequency_response([f], "u_R1", "alpha_dot")[0]
        assert abs(G - textbook) < 1e-7 * abs(textbook), f
    i, u, rate = model.outputs.index("i_R1"), model.inputs.index("u_R1"), model.states.index("alpha_dot")
    assert model.D[i, u] == pytest.approx(1 / R, rel=1e-9)
    assert model.C[i, rate] == pytest.approx(-ke * N / R, rel=1e-9)
    assert model.C[model.outputs.index("alpha_m_dot"), rate] == pytest.approx(N, rel=1e-12)
    # a voltage beyond the clamp does not reach the motor
    U_L = float(gimbal_fmu.start("motor1.U_L"))
    for voltage, side in ((1.5 * U_L, 1), (U_L, 1), (-U_L, -1)):
        clamped = linearization.linearize({**values, "u_R1": voltage})
        assert np.all(clamped.B[:, u] == 0.0) and np.all(clamped.D[:, u] == 0.0), voltage
        assert clamped.modes["motor1.voltage_clamped"] == side and clamped.modes["motor2.voltage_clamped"] == 0
    # (the current limit raised: 0.999 U_L / R would be beyond the default i_L, where D is 0 for that reason)
    just_inside = linearization.linearize({**values, "u_R1": 0.999 * U_L, "motor1.i_L": 10 * U_L / R})
    assert just_inside.modes["motor1.voltage_clamped"] == 0 and just_inside.modes["motor1.limited"] == 0
    assert just_inside.D[i, u] == pytest.approx(1 / R, rel=1e-9)


def test_python_control_state_space_and_files(tmp_path):
    import control

    model = linearization.linearize(SINGLE_AXIS)
    sys = model.to_statespace(inputs=["u_R1", "base.gamma_dot"], outputs=["alpha_dot", "los.omega[3]"])
    assert isinstance(sys, control.StateSpace)
    assert sys.input_labels == ["u_R1", "base_gamma_dot"] and sys.output_labels == ["alpha_dot", "los_omega[3]"]
    assert sys.state_labels == model.states
    G = model.frequency_response([2.0], "u_R1", "alpha_dot")[0]
    assert complex(sys(2j * math.pi * 2.0)[0, 0]) == pytest.approx(G, rel=1e-12)
    saved = model.save(tmp_path / "m.npz")
    again = linearization.LinearModel.load(saved)
    for name in "ABCD":
        assert np.array_equal(getattr(again, name), getattr(model, name))
    assert again.states == model.states and again.modes == model.modes and again.point == pytest.approx(model.point)
    from scipy.io import loadmat

    mat = loadmat(model.save(tmp_path / "m.mat"))
    assert np.array_equal(mat["A"], model.A) and np.array_equal(mat["D"], model.D)
    # names are MATLAB cell arrays of strings
    assert [str(np.ravel(cell)[0]) for cell in np.ravel(mat["states"])] == model.states
    with pytest.raises(SceneError, match="write .npz or .mat"):
        model.save(tmp_path / "m.txt")


@pytest.mark.parametrize("values, message", [
    ({"no.such": 1.0}, "'no.such' is not a variable"),
    ({"motor1.R": -1.0}, "motor1.R"),
    ({"alpha": math.nan}, "not finite"),
    ({"gear1.model": 1.5}, "'gear1.model' is an Integer: 1.5 is not a whole number"),
    ({"energy.kinetic": 1.0}, "energy.kinetic is a computed output"),
])
def test_bad_points_are_refused_with_the_culprit_named(values, message):
    with pytest.raises(SceneError, match=message):
        linearization.linearize(values)


def test_a_running_instance_is_linearized_where_it_is_and_left_undisturbed(gimbal_fmu):
    """linearize_instance at t = 20 ms of a run: the matrices and modes of the same point set up directly,
    and the run goes on exactly as without the call (the next step's outputs bit for bit, against a replay
    from an FMU state taken at the same point)."""
    fmu = gimbal_fmu
    outputs = [name for name in linearization.linearize({}).outputs]
    slave = fmu.instantiate("linearization")
    try:
        values = {"u_R1": 2.0, "u_R2": -1.0, "base.fixed": True}
        start(fmu, slave, values)
        for k in range(20):
            slave.doStep(k * 1e-3, 1e-3)
        point = slave.getFMUstate()
        here = dict(zip(["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot",
                         "i_R1", "i_R2", "theta_b1", "theta_b2"],
                        fmu.get_values(slave, ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot",
                                               "beta_dot", "beta_m_dot", "i_R1", "i_R2", "theta_b1", "theta_b2"])))
        model = linearization.linearize_instance(fmu, slave)
        assert model.time == pytest.approx(0.02, abs=1e-15)
        with pytest.raises(SceneError, match="not an input"):
            linearization.linearize_instance(fmu, slave, {"motor1.R": 3.0})
        slave.doStep(0.02, 1e-3)
        after_linearizing = fmu.get_values(slave, outputs)
        slave.setFMUstate(point)
        slave.doStep(0.02, 1e-3)
        assert fmu.get_values(slave, outputs) == after_linearizing
        slave.freeFMUstate(point)
    finally:
        slave.freeInstance()
    direct = linearization.linearize({**values, **here})
    assert direct.modes == model.modes and direct.states == model.states
    for name in "ABCD":
        expected, got = getattr(direct, name), getattr(model, name)
        assert np.allclose(got, expected, rtol=1e-7, atol=1e-9 * np.max(np.abs(expected))), name


def test_the_linear_model_struct_is_built_from_the_library_and_checked_against_its_size(probe_lib_path):
    """The binding asks the library for GimbalLinearModel's dimensions and size; a library whose struct
    does not match what the fields make is refused by name, not read at the wrong offsets."""
    import ctypes

    from gimbal2axis.analysis import linearization
    from gimbal2axis.errors import SceneError

    library = ctypes.CDLL(str(probe_lib_path))
    struct_type, dimensions = linearization._linear_model_struct(library)
    assert dimensions == (14, 17, 17)  # 12 states and the two current amplifiers' integrators

    class OtherVersion:
        """The real library, except that it reports one state more."""
        def __init__(self, real):
            self.gimbal_probe_linear_model_layout = self
            self._real = real.gimbal_probe_linear_model_layout

        def __call__(self, states, inputs, outputs, size):
            self._real(states, inputs, outputs, size)
            ctypes.cast(states, ctypes.POINTER(ctypes.c_int))[0] += 1

    with pytest.raises(SceneError, match="GimbalLinearModel has .* bytes"):
        linearization._linear_model_struct(OtherVersion(library))
