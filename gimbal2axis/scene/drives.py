"""What each motor's command is in a scene: a voltage, or a current to the FMU's servo amplifier.

`motor<j>.drive` (the FMU's DriveMode, docs/physics.md section 4.6) decides it per motor:

  voltage (0, the default)  the controller's output is the armature voltage u_R<j> [V], clamped to
                            +-motor<j>.U_L; the record's columns u_R<j> (applied over the step),
                            u_R<j>_cmd (the controller's output, clamped), u_R<j>_asked (before the clamp)
  current (1)               the controller's output is the current command i_R<j>_cmd [A] to the
                            amplifier, clamped to +-motor<j>.i_L as the FMU clamps it; the columns
                            i_R<j>_cmd (applied: the FMU's input), i_R<j>_ctrl (the controller's
                            output, clamped), i_R<j>_asked (before the clamp). The armature voltage
                            is then the FMU's output amplifier<j>.u.

The loops do not care which: they write the first two inputs and clamp to the limit. Everything that
reads the record asks here which columns an axis has (command_columns), so that a column's unit is
always what its name says.
"""
from __future__ import annotations

from typing import NamedTuple

from ..errors import SceneError
from .parameters import parameter_value

VOLTAGE, CURRENT = 0, 1


class Drive(NamedTuple):
    motor: int          # 1 azimuth, 2 elevation
    kind: str           # "voltage" or "current"
    input_name: str     # the FMU input the command goes to
    limit: float        # the clamp of the controller's output: motor<j>.U_L [V] or motor<j>.i_L [A]
    limit_name: str
    unit: str           # "V" or "A"
    applied: str        # the record's column of the command applied over [t_k, t_k+1]
    commanded: str      # ... of the controller's output at t_k, clamped
    asked: str          # ... of the controller's output at t_k, before the clamp

    @property
    def amplifier_outputs(self) -> tuple[str, str]:
        """The FMU's outputs of this motor's servo amplifier (current drive): its output voltage and integrator."""
        return f"amplifier{self.motor}.u", f"amplifier{self.motor}.x_I"

    @property
    def voltage_column(self) -> str:
        """The record's column of the armature voltage the motor gets."""
        return self.applied if self.kind == "voltage" else f"amplifier{self.motor}.u"


def _drive(motor: int, kind: str, limit: float) -> Drive:
    if kind == "voltage":
        return Drive(motor, kind, f"u_R{motor}", limit, f"motor{motor}.U_L", "V", f"u_R{motor}",
                     f"u_R{motor}_cmd", f"u_R{motor}_asked")
    return Drive(motor, kind, f"i_R{motor}_cmd", limit, f"motor{motor}.i_L", "A", f"i_R{motor}_cmd",
                 f"i_R{motor}_ctrl", f"i_R{motor}_asked")


def scene_drives(scene, fmu) -> tuple[Drive, Drive]:
    """Each motor's drive in `scene` run on `fmu`, with its limit (the scene's value, else the FMU's start)."""
    drives = []
    for motor in (1, 2):
        value = parameter_value(scene, fmu, f"motor{motor}.drive")
        current = value is not None and int(value) == CURRENT
        if current and not fmu.has(f"i_R{motor}_cmd"):
            raise SceneError(f"{scene.name}: motor{motor}.drive = current, but {fmu.path} has no input i_R{motor}_cmd")
        kind = "current" if current else "voltage"
        limit_name = f"motor{motor}.i_L" if current else f"motor{motor}.U_L"
        drives.append(_drive(motor, kind, float(parameter_value(scene, fmu, limit_name))))
    return tuple(drives)


def command_columns(signals, motor: int) -> Drive:
    """The drive of `motor` as a record (a signals dict, a table's column names) shows it: current
    where it has the column i_R<j>_cmd or i_R<j>_ctrl (a plot's record keeps only the first), else
    voltage. The limit is not known from the record (nan)."""
    current = f"i_R{motor}_cmd" in signals or f"i_R{motor}_ctrl" in signals
    return _drive(motor, "current" if current else "voltage", float("nan"))


def command_signals(drives, applied, commanded, asked) -> dict:
    """The record's command columns of both motors, each named by its drive: `applied`, `commanded`,
    `asked` are (rows, 2) arrays (applied over the step; the controller's output clamped; before the clamp)."""
    signals = {}
    for axis, drive in enumerate(drives):
        signals[drive.applied] = applied[:, axis]
        signals[drive.commanded] = commanded[:, axis]
        signals[drive.asked] = asked[:, axis]
    return signals


def other_drive_columns(drive: Drive) -> dict:
    """{column: what to name instead} of the record's command columns a motor of the other drive would
    have: what a [plot] of this scene cannot draw."""
    other = _drive(drive.motor, "current" if drive.kind == "voltage" else "voltage", float("nan"))
    own = {"applied": drive.applied, "commanded": drive.commanded, "asked": drive.asked}
    columns = {getattr(other, role): name for role, name in own.items()}
    return {column: name for column, name in columns.items() if column not in own.values()}
