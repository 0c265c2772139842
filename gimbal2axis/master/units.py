"""The unit of every signal a run records, and how the result files carry it: the CSV's header
names each column `name [unit]` (`time [s]`, `alpha [rad]`, `los_error [rad]`), the Parquet file's
schema gives each field the metadata `unit`. The numbers are SI as the FMU computes them (rad, not
the mrad of the summary line, which writes its unit beside each number).

One table for both kinds of signal:
- the FMU's variables (outputs, and the inputs a run records): their units in the model description,
  which model_core/include/gimbal/*_variables.def generates; tests/package/master/test_result_units.py holds the
  table to the built FMU's modelDescription.xml, variable by variable;
- the signals the runner adds (scene/scene.py DERIVED_SIGNALS and the master's records: commands,
  set points, line-of-sight angles and errors, heave, the carrier's rate in the payload frame).

"1" is a dimensionless number (the FMI's name for it): the Integer mode flags and event counts.
A name missing from the table is written without a unit rather than refusing the run; the test
that runs the scenes finds it.
"""
from __future__ import annotations

# The FMU's variables: modelDescription.xml's unit of each (checked against the FMU by the tests).
_FMU_UNITS = {
    **{name: "rad" for name in ("alpha", "alpha_m", "beta", "beta_m", "theta_b1", "theta_b2",
                                "base.delta", "base.psi", "base.gamma")},
    **{name: "rad/s" for name in ("alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot", "los.omega[1]",
                                  "los.omega[2]", "los.omega[3]", "base.delta_dot", "base.psi_dot",
                                  "base.gamma_dot")},
    **{name: "rad/s2" for name in ("base.delta_ddot", "base.psi_ddot", "base.gamma_ddot")},
    **{f"base.v_a[{i}]": "m/s" for i in (1, 2, 3)},
    **{f"base.a_a[{i}]": "m/s2" for i in (1, 2, 3)},
    "u_R1": "V", "u_R2": "V", "i_R1": "A", "i_R2": "A", "T_E1": "N.m", "T_E2": "N.m",
    "i_R1_cmd": "A", "i_R2_cmd": "A", "amplifier1.u": "V", "amplifier2.u": "V", "amplifier1.x_I": "V",
    "amplifier2.x_I": "V",
    **{f"energy.{kind}": "J" for kind in ("kinetic", "potential", "spring", "magnetic", "electrical_in",
                                          "resistive", "viscous", "shaft_damping", "dry_friction", "cable",
                                          "cogging")},
    "events.last_time": "s",
    **{name: "1" for name in ("gear1.contact", "gear2.contact", "motor1.limited", "motor2.limited",
                              "body1.stick_slip", "rotor1.stick_slip", "body2.stick_slip", "rotor2.stick_slip",
                              "elevation_stop.contact", "motor1.amplifier_saturated", "motor2.amplifier_saturated",
                              "events.total", "events.backlash1", "events.backlash2", "events.current_limit1",
                              "events.current_limit2", "events.stick_slip", "events.zeno_guard", "solver.states",
                              "solver.steps", "solver.rhs_evaluations", "solver.jacobian_evaluations",
                              "solver.method_switches")},
}

# What the runner computes: the controller's commands (before the delay; before the clamp), the set
# points, the line-of-sight geometry (docs/jitter.md), the base's heave and its rate in frame 2.
_RUNNER_UNITS = {
    "time": "s",
    "u_R1_cmd": "V", "u_R2_cmd": "V", "u_R1_asked": "V", "u_R2_asked": "V",
    # a motor in current drive (scene/drives.py): the controller's current commands
    "i_R1_ctrl": "A", "i_R2_ctrl": "A", "i_R1_asked": "A", "i_R2_asked": "A",
    **{name: "rad" for name in ("alpha_ref", "beta_ref", "alpha_error", "beta_error", "los_azimuth",
                                "los_elevation", "los_error", "los_error_xel", "los_error_el")},
    "heave": "m",
    # a moving target (results.tracking_signals)
    **{name: "rad" for name in ("target_azimuth", "target_elevation", "alpha_cmd", "beta_cmd")},
    "target_range": "m",
    **{name: "rad/s" for name in ("alpha_cmd_dot", "beta_cmd_dot")},
    **{name: "rad/s2" for name in ("alpha_cmd_ddot", "beta_cmd_ddot")},
    **{f"base.omega2[{i}]": "rad/s" for i in (1, 2, 3)},
}

UNITS = {**_FMU_UNITS, **_RUNNER_UNITS}


def unit_of(name: str) -> str | None:
    """The signal's unit ("1": dimensionless), None when the table does not know it."""
    return UNITS.get(name)


def column_label(name: str) -> str:
    """The CSV header's field of a signal: `alpha [rad]`; the bare name when its unit is unknown."""
    unit = UNITS.get(name)
    return name if unit is None else f"{name} [{unit}]"


def csv_header(names) -> str:
    """The CSV's header line (without its newline): the labels of `names`, comma-separated."""
    return ",".join(column_label(name) for name in names)


def split_label(label: str) -> tuple[str, str | None]:
    """('alpha', 'rad') from a header field 'alpha [rad]'; (label, None) when it has no unit. For
    readers of the CSV that want the plain names (the names themselves hold no ' [')."""
    name, bracket, unit = label.partition(" [")
    if not bracket or not unit.endswith("]"):
        return label, None
    return name, unit[:-1]


def with_units(schema):
    """A pyarrow schema whose fields carry their unit as metadata b"unit" (where the table knows it):
    what pyarrow.parquet.read_schema(path).field(name).metadata[b"unit"] then reads from the file."""
    import pyarrow as pa

    fields = []
    for field in schema:
        unit = UNITS.get(field.name)
        fields.append(field if unit is None else field.with_metadata({**(field.metadata or {}), b"unit": unit.encode()}))
    return pa.schema(fields, metadata=schema.metadata)
