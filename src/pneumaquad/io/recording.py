"""Streamed recordings of a run: the names of :mod:`pneumaquad.io.run_folder`, which owns
the run folder's layout, kept importable from here.

A run writes its time series to ``recording.csv`` while it runs (one flushed block at a
time, so an interrupted run still leaves a readable file) and to ``recording.parquet``
once it closes. Columns are named ``quantity [unit]`` in SI units, e.g. ``"time [s]"``,
``"position [m]"``, ``"cap pressure [Pa]"``. Summaries are written only through
:class:`~pneumaquad.io.run_folder.RunFolderWriter`.
"""

from pneumaquad.io.run_folder import RunRecorder, create_run_folder, jsonable, read_recording

__all__ = ["RunRecorder", "create_run_folder", "jsonable", "read_recording"]
