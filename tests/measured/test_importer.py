"""Import of lab recordings: CSV, MAT v5, MAT v7.3, unit conversion and error messages."""

from __future__ import annotations

import pickle

import h5py
import numpy as np
import pytest
from scipy.io import savemat

from pneumaquad.io.measured import (
    MeasuredDataError,
    list_source_columns,
    load_mapping,
    mapping_from_dict,
    read_measured,
)
from pneumaquad.rig.simulate import RIG_COLUMNS

PSI = 6894.757  # Pa per psi, to 7 significant digits (lbf/in^2)
INCH = 0.0254  # m
ATMOSPHERE = 101325.0  # Pa

COUNT = 50
TIME_MS = np.arange(COUNT) * 1.0  # 1 ms sampling, in ms
POSITION_IN = np.linspace(0.1, 1.6, COUNT)
CAP_PSIG = np.linspace(10.0, 60.0, COUNT)
ROD_PSIA = np.linspace(70.0, 30.0, COUNT)
SUPPLY_BARG = np.full(COUNT, 4.5)
COMMAND_V = np.linspace(2.0, 8.0, COUNT)

MAPPING = {
    "time": {"source": "t", "unit": "ms"},
    "position": {"source": "x", "unit": "in"},
    "cap pressure": {"source": "p_cap", "unit": "psig"},
    "rod_pressure": ("p_rod", "psia"),
    "supply pressure": {"source": "p_supply", "unit": "barg"},
    "command": {"source": "u", "unit": "V"},
}


def check_converted(data: dict[str, np.ndarray], atmosphere: float = ATMOSPHERE) -> None:
    """Compare with conversions written out here, independently of the importer's table."""
    assert list(data) == [
        "time [s]",
        "position [m]",
        "cap pressure [Pa]",
        "rod pressure [Pa]",
        "supply pressure [Pa]",
        "command [V]",
    ]
    assert set(data) <= set(RIG_COLUMNS)  # same names as a simulated rig recording
    np.testing.assert_allclose(data["time [s]"], TIME_MS / 1000)
    np.testing.assert_allclose(data["position [m]"], POSITION_IN * INCH)
    np.testing.assert_allclose(data["cap pressure [Pa]"], CAP_PSIG * PSI + atmosphere, rtol=1e-6)
    np.testing.assert_allclose(data["rod pressure [Pa]"], ROD_PSIA * PSI, rtol=1e-6)
    np.testing.assert_allclose(data["supply pressure [Pa]"], 4.5e5 + atmosphere)
    np.testing.assert_allclose(data["command [V]"], COMMAND_V)
    assert all(values.dtype == np.float64 for values in data.values())


def write_csv(path, columns: dict[str, list], header=None) -> None:
    names = header or list(columns)
    rows = [",".join(names)]
    rows += [",".join(str(v) for v in values) for values in zip(*columns.values(), strict=True)]
    path.write_text("\n".join(rows) + "\n")


def lab_columns() -> dict[str, list]:
    return {
        "t": list(TIME_MS),
        "x": list(POSITION_IN),
        "p_cap": list(CAP_PSIG),
        "p_rod": list(ROD_PSIA),
        "p_supply": list(SUPPLY_BARG),
        "u": list(COMMAND_V),
        "unused": ["junk"] * COUNT,
    }


def test_csv_round_trip_with_dict_mapping(tmp_path):
    path = tmp_path / "step.csv"
    write_csv(path, lab_columns())
    data = read_measured(path, MAPPING)
    check_converted(data)
    # Spot values worked out by hand: 10 psig = 68947.57 Pa + 101325 Pa; 0.1 in = 2.54 mm.
    assert data["cap pressure [Pa]"][0] == pytest.approx(170272.57, abs=0.01)
    assert data["position [m]"][0] == pytest.approx(0.00254)
    assert data["supply pressure [Pa]"][0] == pytest.approx(551325.0)


