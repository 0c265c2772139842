"""Writes the FMU's reference results (FMI-LS-REF, the layered standard for related files, version
1.0.0-alpha.1) into fmu_src/reference_results/, which the build packs into the FMU as
extra/org.fmi-standard.fmi-ls-ref/: short experiments run by fmpy on the built FMU, each an SSP
parameter set (.ssv: the start values and structural switches), its stimuli (-in.csv, one row per
communication point; absent when the inputs stay at their start values) and its reference outputs
(-ref.csv), described by experiments.xml and listed with their roles and SHA-256 checksums in
fmi-ls-manifest.xml. An importer replays an experiment and compares its outputs with the reference
within the stated tolerance; tests/fmu/test_reference_results.py does so with fmpy.

Run it again after a change that is meant to change results (from the repository's root, after the
build):   .venv/bin/python scripts/reference_results.py [--fmu build/Gimbal2Axis.fmu]
"""
from __future__ import annotations

import argparse
import hashlib
import math
import pathlib
import shutil
import tempfile
from xml.sax.saxutils import quoteattr

import numpy as np
from fmpy import simulate_fmu
from fmpy.util import write_csv

REPOSITORY = pathlib.Path(__file__).resolve().parents[1]
DESTINATION = REPOSITORY / "fmu_src" / "reference_results"
LS_VERSION = "1.0.0-alpha.1"
# An importer passes when every reference signal is within ABSOLUTE + RELATIVE * |reference| (SI units).
ABSOLUTE_TOLERANCE, RELATIVE_TOLERANCE = 1e-6, 1e-6
BASE_INPUTS = [f"base.{a}{d}" for a in ("delta", "psi", "gamma") for d in ("", "_dot", "_ddot")] + \
    [f"base.{v}[{i}]" for v in ("v_a", "a_a") for i in (1, 2, 3)]
OUTPUTS = ["alpha", "beta", "alpha_dot", "beta_dot", "alpha_m", "beta_m", "i_R1", "i_R2", "theta_b1", "theta_b2",
           "los.omega[1]", "los.omega[2]", "los.omega[3]"]


def _free_swing(times):
    return None


def _voltage_steps(times):
    """Motor 1 to +6 V at 0.1 s, motor 2 to -4 V at 0.3 s (held over each step); the still carrier's
    inputs given as 0."""
    return {"u_R1": np.where(times >= 0.1 - 1e-12, 6.0, 0.0), "u_R2": np.where(times >= 0.3 - 1e-12, -4.0, 0.0),
            **{name: np.zeros_like(times) for name in BASE_INPUTS}}


def _rolling_carrier(times):
    """The carrier rolls 5 deg at 0.25 Hz and pitches 2 deg at 0.4 Hz, with exact rates and accelerations;
    every other input given as 0."""
    signals = {name: np.zeros_like(times) for name in BASE_INPUTS}
    for name, amplitude_deg, frequency in (("gamma", 5.0, 0.25), ("delta", 2.0, 0.4)):
        amplitude, w = math.radians(amplitude_deg), 2.0 * math.pi * frequency
        signals[f"base.{name}"] = amplitude * np.sin(w * times)
        signals[f"base.{name}_dot"] = amplitude * w * np.cos(w * times)
        signals[f"base.{name}_ddot"] = -amplitude * w * w * np.sin(w * times)
    signals["u_R1"], signals["u_R2"] = np.full_like(times, 1.5), np.zeros_like(times)
    return signals


# name: (description, stop time, communication step, start values, stimuli)
EXPERIMENTS = {
    "free_swing": ("fixed carrier, motors at 0 V, the payload released at beta = 0.5 rad: gravity, friction and "
                   "the gears' backlash", 1.0, 1e-3, {"base.fixed": True, "beta": 0.5}, _free_swing),
    "voltage_steps": ("fixed carrier, voltage steps on both motors: current limiter, backlash impacts, "
                      "stick-slip", 0.6, 1e-3, {"base.fixed": True}, _voltage_steps),
    "rolling_carrier": ("carrier rolling and pitching, motor 1 at 1.5 V: the moving-base terms", 1.0, 2e-3,
                        {}, _rolling_carrier),
}


def _ssv(name: str, start_values: dict) -> str:
    rows = []
    for variable, value in start_values.items():
        if isinstance(value, bool):
            element = f'<ssv:Boolean value="{str(value).lower()}"/>'
        else:
            element = f'<ssv:Real value="{value!r}"/>'
        rows.append(f'    <ssv:Parameter name={quoteattr(variable)}>{element}</ssv:Parameter>')
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
            f'version="1.0" name={quoteattr(name)}>\n  <ssv:Parameters>\n' + "\n".join(rows) +
            '\n  </ssv:Parameters>\n</ssv:ParameterSet>\n')


