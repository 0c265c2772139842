"""The gimbal's continuous model linearized at an operating point: A, B, C, D (docs/linearization.md).

    d(dx)/dt = A dx + B du,      dy = C dx + D du

The matrices come from the dynamics core itself, through libgimbal_probe.so (built beside the FMU:
`cmake --build build --target gimbal_probe`; found as gimbal2axis.locations says). A is the Jacobian
the core's implicit integrators use; B, C and D are central differences of the core's right-hand side
and outputs. They hold within the modes in force at the point (gear contact, current limiter, voltage
clamp, friction regime), which the model reports.

The operating point is either
  - a set of values (parameters and fidelity switches, start values of the states, inputs) for a
    fresh instance initialized at t = 0: `linearize({...})`, or
  - the state of a running FMU instance: `linearize_instance(fmu, slave)` serializes its FMU state and
    linearizes there (parameters, state, modes and inputs as the instance holds them).

States are named by the outputs that carry them (alpha, alpha_dot, i_R1, theta_b1, ...; a rigid
gear's rotor and a quasi-static motor's current are not states). Inputs are the FMU's 17 Real inputs,
outputs the 17 Real outputs alpha .. los.omega[3], all in SI units (rad, rad/s, V, A, N.m).
"""
from __future__ import annotations

import ctypes
import dataclasses
import math
import os
import pathlib
import struct

import numpy as np

from ..errors import SceneError
from ..locations import probe_library_path
from .names import did_you_mean

REAL, INTEGER, BOOLEAN = 0, 1, 2
INPUT_CAUSALITY = 1
SERIALIZED_MAGIC = 0x46535441   # the first field of the wrapper's FMU-state header ("FSTA"); then the format version and the size
FRICTION_MODES = ["none", "slipping +", "slipping -", "stuck", "at break-away +", "at break-away -"]


class _Setting(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("vr", ctypes.c_uint), ("value", ctypes.c_double)]


def _linear_model_struct(lib):
    """The ctypes view of GimbalLinearModel, its dimensions asked from the library (not copied here) and
    its size checked against the library's sizeof."""
    lib.gimbal_probe_linear_model_layout.restype = None
    lib.gimbal_probe_linear_model_layout.argtypes = [ctypes.POINTER(ctypes.c_int)] * 3 + [ctypes.POINTER(ctypes.c_size_t)]
    max_states, inputs, outputs, size = ctypes.c_int(), ctypes.c_int(), ctypes.c_int(), ctypes.c_size_t()
    lib.gimbal_probe_linear_model_layout(ctypes.byref(max_states), ctypes.byref(inputs), ctypes.byref(outputs),
                                         ctypes.byref(size))
    n, m, p = max_states.value, inputs.value, outputs.value

    class LinearModelStruct(ctypes.Structure):
        _fields_ = [("state_count", ctypes.c_int),
                    ("state_vr", ctypes.c_uint * n),
                    ("input_vr", ctypes.c_uint * m),
                    ("output_vr", ctypes.c_uint * p),
                    ("A", ctypes.c_double * (n * n)),
                    ("B", ctypes.c_double * (n * m)),
                    ("C", ctypes.c_double * (p * n)),
                    ("D", ctypes.c_double * (p * m)),
                    ("gear_contact", ctypes.c_int * 2),
                    ("motor_limited", ctypes.c_int * 2),
                    ("voltage_clamped", ctypes.c_int * 2),
                    ("friction", ctypes.c_int * 4),
                    ("elevation_stop", ctypes.c_int),
                    ("time", ctypes.c_double),
                    ("amplifier_saturated", ctypes.c_int * 2)]

    if ctypes.sizeof(LinearModelStruct) != size.value:
        raise SceneError(f"the probe library's GimbalLinearModel has {size.value} bytes where its fields as read here "
                         f"make {ctypes.sizeof(LinearModelStruct)}: gimbal2axis and the library come from different versions")
    return LinearModelStruct, (n, m, p)