def test_toml_mapping_and_atmospheric_pressure(tmp_path):
    path = tmp_path / "step.csv"
    write_csv(path, lab_columns())
    toml = tmp_path / "mapping.toml"
    toml.write_text(
        'atmospheric_pressure = "14.2 psia"\n\n[columns]\n'
        'time = { source = "t", unit = "ms" }\n'
        'position = { source = "x", unit = "in" }\n'
        'cap_pressure = { source = "p_cap", unit = "PSIG" }\n'
        'rod_pressure = { source = "p_rod", unit = "psia" }\n'
        '"supply pressure" = { source = "p_supply", unit = "barg" }\n'
        'command = { source = "u", unit = "V" }\n'
    )
    mapping = load_mapping(toml)
    assert mapping.atmospheric_pressure == pytest.approx(14.2 * PSI, rel=1e-6)
    check_converted(read_measured(path, toml), atmosphere=14.2 * PSI)
    check_converted(read_measured(path, mapping, atmospheric_pressure=95000.0), 95000.0)


def test_mat_v5_vectors_rows_matrix_and_struct(tmp_path):
    path = tmp_path / "step.mat"
    # A thesis-style log matrix (cf. App. A.2 data(:,k)), a row vector, a column vector, and
    # a struct field.
    data = np.column_stack([POSITION_IN, CAP_PSIG, ROD_PSIA])
    savemat(
        path,
        {
            "data": data,
            "t": TIME_MS.reshape(1, -1),
            "u": COMMAND_V.reshape(-1, 1),
            "sensors": {"supply": SUPPLY_BARG.reshape(-1, 1)},
        },
    )
    mapping = {
        "time": ("t", "ms"),
        "position": {"source": "data", "column": 1, "unit": "in"},
        "cap pressure": {"source": "data", "column": 2, "unit": "psig"},
        "rod pressure": {"source": "data", "column": 3, "unit": "psia"},
        "supply pressure": ("sensors.supply", "barg"),
        "command": ("u", "V"),
    }
    check_converted(read_measured(path, mapping))
    assert "data (50x3)" in list_source_columns(path)


def write_mat73(path, variables: dict[str, np.ndarray], struct: dict[str, np.ndarray]) -> None:
    """Write a MATLAB v7.3-style file: HDF5 with a 512-byte user block, arrays transposed."""
    with h5py.File(path, "w", userblock_size=512) as handle:
        for name, values in variables.items():
            # MATLAB stores column-major: an n-by-m array appears as m-by-n in HDF5.
            dataset = handle.create_dataset(name, data=np.atleast_2d(values).T)
            dataset.attrs["MATLAB_class"] = np.bytes_("double")
        group = handle.create_group("log")
        group.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, values in struct.items():
            group.create_dataset(name, data=np.atleast_2d(values).T)
        handle.create_group("#refs#")
    with open(path, "r+b") as raw:
        raw.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 .")


def test_mat_v73_column_and_row_vectors_and_matrix(tmp_path):
    path = tmp_path / "step73.mat"
    write_mat73(
        path,
        {
            "t": TIME_MS.reshape(-1, 1),  # MATLAB column vector
            "u": COMMAND_V.reshape(1, -1),  # MATLAB row vector
            "data": np.column_stack([POSITION_IN, CAP_PSIG, ROD_PSIA]),  # 50-by-3 in MATLAB
        },
        {"supply": SUPPLY_BARG.reshape(-1, 1)},
    )
    with h5py.File(path, "r") as handle:
        assert handle["data"].shape == (3, COUNT)  # the transposed storage really happened
    mapping = {
        "time": ("t", "ms"),
        "position": {"source": "data", "column": 1, "unit": "in"},
        "cap pressure": {"source": "data", "column": 2, "unit": "psig"},
        "rod pressure": {"source": "data", "column": 3, "unit": "psia"},
        "supply pressure": ("log.supply", "barg"),
        "command": ("u", "V"),
    }
    check_converted(read_measured(path, mapping))
    assert "data (50x3)" in list_source_columns(path)


