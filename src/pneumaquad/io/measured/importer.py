"""Read lab recordings (CSV, MATLAB v5 and v7.3 ``.mat``) into the project's SI columns.

The output matches a simulated rig recording (`pneumaquad.rig.simulate.RIG_COLUMNS`,
`pneumaquad.io.run_folder.read_recording`): a dict of float64 arrays keyed ``"time [s]"``,
``"position [m]"``, ``"cap pressure [Pa]"`` (absolute), ... Only the columns named in the
mapping are read. Every problem found is reported at once in a `MeasuredDataError`; no
sample is dropped or repaired.
"""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .mapping import (
    QUANTITIES,
    ColumnMapping,
    ColumnSpec,
    MeasuredDataError,
    load_mapping,
    mapping_from_dict,
    to_si,
)

__all__ = ["list_source_columns", "read_measured", "read_source"]

_CSV_DELIMITERS = {".csv": ",", ".txt": ",", ".tsv": "\t"}
_SHOWN_INDICES = 5


def read_measured(
    path: str | Path,
    mapping: ColumnMapping | Mapping[str, Any] | str | Path,
    *,
    atmospheric_pressure: float | None = None,
    delimiter: str | None = None,
) -> dict[str, np.ndarray]:
    """Import a lab recording and convert the mapped columns to SI.

    Parameters
    ----------
    path : str or Path
        ``.csv``/``.txt`` (comma), ``.tsv`` (tab) with one header row, or ``.mat``
        (v5 read with `scipy.io.loadmat`, v7.3 with `h5py`).
    mapping : ColumnMapping, dict, or path of a TOML file
        Which source column is which quantity, and its unit (see
        `pneumaquad.io.measured.mapping`).
    atmospheric_pressure : float, optional
        Overrides the mapping's atmospheric pressure added to gauge units [Pa].
    delimiter : str, optional
        CSV delimiter, overriding the one implied by the file suffix.

    Returns
    -------
    dict of str to numpy.ndarray
        Project column names (``"time [s]"``, ``"position [m]"``, ...) to SI values,
        pressures absolute, in the order of `QUANTITIES`.

    Raises
    ------
    MeasuredDataError
        Naming the file, the column and the problem: unreadable file, mapped columns
        missing (with the available ones listed), non-numeric cells, columns of different
        lengths, NaNs (count and first indices), time not strictly increasing (index and
        values), or a mapping problem.
    """
    path = Path(path)
    if not isinstance(mapping, ColumnMapping):
        mapping = (
            mapping_from_dict(mapping) if isinstance(mapping, Mapping) else load_mapping(mapping)
        )
    atmosphere = mapping.atmospheric_pressure
    if atmospheric_pressure is not None:
        if not (np.isfinite(atmospheric_pressure) and atmospheric_pressure > 0):
            raise MeasuredDataError(
                [f"atmospheric pressure {atmospheric_pressure!r} must be a positive number [Pa]"],
                str(path),
            )
        atmosphere = float(atmospheric_pressure)
    variables = read_source(path, delimiter=delimiter, wanted=_wanted(mapping))
    problems: list[str] = []
    raw: dict[str, np.ndarray] = {}
    for quantity, spec in mapping.columns.items():
        values = _extract(quantity, spec, variables, problems)
        if values is not None:
            raw[quantity] = values
    _check_lengths(mapping, raw, problems)
    for quantity, values in raw.items():
        _check_finite(quantity, mapping.columns[quantity], values, problems)
    if "time" in raw and np.all(np.isfinite(raw["time"])):
        _check_time(mapping.columns["time"], raw["time"], problems)
    if problems:
        raise MeasuredDataError(problems, str(path))
    return {
        QUANTITIES[quantity].column: np.ascontiguousarray(
            to_si(raw[quantity], mapping.columns[quantity].unit, QUANTITIES[quantity].kind,
                  atmosphere), dtype=np.float64
        )
        for quantity in QUANTITIES
        if quantity in raw
    }