class Probe:
    """The core's analysis entries (model_core/include/gimbal/probe_api.h) through ctypes."""

    def __init__(self, build_dir: str | os.PathLike | None = None):
        self.path = probe_library_path(build_dir)
        lib = ctypes.CDLL(str(self.path))
        lib.gimbal_probe_variable.restype = ctypes.c_int
        lib.gimbal_probe_variable.argtypes = [ctypes.c_int, ctypes.c_uint, ctypes.POINTER(ctypes.c_char_p),
                                              ctypes.POINTER(ctypes.c_int)]
        lib.gimbal_probe_snapshot_size.restype = ctypes.c_size_t
        self._model_struct, self.dimensions = _linear_model_struct(lib)
        lib.gimbal_probe_linearize.restype = ctypes.c_int
        lib.gimbal_probe_linearize.argtypes = [ctypes.POINTER(_Setting), ctypes.c_size_t, ctypes.c_void_p,
                                               ctypes.c_size_t, ctypes.POINTER(self._model_struct), ctypes.c_char_p,
                                               ctypes.c_size_t]
        self._lib = lib
        self.variables: dict[str, tuple[int, int, int]] = {}   # name -> (type, vr, causality)
        self.real_names: dict[int, str] = {}
        for type_ in (REAL, INTEGER, BOOLEAN):
            vr = 0
            name, causality = ctypes.c_char_p(), ctypes.c_int()
            while lib.gimbal_probe_variable(type_, vr, ctypes.byref(name), ctypes.byref(causality)):
                text = name.value.decode()
                self.variables[text] = (type_, vr, causality.value)
                if type_ == REAL:
                    self.real_names[vr] = text
                vr += 1
        self.snapshot_size = int(lib.gimbal_probe_snapshot_size())

    def linearize(self, values: dict | None = None, snapshot: bytes | None = None) -> "LinearModel":
        values = dict(values or {})
        settings = (_Setting * max(len(values), 1))()
        for k, (name, value) in enumerate(values.items()):
            settings[k] = self._setting(name, value, at_snapshot=snapshot is not None)
        buffer = None
        if snapshot is not None:
            if len(snapshot) != self.snapshot_size:
                raise SceneError(f"linearize: the snapshot has {len(snapshot)} bytes where {self.path} expects "
                                 f"{self.snapshot_size}: the FMU and the probe library come from different builds")
            buffer = ctypes.create_string_buffer(bytes(snapshot), len(snapshot))
        model = self._model_struct()
        message = ctypes.create_string_buffer(1024)
        status = self._lib.gimbal_probe_linearize(settings, len(values), buffer, len(snapshot or b""),
                                                  ctypes.byref(model), message, len(message))
        if status != 0:
            raise SceneError(f"linearize: {message.value.decode(errors='replace')}")
        return self._linear_model(model, values)

    def _setting(self, name: str, value, at_snapshot: bool) -> "_Setting":
        """The probe's setting of variable `name` to `value`, checked."""
        if name not in self.variables:
            raise SceneError(f"linearize: '{name}' is not a variable of the gimbal model"
                             f"{did_you_mean(name, self.variables)}")
        type_, vr, causality = self.variables[name]
        if at_snapshot and causality != INPUT_CAUSALITY:
            raise SceneError(f"linearize: '{name}' is not an input: at a running instance's operating point "
                             f"only inputs can be changed")
        value = float(value)
        if not math.isfinite(value):
            raise SceneError(f"linearize: '{name}' = {value} is not finite")
        if type_ != REAL and not value.is_integer():
            raise SceneError(f"linearize: '{name}' is {'an Integer' if type_ == INTEGER else 'a Boolean'}: "
                             f"{value:g} is not a whole number")
        return _Setting(type_, vr, value)

    def _linear_model(self, model, values: dict) -> "LinearModel":
        """The LinearModel of the probe's result struct, linearized at `values`."""
        n = model.state_count
        max_states, input_count, output_count = self.dimensions
        A = np.ctypeslib.as_array(model.A).reshape(max_states, max_states)[:n, :n].copy()
        B = np.ctypeslib.as_array(model.B).reshape(max_states, input_count)[:n].copy()
        C = np.ctypeslib.as_array(model.C).reshape(output_count, max_states)[:, :n].copy()
        D = np.ctypeslib.as_array(model.D).reshape(output_count, input_count).copy()
        modes = {}
        for axis in (0, 1):
            modes[f"gear{axis + 1}.contact"] = int(model.gear_contact[axis])
            modes[f"motor{axis + 1}.limited"] = int(model.motor_limited[axis])
            modes[f"motor{axis + 1}.voltage_clamped"] = int(model.voltage_clamped[axis])
        for body, name in enumerate(["body1", "rotor1", "body2", "rotor2"]):
            modes[f"{name}.friction"] = FRICTION_MODES[model.friction[body]]
        modes["elevation_stop.contact"] = int(model.elevation_stop)
        return LinearModel(A=A, B=B, C=C, D=D,
                           states=[self.real_names[model.state_vr[k]] for k in range(n)],
                           inputs=[self.real_names[model.input_vr[k]] for k in range(input_count)],
                           outputs=[self.real_names[model.output_vr[k]] for k in range(output_count)],
                           modes=modes, time=float(model.time),
                           point={name: float(value) for name, value in values.items()})