def error_of(path, mapping, **kwargs) -> str:
    with pytest.raises(MeasuredDataError) as caught:
        read_measured(path, mapping, **kwargs)
    return str(caught.value)


def test_missing_column_lists_the_available_ones(tmp_path):
    path = tmp_path / "step.csv"
    write_csv(path, lab_columns())
    message = error_of(path, {**MAPPING, "position": ("pos", "mm")})
    assert str(path) in message
    assert "position ('pos')" in message
    assert "no column or variable 'pos'" in message
    for name in ("t", "x", "p_cap", "p_rod", "p_supply", "u", "unused"):
        assert f"'{name}'" in message


def test_non_monotonic_time_names_index_and_values(tmp_path):
    columns = lab_columns()
    columns["t"][7] = 5.0  # ... 6.0, 5.0, 8.0 ...
    columns["t"][20] = 19.0  # repeated
    path = tmp_path / "step.csv"
    write_csv(path, columns)
    message = error_of(path, MAPPING)
    assert "time ('t')" in message
    assert "not strictly increasing at 2 place(s)" in message
    assert "index 7" in message
    assert "from 6 to 5 ms" in message
    assert "[7, 20]" in message


def test_nans_are_counted_per_column_with_first_indices(tmp_path):
    columns = lab_columns()
    for index in (3, 4, 30):
        columns["p_cap"][index] = ""  # empty cell: missing
    columns["x"][11] = "NaN"
    path = tmp_path / "step.csv"
    write_csv(path, columns)
    message = error_of(path, MAPPING)
    assert message.startswith(f"2 problems with measured data in {path}")
    assert "cap pressure ('p_cap'): 3 NaN/missing" in message
    assert "[3, 4, 30]" in message
    assert "position ('x'): 1 NaN/missing" in message
    assert "[11]" in message


def test_non_numeric_and_ragged_lines(tmp_path):
    columns = lab_columns()
    columns["u"][9] = "7.0V"
    path = tmp_path / "step.csv"
    write_csv(path, columns)
    message = error_of(path, MAPPING)
    assert "command ('u'): 1 non-numeric value(s): '7.0V' at index 9" in message
    path.write_text(path.read_text() + "1,2,3\n")
    assert "do not have 7 cells like the header" in error_of(path, MAPPING)


@pytest.mark.parametrize(
    ("entry", "expected"),
    [
        (("p_cap", "in"), ["cap pressure: unit 'in' is a length", "expected a pressure"]),
        (("p_cap", "psi"), ["'psi' does not say gauge or absolute", "'psig'", "'psia'"]),
        (("p_cap", "bar"), ["'bar' does not say gauge or absolute", "'barg'", "'bara'"]),
        (("p_cap", "furlong"), ["unit 'furlong' is a length", "psig"]),
        (("p_cap", "bogus"), ["unit 'bogus' could not be parsed", "psig"]),
        ({"source": "p_cap"}, ["'unit' must be a unit name"]),
        ({"source": "p_cap", "unit": "psig", "column": 0}, ["1-based"]),
    ],
)
def test_unit_and_entry_problems(entry, expected):
    with pytest.raises(MeasuredDataError) as caught:
        mapping_from_dict({**MAPPING, "cap pressure": entry}, origin="lab.toml")
    message = str(caught.value)
    assert "lab.toml" in message
    for fragment in expected:
        assert fragment in message