def _run(fmu: pathlib.Path, stop_time: float, step: float, start_values: dict, stimuli: dict | None):
    times = np.round(np.arange(0.0, stop_time + step / 2, step), 12)
    signals = None if stimuli is None else stimuli(times)
    inputs = None
    if signals:
        inputs = np.zeros(len(times), dtype=[("time", np.float64)] + [(n, np.float64) for n in signals])
        inputs["time"] = times
        for n, values in signals.items():
            inputs[n] = values
    result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=stop_time, output_interval=step,
                          start_values=dict(start_values), input=inputs, output=OUTPUTS)
    return inputs, result


def _documentation() -> str:
    lines = ["Reference results of Gimbal2Axis (FMI-LS-REF " + LS_VERSION + "), in extra/org.fmi-standard.fmi-ls-ref/.",
             "",
             "experiments.xml lists the experiments; each gives its parameter set (.ssv: start values and",
             "structural switches, set before initialization), its stimuli (-in.csv: the inputs at every",
             "communication point, held over the step that starts there; without it the inputs stay at their",
             "start values) and its reference outputs (-ref.csv). Run each in Co-Simulation from 0 s with the",
             "experiment's step as communication step and compare every reference column:",
             f"    |output - reference| <= {ABSOLUTE_TOLERANCE:g} + {RELATIVE_TOLERANCE:g} * |reference|   (SI units)",
             "fmpy on the platform that made them reproduces them to the last bit; the tolerance leaves room",
             "for another importer's or platform's rounding (a different clock, another libm).",
             ""]
    for name, (description, stop_time, step, _, _) in EXPERIMENTS.items():
        lines.append(f"{name}: {description}; {stop_time:g} s, step {step:g} s.")
    lines += ["", "Made by scripts/reference_results.py of the Gimbal2Axis repository from the FMU itself."]
    return "\n".join(lines) + "\n"


def _checksum(path: pathlib.Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def write_references(fmu: pathlib.Path, destination: pathlib.Path) -> list[str]:
    with tempfile.TemporaryDirectory() as scratch:
        staging = pathlib.Path(scratch)
        experiments, related = [], []
        for name, (description, stop_time, step, start_values, stimuli) in EXPERIMENTS.items():
            inputs, result = _run(fmu, stop_time, step, start_values, stimuli)
            (staging / f"{name}.ssv").write_text(_ssv(name, start_values))
            write_csv(str(staging / f"{name}-ref.csv"), result)
            parts = [f'    <Parameters source="{name}.ssv"/>']
            related.append((f"{name}.ssv", "parameter", "application/x-ssp-parameter-set",
                            f"{name}: start values and structural switches"))
            if inputs is not None:
                write_csv(str(staging / f"{name}-in.csv"), inputs)
                parts.append(f'    <Stimuli source="{name}-in.csv"/>')
                related.append((f"{name}-in.csv", "testcase", "text/csv",
                                f"{name}: the inputs at every communication point (held over the step)"))
            parts.append(f'    <References source="{name}-ref.csv"/>')
            related.append((f"{name}-ref.csv", "result", "text/csv",
                            f"{name}: the outputs at every communication point; an importer matches within "
                            f"{ABSOLUTE_TOLERANCE:g} + {RELATIVE_TOLERANCE:g} |reference| (SI units)"))
            experiments.append(f'  <Experiment name="{name}" description={quoteattr(description)} startTime="0.0" '
                               f'stopTime="{stop_time!r}" stepSize="{step!r}">\n' + "\n".join(parts) +
                               "\n  </Experiment>")
        (staging / "experiments.xml").write_text(
            '<?xml version="1.0" encoding="UTF-8"?>\n<Experiments name="Gimbal2Axis smoke tests">\n' +
            "\n".join(experiments) + "\n</Experiments>\n")
        related.insert(0, ("experiments.xml", "experiment/smoke-test", "application/xml",
                           "short Co-Simulation experiments with reference results, for an importer to check itself"))
        rows = [f'  <Related type="{kind}" source="{source}" role="{role}" description={quoteattr(text)} '
                f'checksum="{_checksum(staging / source)}" checksumType="SHA-256"/>'
                for source, role, kind, text in related]
        (staging / "fmi-ls-manifest.xml").write_text(
            '<?xml version="1.0" encoding="UTF-8"?>\n<fmiReferences xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"'
            f'\n    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref" fmi-ls:fmi-ls-version="{LS_VERSION}"'
            '\n    fmi-ls:fmi-ls-description="Layered Standard providing information on related files included in an FMU.">\n'
            + "\n".join(rows) + "\n</fmiReferences>\n")
        (staging / "fmi-ls-ref.txt").write_text(_documentation())
        if destination.exists():
            shutil.rmtree(destination)
        shutil.copytree(staging, destination)
    return sorted(p.name for p in destination.iterdir())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmu", default=str(REPOSITORY / "build" / "Gimbal2Axis.fmu"))
    parser.add_argument("--out", default=str(DESTINATION))
    args = parser.parse_args()
    written = write_references(pathlib.Path(args.fmu), pathlib.Path(args.out))
    print(f"wrote {len(written)} files into {args.out}: {', '.join(written)}")


if __name__ == "__main__":
    main()