# is_identically_zero: round-off of the core's differences is ~1e-16 of the largest gain; a physical
# path, however weak, is far above 1e-10 of it. Checked from 0.01 Hz to 1 kHz (the Bode plot's default band).
ZERO_GAIN_RATIO = 1e-10
ZERO_CHECK_HZ = np.logspace(-2, 3, 11)


def _axes_of(signal: str) -> set[int]:
    """The gimbal axes (1 azimuth, 2 elevation) a signal belongs to: a motor voltage, a body's angle or
    rate, a current, a backlash position or shaft torque its own axis; the carrier's inputs and the line
    of sight's rates both."""
    if signal.startswith("alpha") or signal in ("u_R1", "i_R1", "theta_b1", "T_E1"):
        return {1}
    if signal.startswith("beta") or signal in ("u_R2", "i_R2", "theta_b2", "T_E2"):
        return {2}
    return {1, 2}


def control_name(name: str) -> str:
    """The FMU's variable name as a python-control signal name ('.' is reserved there)."""
    return name.replace(".", "_")


@dataclasses.dataclass
class LinearModel:
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    modes: dict
    time: float = 0.0
    point: dict = dataclasses.field(default_factory=dict)   # the values it was linearized with

    def select(self, inputs: list[str] | None = None, outputs: list[str] | None = None) -> "LinearModel":
        """The same model with only some inputs and outputs (in the order given)."""
        def index(names, chosen, what):
            if chosen is None:
                return list(range(len(names)))
            missing = [c for c in chosen if c not in names]
            if missing:
                raise SceneError(f"linear model: {missing} are not {what} (it has {names})")
            return [names.index(c) for c in chosen]

        i, o = index(self.inputs, inputs, "inputs"), index(self.outputs, outputs, "outputs")
        return dataclasses.replace(self, B=self.B[:, i], C=self.C[o], D=self.D[np.ix_(o, i)],
                                   inputs=[self.inputs[k] for k in i], outputs=[self.outputs[k] for k in o])

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A)

    def frequency_response(self, frequencies_hz, input: str, output: str) -> np.ndarray:
        """G(j w) = C (j w I - A)^-1 B + D from one input to one output, at each frequency (complex),
        evaluated by python-control."""
        import control

        i, o = self.inputs.index(input), self.outputs.index(output)
        path = control.ss(self.A, self.B[:, [i]], self.C[[o]], self.D[[o]][:, [i]])
        w = 2 * math.pi * np.atleast_1d(np.asarray(frequencies_hz, float))
        return np.asarray(path(1j * w), complex).reshape(-1)

    def held_frequency_response(self, frequencies_hz, input: str, output: str, step: float) -> np.ndarray:
        """What a sine dwell of the sampled plant measures: the input held over steps of `step` s (zero-order
        hold), the output sampled at the step ends, and the input's continuous-time fundamental taken as the
        reference (gimbal2axis.analysis.frequency_response.zoh_fundamental). It differs from
        frequency_response by the aliases of the staircase's harmonics, which matter as f approaches 1 / (2 step)."""
        import control

        i, o = self.inputs.index(input), self.outputs.index(output)
        # Zero-order-hold discretization over one step (python-control's c2d); the output published at
        # t_k holds the input of the step before, so D enters as D / z, not as the sampled system's D.
        held = control.c2d(control.ss(self.A, self.B[:, [i]], self.C[[o]], np.zeros((1, 1))), step, method="zoh")
        out = []
        for f in np.atleast_1d(np.asarray(frequencies_hz, float)):
            z = np.exp(2j * math.pi * f * step)
            samples = complex(np.asarray(held(z)).reshape(-1)[0]) + self.D[o, i] / z
            half = math.pi * f * step
            hold = complex(math.cos(half), -math.sin(half)) * math.sin(half) / half
            out.append(samples / hold)
        return np.array(out)

    def is_identically_zero(self, input: str, output: str) -> bool:
        """Whether G from `input` to `output` is zero at every frequency, to round-off: below ZERO_GAIN_RATIO
        times the largest gain from the same input to any output, at every frequency of ZERO_CHECK_HZ. A
        held mode makes a path exactly 0 in A or B (a stuck body's rows), or leaves round-off (1e-17 through
        the mass matrix's differences for a gear in its gap); a physical path, however weak (the azimuth
        moving the elevation through the payload's products of inertia), is many decades above that."""
        i, o = self.inputs.index(input), self.outputs.index(output)
        n = len(self.states)
        largest = np.abs(self.D[:, i])   # over the frequencies, per output
        for f in ZERO_CHECK_HZ:
            x = np.linalg.solve(2j * math.pi * f * np.eye(n) - self.A, self.B[:, i]) if n else np.zeros(0)
            largest = np.maximum(largest, np.abs(self.C @ x + self.D[:, i]))
        return bool(largest[o] <= ZERO_GAIN_RATIO * largest.max())

    def held_modes_on(self, input: str, output: str) -> list[tuple[str, object, str]]:
        """(mode, its value, the setting that frees it) for each mode in force at this point that holds a
        link between `input` and `output`: on the axis (motor, rotor, gear, load) of the input and of the
        output (both axes for the carrier's inputs and the line-of-sight rates)."""
        held = []
        for axis in sorted(_axes_of(input) | _axes_of(output)):
            load_rate, rotor_rate = ("alpha_dot", "alpha_m_dot") if axis == 1 else ("beta_dot", "beta_m_dot")
            if self.modes.get(f"motor{axis}.voltage_clamped", 0) != 0:
                held.append((f"motor{axis}.voltage_clamped", self.modes[f"motor{axis}.voltage_clamped"],
                             f"a voltage inside the clamp, --set u_R{axis}=V with |V| < motor{axis}.U_L"))
            if self.modes.get(f"motor{axis}.limited", 0) != 0:
                held.append((f"motor{axis}.limited", self.modes[f"motor{axis}.limited"],
                             f"a current below the limit, a smaller --set u_R{axis}=V or a larger --set motor{axis}.i_L=A"))
            for body, rate in ((f"rotor{axis}", rotor_rate), (f"body{axis}", load_rate)):
                if self.modes.get(f"{body}.friction") == "stuck":
                    how = (f"--set dry_friction=false, or a start rate that makes it slip, e.g. --set {rate}=0.1"
                           if rate in self.states else "--set dry_friction=false")
                    held.append((f"{body}.friction", "stuck", how))
            if axis == 2 and self.modes.get("elevation_stop.contact", 0) != 0:
                held.append(("elevation_stop.contact", self.modes["elevation_stop.contact"],
                             "a start inside the elevation stops, e.g. --set beta=0, or --set elevation_stop=false"))
            # contact 0 means "in the gap" only where there is a gap: the backlash position is then a state
            if self.modes.get(f"gear{axis}.contact", 0) == 0 and f"theta_b{axis}" in self.states:
                held.append((f"gear{axis}.contact", 0, f"a gear without backlash, --set gear{axis}.model=1 "
                                                       f"(compliant) or gear{axis}.model=0 (rigid)"))
        return held

    def zero_path_warning(self, input: str, output: str) -> str | None:
        """One line saying that G from `input` to `output` is identically zero and which held modes (with
        the settings that free them) make it so; None where it is not zero."""
        if not self.is_identically_zero(input, output):
            return None
        i = self.inputs.index(input)
        if input.startswith("base.") and not (self.B[:, i].any() or self.D[:, i].any()):
            why = ("base.fixed = true: the carrier's inputs are not used" if self.point.get("base.fixed")
                   else "a uniform translation of the carrier does not act on the gimbal" if input.startswith("base.v_a")
                   else "this carrier input acts on nothing at this operating point")
            return f"{input} -> {output} is identically zero in this linear model: {why}"
        held = self.held_modes_on(input, output)
        if not held:
            return (f"{input} -> {output} is identically zero in this linear model, and no held mode explains "
                    f"it: the input does not act on that output at this operating point")
        reasons = "; ".join(f"{mode} = {value} (freed by {how})" for mode, value, how in held)
        return f"{input} -> {output} is identically zero in this linear model: held by {reasons}"

    def to_statespace(self, inputs: list[str] | None = None, outputs: list[str] | None = None):
        """A python-control StateSpace (package `control`), with the states, inputs and outputs named as the
        FMU names them but with '.' written '_' (python-control reserves '.' for subsystems):
        base.gamma_dot -> base_gamma_dot, los.omega[3] -> los_omega[3]."""
        import control

        model = self.select(inputs, outputs)
        return control.ss(model.A, model.B, model.C, model.D, states=[control_name(n) for n in model.states],
                          inputs=[control_name(n) for n in model.inputs],
                          outputs=[control_name(n) for n in model.outputs], name="gimbal_linear")

    def save(self, path: str | os.PathLike) -> pathlib.Path:
        """Writes .npz (numpy) or .mat (MATLAB, scipy.io) with A, B, C, D, the names, the modes and the point."""
        path = pathlib.Path(path)
        data = dict(A=self.A, B=self.B, C=self.C, D=self.D, states=np.array(self.states), inputs=np.array(self.inputs),
                    outputs=np.array(self.outputs), time=np.array(self.time),
                    mode_names=np.array(list(self.modes)), mode_values=np.array([str(v) for v in self.modes.values()]),
                    point_names=np.array(list(self.point), dtype=str),
                    point_values=np.array([float(v) for v in self.point.values()], float))
        if path.suffix == ".npz":
            np.savez(path, **data)
        elif path.suffix == ".mat":
            from scipy.io import savemat

            savemat(path, {k: (v.astype(object) if v.dtype.kind == "U" else v) for k, v in data.items()})
        else:
            raise SceneError(f"{path}: write .npz or .mat")
        return path

    @classmethod
    def load(cls, path: str | os.PathLike) -> "LinearModel":
        """Reads what save() wrote as .npz."""
        with np.load(path) as data:
            modes = dict(zip(data["mode_names"].tolist(), data["mode_values"].tolist()))
            modes = {k: (int(v) if v.lstrip("-").isdigit() else v) for k, v in modes.items()}
            return cls(A=data["A"], B=data["B"], C=data["C"], D=data["D"], states=data["states"].tolist(),
                       inputs=data["inputs"].tolist(), outputs=data["outputs"].tolist(), modes=modes,
                       time=float(data["time"]),
                       point=dict(zip(data["point_names"].tolist(), data["point_values"].tolist())))

    def summary(self) -> str:
        poles = self.poles()
        # eigenvalues at round-off level of the largest are zeros (free angles: integrators)
        floor = 1e-9 * max(float(np.max(np.abs(poles))), 1.0) if len(poles) else 0.0
        poles = sorted((0j if abs(p) < floor else p for p in poles), key=lambda p: (abs(p), p.imag))
        lines = [f"linear model at t = {self.time:g} s: {len(self.states)} states, {len(self.inputs)} inputs, "
                 f"{len(self.outputs)} outputs",
                 "states: " + ", ".join(self.states),
                 "modes: " + ", ".join(f"{k} = {v}" for k, v in self.modes.items()),
                 "poles [1/s] (natural frequency [Hz], damping):"]
        for p in poles:
            wn = abs(p)
            zeta = -p.real / wn if wn > 0 else math.nan
            lines.append(f"  {p.real:14.6g} {p.imag:+14.6g}j   ({wn / (2 * math.pi):10.4g} Hz, {zeta:7.4g})")
        return "\n".join(lines)