def test_mapping_level_problems_are_all_reported():
    with pytest.raises(MeasuredDataError) as caught:
        mapping_from_dict(
            {
                "columns": {"position": ("x", "V"), "force": ("f", "N")},
                "atmospheric_pressure": -3,
            }
        )
    problems = caught.value.problems
    assert len(problems) == 4
    assert any("position: unit 'V' is a voltage; expected a length" in p for p in problems)
    assert any("unknown quantity 'force'" in p for p in problems)
    assert any("no 'time' entry" in p for p in problems)
    assert any("atmospheric_pressure: -3" in p for p in problems)
    for text in ("14.7 psig", "1 in", "abc psia", "101325"):
        with pytest.raises(MeasuredDataError, match="atmospheric_pressure"):
            mapping_from_dict({"columns": MAPPING, "atmospheric_pressure": text})
    kilopascal = mapping_from_dict({"columns": MAPPING, "atmospheric_pressure": "101.3 kPa"})
    assert kilopascal.atmospheric_pressure == pytest.approx(101300.0)
    copy = pickle.loads(pickle.dumps(caught.value))
    assert str(copy) == str(caught.value)
    assert isinstance(caught.value, ValueError)


def test_mat_problems_lengths_matrix_and_column_range(tmp_path):
    path = tmp_path / "bad.mat"
    savemat(path, {"t": TIME_MS, "x": POSITION_IN[:-2], "data": np.ones((COUNT, 2))})
    message = error_of(path, {"time": ("t", "ms"), "position": ("x", "in")})
    assert "different numbers of samples" in message
    assert "time ('t'): 50" in message and "position ('x'): 48" in message
    message = error_of(path, {"time": ("t", "ms"), "position": ("data", "in")})
    assert "'data' is a 50x2 array; give 'column'" in message
    entry = {"source": "data", "column": 3, "unit": "in"}
    message = error_of(path, {"time": ("t", "ms"), "position": entry})
    assert "column 3 requested but 'data' has shape (50, 2)" in message


def test_file_level_problems(tmp_path):
    assert "no such file" in error_of(tmp_path / "absent.csv", MAPPING)
    other = tmp_path / "run.xlsx"
    other.write_bytes(b"x")
    assert "unsupported file type '.xlsx'" in error_of(other, MAPPING)
    broken = tmp_path / "broken.mat"
    broken.write_bytes(b"not a mat file at all" * 10)
    assert "cannot read the MAT file" in error_of(broken, MAPPING)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    assert "empty" in error_of(empty, MAPPING)
    bad_toml = tmp_path / "bad.toml"
    bad_toml.write_text("columns = [")
    with pytest.raises(MeasuredDataError, match="invalid TOML"):
        load_mapping(bad_toml)
    path = tmp_path / "step.csv"
    write_csv(path, lab_columns())
    assert "atmospheric pressure" in error_of(path, MAPPING, atmospheric_pressure=0.0)


@pytest.mark.parametrize("unit", ["psig", "psia", "barg", "bara", "kPa", "kPag", "atm", "mm", "in"])
def test_lab_units_convert_as_parameter_files_do(unit):
    """One unit system: a lab column in ``unit`` converts like a parameter in ``unit``."""
    from pneumaquad.io.measured.mapping import to_si
    from pneumaquad.params.units import convert_quantity

    kind = "length" if unit in {"mm", "in"} else "pressure"
    atmosphere = 98000.0
    column = to_si(np.array([2.5]), unit, kind, atmosphere)[0]
    assert column == convert_quantity(f"2.5 {unit}", kind, atmospheric_pressure=atmosphere)


@pytest.mark.parametrize(("written", "quantity", "spelled"), [
    ("PSIG", "cap pressure", "psig"), ("KPA", "cap pressure", "kPa"), ("MS", "time", "ms"),
    ("MM", "position", "mm"), ("mPa", "cap pressure", "mPa"),
])
def test_capitalised_lab_units_take_their_usual_spelling(written, quantity, spelled):
    """A name that is not a unit of the quantity's kind as written (pint reads "MS" as
    megasiemens) is matched to the usual unit regardless of case; a real unit of the
    right kind as written ("mPa") is kept."""
    mapping = mapping_from_dict({"columns": {"time": ("t", "s"), quantity: ("x", written)}})
    assert mapping.columns[quantity].unit == spelled
