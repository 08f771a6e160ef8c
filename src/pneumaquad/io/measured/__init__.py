"""Import of lab recordings (CSV, MATLAB .mat) into the project's SI recording columns.

A column mapping (`pneumaquad.io.measured.mapping`) says which source column is which
quantity and in what unit; `read_measured` returns the same ``"quantity [unit]"`` columns
as a simulated rig recording, so the two can be compared with
`pneumaquad.analysis.compare_recordings`.
"""

from .importer import list_source_columns, read_measured, read_source
from .mapping import (
    QUANTITIES,
    STANDARD_ATMOSPHERE,
    ColumnMapping,
    ColumnSpec,
    MeasuredDataError,
    load_mapping,
    mapping_from_dict,
)

__all__ = [
    "QUANTITIES",
    "STANDARD_ATMOSPHERE",
    "ColumnMapping",
    "ColumnSpec",
    "MeasuredDataError",
    "list_source_columns",
    "load_mapping",
    "mapping_from_dict",
    "read_measured",
    "read_source",
]