_PROBES: dict = {}


def _probe(build_dir=None) -> Probe:
    key = str(probe_library_path(build_dir))
    if key not in _PROBES:
        _PROBES[key] = Probe(build_dir)
    return _PROBES[key]


def variable_names(build_dir: str | os.PathLike | None = None) -> list[str]:
    """The names of the gimbal model's variables that linearize() takes (the probe library's, the FMU's)."""
    return list(_probe(build_dir).variables)


def linearize(values: dict | None = None, build_dir: str | os.PathLike | None = None) -> LinearModel:
    """Linearizes a fresh instance given `values` (parameters, fidelity switches, start values of the
    states such as alpha or beta_dot, inputs such as u_R1 or base.gamma), initialized at t = 0."""
    return _probe(build_dir).linearize(values)


def linearize_instance(fmu, slave, inputs: dict | None = None, build_dir: str | os.PathLike | None = None) -> LinearModel:
    """Linearizes where a running FMU instance is (fmpy FMU2Slave `slave` of the gimbal2axis FMU `fmu`),
    optionally with some of its inputs changed. The instance is not disturbed."""
    probe = _probe(build_dir)
    state = slave.getFMUstate()
    try:
        serialized = bytes(slave.serializeFMUstate(state))
    finally:
        slave.freeFMUstate(state)
    magic, _version, recorded_size = struct.unpack_from("<IIQ", serialized)
    if magic != SERIALIZED_MAGIC or recorded_size != len(serialized):
        raise SceneError(f"linearize: {fmu.path} handed out an FMU state that does not start like one of this "
                         f"project's FMUs (magic {magic:#x}, recorded size {recorded_size})")
    # The core's snapshot is the tail of the record; the wrapper's header before it is whatever the rest is
    # (its size is the wrapper's, not copied here). The core checks the snapshot's own format and size.
    header_bytes = len(serialized) - probe.snapshot_size
    if header_bytes < struct.calcsize("<IIQ"):
        raise SceneError(f"linearize: {fmu.path} serializes {len(serialized)} bytes, too few for the "
                         f"{probe.snapshot_size}-byte model state {probe.path} expects: they come from different builds")
    model = probe.linearize(inputs, snapshot=serialized[header_bytes:])
    return model
