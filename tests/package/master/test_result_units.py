"""Units in the result files: the CSV's header names every column `name [unit]`, the Parquet schema
gives every field its unit as metadata, both from gimbal2axis/master/units.py, whose FMU entries are
the model description's."""
import csv
import pathlib

import pyarrow.parquet as pq
import pytest

from gimbal2axis import FMU, load_scene
from gimbal2axis.master import run
from gimbal2axis.master.scene_files import run_scene_file
from gimbal2axis.master.units import UNITS, column_label, csv_header, split_label, unit_of

ROOT = pathlib.Path(__file__).resolve().parents[3]


def model_description_unit(variable) -> str:
    """The unit a variable has in modelDescription.xml; "1" for the Integer, Enumeration and Boolean ones,
    which have none (counts, flags, modes)."""
    if variable.type != "Real":
        return "1"
    unit = variable.unit or (variable.declaredType.unit if variable.declaredType is not None else None)
    return unit or "1"


def test_the_table_has_the_fmus_units(gimbal_fmu):
    """Every input and output of the FMU, with the model description's unit; and no FMU-looking name in
    the table that the FMU does not have (a renamed variable)."""
    for variable in gimbal_fmu.model_description.modelVariables:
        if variable.causality in ("input", "output"):
            assert unit_of(variable.name) == model_description_unit(variable), variable.name
    runner_signals = {"time", "u_R1_cmd", "u_R2_cmd", "u_R1_asked", "u_R2_asked", "i_R1_ctrl", "i_R2_ctrl",
                      "i_R1_asked", "i_R2_asked", "alpha_ref", "beta_ref",
                      "alpha_error", "beta_error", "los_azimuth", "los_elevation", "los_error", "los_error_xel",
                      "los_error_el", "heave", "base.omega2[1]", "base.omega2[2]", "base.omega2[3]",
                      "target_azimuth", "target_elevation", "target_range", "alpha_cmd", "beta_cmd", "alpha_cmd_dot",
                      "beta_cmd_dot", "alpha_cmd_ddot", "beta_cmd_ddot"}
    assert set(UNITS) - set(gimbal_fmu.variables) == runner_signals


def test_labels_and_their_reading():
    assert column_label("los.omega[1]") == "los.omega[1] [rad/s]"
    assert csv_header(["time", "los_error", "not_in_the_table"]) == "time [s],los_error [rad],not_in_the_table"
    assert split_label("los.omega[1] [rad/s]") == ("los.omega[1]", "rad/s")
    assert split_label("base.v_a[2]") == ("base.v_a[2]", None)
    for name, unit in UNITS.items():
        assert split_label(column_label(name)) == (name, unit)


def read_header(path: pathlib.Path) -> list[str]:
    with open(path, newline="") as f:
        return next(csv.reader(f))


@pytest.mark.parametrize("scene_file", ["ship_stabilization.toml", "free_swing.toml"])
def test_every_column_of_a_run_has_its_unit_in_the_csv_and_the_parquet_file(scene_file, fmu_path, tmp_path):
    """The streamed run (`gimbal2axis run`) and the run in memory (RunResult.write_csv) alike."""
    path = ROOT / "scenes" / scene_file
    result, csv_path, _ = run_scene_file(path, fmu_path, tmp_path / "streamed", stop_time=0.05, stream=True)
    header = read_header(csv_path)
    names = [split_label(label)[0] for label in header]
    assert [split_label(label)[1] for label in header if split_label(label)[1] is None] == [], header
    assert header[0] == "time [s]" and "alpha [rad]" in header and "los_error [rad]" in header
    assert "u_R1 [V]" in header and "i_R1 [A]" in header and "T_E1 [N.m]" in header
    schema = pq.read_schema(csv_path.with_suffix(".parquet"))
    assert schema.names == names
    assert {field.name: field.metadata[b"unit"].decode() for field in schema} == {n: UNITS[n] for n in names}

    with FMU(fmu_path) as fmu:
        in_memory = run(load_scene(path), fmu, stop_time=0.05)
    in_memory.write_csv(tmp_path / "in_memory.csv")
    assert read_header(tmp_path / "in_memory.csv") == header