def read_source(
    path: str | Path, *, delimiter: str | None = None, wanted: set[str] | None = None
) -> dict[str, np.ndarray | list[str]]:
    """Raw columns/variables of a source file, without unit conversion.

    CSV columns come back as lists of cell strings (parsed later, only when mapped);
    MATLAB variables as numeric arrays in MATLAB orientation (rows x columns; vectors
    1-D). Struct fields are named ``"struct.field"``.

    Parameters
    ----------
    path : str or Path
        The recording.
    delimiter : str, optional
        CSV delimiter override.
    wanted : set of str, optional
        CSV headers to keep (all when None); others are listed with empty content.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise MeasuredDataError(["no such file"], str(path))
    if suffix == ".mat":
        return dict(_read_mat(path))
    if suffix in _CSV_DELIMITERS or delimiter is not None:
        return dict(_read_csv(path, delimiter or _CSV_DELIMITERS.get(suffix, ","), wanted))
    raise MeasuredDataError(
        [f"unsupported file type {path.suffix!r}; expected .csv, .txt, .tsv or .mat"], str(path)
    )


def list_source_columns(path: str | Path, *, delimiter: str | None = None) -> list[str]:
    """Names of the columns (CSV) or numeric variables (MAT, with matrix sizes) in a file."""
    return _describe(read_source(path, delimiter=delimiter))


def _wanted(mapping: ColumnMapping) -> set[str]:
    return {spec.source for spec in mapping.columns.values()}


def _read_csv(path: Path, delimiter: str, wanted: set[str] | None) -> dict[str, list[str]]:
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.reader(handle, delimiter=delimiter))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise MeasuredDataError([f"cannot read the CSV file: {error}"], str(path)) from None
    if not rows:
        raise MeasuredDataError(["the file is empty (no header row)"], str(path))
    header = [name.strip() for name in rows[0]]
    problems = []
    duplicates = sorted({name for name in header if header.count(name) > 1})
    if duplicates and (wanted is None or set(duplicates) & wanted):
        problems.append(f"duplicate column names {duplicates} in the header")
    body = rows[1:]
    # Entirely empty lines (e.g. a trailing newline) carry no data.
    numbered = [(number, row) for number, row in enumerate(body, start=2) if any(row)]
    ragged = [number for number, row in numbered if len(row) != len(header)]
    if ragged:
        problems.append(
            f"{len(ragged)} line(s) do not have {len(header)} cells like the header, first "
            f"at line(s) {ragged[:_SHOWN_INDICES]}"
        )
    if problems:
        raise MeasuredDataError(problems, str(path))
    columns: dict[str, list[str]] = {}
    for index, name in enumerate(header):
        keep = wanted is None or name in wanted
        columns[name] = [row[index] for _, row in numbered] if keep else []
    return columns


def _read_mat(path: Path) -> dict[str, np.ndarray]:
    import h5py

    if h5py.is_hdf5(path):
        try:
            with h5py.File(path, "r") as handle:
                return dict(_hdf5_variables(handle, ""))
        except OSError as error:
            raise MeasuredDataError(
                [f"cannot read the MAT v7.3 file: {error}"], str(path)
            ) from None
    from scipy.io import loadmat

    try:
        content = loadmat(path, simplify_cells=True)
    except (OSError, ValueError, NotImplementedError, TypeError) as error:
        raise MeasuredDataError([f"cannot read the MAT file: {error}"], str(path)) from None
    return dict(_mat5_variables(content, ""))


def _mat5_variables(content: Mapping[str, Any], prefix: str):
    for name, value in content.items():
        if name.startswith("__"):
            continue
        if isinstance(value, Mapping):
            yield from _mat5_variables(value, f"{prefix}{name}.")
        elif isinstance(value, np.ndarray) and value.dtype.kind in "fiub":
            yield prefix + name, value
        elif isinstance(value, int | float) and not isinstance(value, bool):
            yield prefix + name, np.asarray([value], dtype=float)


def _hdf5_variables(group, prefix: str):
    import h5py

    for name, item in group.items():
        if name.startswith("#"):  # MATLAB's "#refs#" / "#subsystem#" bookkeeping
            continue
        if isinstance(item, h5py.Group):
            yield from _hdf5_variables(item, f"{prefix}{name}.")
            continue
        if item.attrs.get("MATLAB_empty", 0) or item.dtype.kind not in "fiub":
            continue
        # MATLAB writes column-major data, so HDF5 shows the transpose of the MATLAB array.
        values = np.asarray(item[()]).T
        if values.ndim == 2 and 1 in values.shape:
            values = values.ravel()
        yield prefix + name, values


def _describe(variables: Mapping[str, Any]) -> list[str]:
    described = []
    for name, values in variables.items():
        if isinstance(values, np.ndarray) and values.ndim > 1:
            described.append(f"{name} ({'x'.join(map(str, values.shape))})")
        else:
            described.append(name)
    return described


def _extract(
    quantity: str, spec: ColumnSpec, variables: Mapping[str, Any], problems: list[str]
) -> np.ndarray | None:
    label = f"{quantity} ({spec.describe()})"
    if spec.source not in variables:
        problems.append(
            f"{label}: no column or variable {spec.source!r}; available: {_describe(variables)}"
        )
        return None
    content = variables[spec.source]
    if isinstance(content, list):
        return _parse_cells(label, content, problems)
    values = np.asarray(content)
    if values.ndim == 0:
        values = values.reshape(1)
    if spec.column is not None:
        if values.ndim != 2 or spec.column > values.shape[1]:
            columns = values.shape[1] if values.ndim == 2 else 1
            problems.append(
                f"{label}: column {spec.column} requested but {spec.source!r} has "
                f"shape {values.shape} ({columns} column(s))"
            )
            return None
        return values[:, spec.column - 1].astype(float)
    if values.ndim != 1:
        problems.append(
            f"{label}: {spec.source!r} is a {'x'.join(map(str, values.shape))} array; "
            "give 'column' (1-based) to pick one of its columns"
        )
        return None
    return values.astype(float)


def _parse_cells(label: str, cells: list[str], problems: list[str]) -> np.ndarray | None:
    values = np.empty(len(cells))
    bad: list[tuple[int, str]] = []
    for index, cell in enumerate(cells):
        text = cell.strip()
        if not text:
            values[index] = np.nan  # an empty cell is a missing value: reported as NaN
            continue
        try:
            values[index] = float(text)
        except ValueError:
            bad.append((index, cell))
    if bad:
        shown = ", ".join(f"{cell!r} at index {index}" for index, cell in bad[:_SHOWN_INDICES])
        problems.append(f"{label}: {len(bad)} non-numeric value(s): {shown}")
        return None
    return values


def _check_lengths(
    mapping: ColumnMapping, raw: Mapping[str, np.ndarray], problems: list[str]
) -> None:
    lengths = {quantity: values.size for quantity, values in raw.items()}
    if len(set(lengths.values())) > 1:
        listed = ", ".join(
            f"{quantity} ({mapping.columns[quantity].describe()}): {count}"
            for quantity, count in lengths.items()
        )
        problems.append(f"columns have different numbers of samples: {listed}")
    if any(count == 0 for count in lengths.values()):
        problems.append("the recording holds no samples")


def _check_finite(quantity: str, spec: ColumnSpec, values: np.ndarray, problems: list[str]):
    bad = np.nonzero(~np.isfinite(values))[0]
    if bad.size:
        problems.append(
            f"{quantity} ({spec.describe()}): {bad.size} NaN/missing or infinite value(s) of "
            f"{values.size}, first at indices {bad[:_SHOWN_INDICES].tolist()}"
        )


def _check_time(spec: ColumnSpec, times: np.ndarray, problems: list[str]) -> None:
    steps = np.diff(times)
    bad = np.nonzero(steps <= 0)[0]
    if bad.size:
        first = int(bad[0]) + 1
        problems.append(
            f"time ({spec.describe()}): not strictly increasing at {bad.size} place(s); "
            f"first at index {first}, where it goes from {times[first - 1]:.10g} to "
            f"{times[first]:.10g} {spec.unit} (indices {(bad[:_SHOWN_INDICES] + 1).tolist()})"
        )
