"""The run folder: one versioned layout, one writer (:class:`RunFolderWriter`) and one
reader (:func:`read_run`, also named :data:`read_run_folder`). docs/run-folder.md describes
the contract.

Every simulator run (rig, robot, networked peer) writes a folder holding

``parameters.toml``    the resolved parameters (SI), loadable again with ``--params``
``recording.csv``      streamed while the run goes, flushed block by block
``recording.parquet``  the same table, written when the run closes
``summary.json``       figures of the run and ``"run folder format"``: :data:`FORMAT_VERSION`

and, for robot runs, ``model.xml`` (MJCF) and ``trajectory.npz`` (time, qpos); networked
runs add ``timing.json`` and ``packets.parquet``. Recording columns are named
``quantity [unit]`` in SI units. Only this module builds these file names and writes or
reads ``summary.json``/``timing.json``; summaries go through one check, so a NaN or an
infinity is stored as ``null`` and a value that is not JSON is refused, at the first write
and at every update alike. A folder written in a newer format than
:data:`FORMAT_VERSION` is refused by the reader with a message naming both versions; a
folder without the key (written before it existed, or by a run killed before its summary)
is read as format 1.

Inside :func:`scratch_run_folders` (a study's cases whose folders are read once and
removed) a run folder's recording has no CSV file and no plots are drawn; the Parquet
file, the summary and the rest are written as always.
"""

from __future__ import annotations

import contextvars
import json
import math
import os
import tomllib
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from pneumaquad.io.tables import StreamedTable, read_table, read_table_metadata

if TYPE_CHECKING:
    from pneumaquad.params import ActuatorParameters, RigSetup, RobotParameters

__all__ = [
    "CSV_NAME", "FORMAT_KEY", "FORMAT_VERSION", "MODEL_NAME", "PACKETS_NAME",
    "PARAMETERS_NAME", "PARQUET_NAME", "PROFILE_NAME", "SUMMARY_NAME", "TIMING_NAME",
    "TRAJECTORY_NAME",
    "RunFolder", "RunFolderError", "RunFolderVersionError", "RunFolderWriter", "RunRecorder",
    "create_run_folder", "detect_run_kind", "drawing_plots", "json_text", "jsonable",
    "read_json", "read_recording", "read_run", "read_run_folder", "read_summary",
    "scratch_run_folders", "write_json",
]

#: Version of the layout below, written into every summary under :data:`FORMAT_KEY`.
FORMAT_VERSION = 1
FORMAT_KEY = "run folder format"
PARAMETERS_NAME = "parameters.toml"
CSV_NAME = "recording.csv"
PARQUET_NAME = "recording.parquet"
SUMMARY_NAME = "summary.json"
MODEL_NAME = "model.xml"
TRAJECTORY_NAME = "trajectory.npz"
TIMING_NAME = "timing.json"
PROFILE_NAME = "profile.json"
PACKETS_NAME = "packets.parquet"

RunKind = Literal["rig", "robot"]

_SCRATCH = contextvars.ContextVar("pneumaquad scratch run folders", default=False)


@contextmanager
def scratch_run_folders() -> Iterator[None]:
    """Within the block, run folders are scratch: read once and removed (a study's case
    whose folder is not kept). Their recording is written as Parquet only, without the
    CSV file that is there for a person or an interrupted run, and no plots are drawn
    (:func:`drawing_plots`): both cost a share of a short run's time."""
    token = _SCRATCH.set(True)
    try:
        yield
    finally:
        _SCRATCH.reset(token)


def drawing_plots() -> bool:
    """Whether a run draws its plots (everywhere but inside :func:`scratch_run_folders`)."""
    return not _SCRATCH.get()


class RunFolderError(ValueError):
    """A folder that is not a readable run folder; the message says why."""


class RunFolderVersionError(RunFolderError):
    """A run folder written in a format this version of pneumaquad does not know."""


def create_run_folder(output: Path | None, kind: str, base: Path = Path("runs")) -> Path:
    """Create the folder a run writes into.

    Parameters
    ----------
    output
        Folder requested by the user. Created if missing; an existing folder is
        reused and its files will be overwritten.
    kind
        Run kind used in the generated name, e.g. ``"rig-step"``.
    base
        Parent of generated folders when ``output`` is ``None``.

    Returns
    -------
    Path
        ``output``, or ``base / f"{kind}-{YYYYmmdd-HHMMSS}"`` with a ``-2``,
        ``-3``, ... suffix appended if that name is already taken.
    """
    if output is not None:
        output = Path(output)
        output.mkdir(parents=True, exist_ok=True)
        return output
    base = Path(base)
    base.mkdir(parents=True, exist_ok=True)
    stem = f"{kind}-{datetime.now():%Y%m%d-%H%M%S}"
    candidate = base / stem
    suffix = 1
    while True:
        try:
            candidate.mkdir()
        except FileExistsError:
            suffix += 1
            candidate = base / f"{stem}-{suffix}"
        else:
            return candidate


class RunRecorder(StreamedTable):
    """The run's recording: ``recording.csv`` written live, ``recording.parquet`` on close.

    Use as a context manager (see :class:`~pneumaquad.io.tables.StreamedTable`).

    Parameters
    ----------
    folder
        Run folder (created if missing).
    columns
        Column names, ``quantity [unit]`` in SI units.
    background
        Write the CSV blocks from a writer thread (see
        :class:`~pneumaquad.io.tables.StreamedTable`).
    write_csv
        False: Parquet only (see :func:`scratch_run_folders`).
    """

    def __init__(self, folder: Path, columns: Sequence[str], background: bool = False,
                 write_csv: bool = True) -> None:
        self.folder = Path(folder)
        super().__init__(self.folder / CSV_NAME, self.folder / PARQUET_NAME, columns,
                         metadata=self._provenance, background=background,
                         write_csv=write_csv)

    def _provenance(self) -> dict[str, str]:
        """The Parquet file's metadata: ``pneumaquad version``, ``run folder format`` and,
        when the folder has them, the resolved parameters (``parameters.toml``)."""
        from pneumaquad import __version__

        metadata = {"pneumaquad version": __version__,
                    "run folder format": str(FORMAT_VERSION)}
        parameters = self.folder / PARAMETERS_NAME
        if parameters.is_file():
            metadata["parameters.toml"] = parameters.read_text(encoding="utf-8")
        return metadata


def jsonable(value: Any, where: str = "value") -> Any:
    """``value`` as plain JSON data: numpy scalars and arrays become numbers and lists,
    NaN and ±inf ``None`` (``null``), paths strings.

    Raises
    ------
    TypeError
        For anything else that JSON cannot hold, naming where it sits (``where``).
    """
    if isinstance(value, Mapping):
        return {str(k): jsonable(v, f"{where} / {k}") for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist(), where)
    if isinstance(value, (list, tuple, set, frozenset)):
        return [jsonable(v, where) for v in value]
    if isinstance(value, np.generic):
        return jsonable(value.item(), where)
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    if value is None or isinstance(value, (str, int, bool)):
        return value
    raise TypeError(f"{where}: {value!r} (of type {type(value).__name__}) is not a JSON "
                    "value (numbers, strings, booleans, lists, tables, None)")


def json_text(document: Mapping[str, Any]) -> str:
    """Strict JSON text of ``document`` (through :func:`jsonable`; never NaN or Infinity)."""
    return json.dumps(jsonable(document, "summary"), indent=2, allow_nan=False) + "\n"


def write_json(path: Path, document: Mapping[str, Any]) -> Path:
    """Write ``document`` as strict JSON (:func:`json_text`) to ``path``; returns it."""
    text = json_text(document)  # checked before the file is touched
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _read_json(file: Path) -> dict[str, Any]:
    try:
        document = json.loads(file.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise RunFolderError(f"{file} is not valid JSON: {error}") from None
    if not isinstance(document, dict):
        raise RunFolderError(f"{file} should hold a JSON object, not {type(document).__name__}")
    return document


def read_json(path: Path) -> dict[str, Any]:
    """A JSON object written by :func:`write_json` (a report's ``comparison.json``, say).

    Raises
    ------
    RunFolderError
        For a file that is not valid JSON or not an object.
    """
    return _read_json(Path(path))


def _format_of(summary: Mapping[str, Any], file: Path) -> int:
    """The format version a summary states (1 without the key); refuses unknown ones."""
    version = summary.get(FORMAT_KEY, 1)
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise RunFolderVersionError(
            f"{file}: {FORMAT_KEY!r} is {version!r}; expected a whole number from 1 to "
            f"{FORMAT_VERSION}")
    if version > FORMAT_VERSION:
        raise RunFolderVersionError(
            f"{file.parent} was written in run folder format {version}; this pneumaquad "
            f"reads format {FORMAT_VERSION} and older (a newer pneumaquad reads it)")
    return version


def read_summary(folder: Path) -> dict[str, Any]:
    """``summary.json`` of a run folder (empty without one), its format checked.

    Raises
    ------
    RunFolderError
        For a file that is not a JSON object.
    RunFolderVersionError
        For a folder of a newer or unknown format.
    """
    file = Path(folder) / SUMMARY_NAME
    if not file.is_file():
        return {}
    summary = _read_json(file)
    _format_of(summary, file)
    return summary


class RunFolderWriter:
    """The one writer of a run folder (module docstring for the files).

    Parameters
    ----------
    folder
        The run folder; created if missing, files in it are overwritten.
    """

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder)
        self.path.mkdir(parents=True, exist_ok=True)

    @classmethod
    def create(cls, output: Path | None, kind: str,
               base: Path = Path("runs")) -> RunFolderWriter:
        """A writer for ``output``, or a new ``base/<kind>-<time>`` (:func:`create_run_folder`)."""
        return cls(create_run_folder(output, kind, base))

    def write_parameters(
        self, parameters: RigSetup | ActuatorParameters | RobotParameters
    ) -> Path:
        """Write ``parameters.toml``: the resolved set, SI, loadable again."""
        from pneumaquad.params import resolved_parameters_toml

        file = self.path / PARAMETERS_NAME
        file.write_text(resolved_parameters_toml(parameters), encoding="utf-8")
        return file

    def write_model(self, xml: str) -> Path:
        """Write ``model.xml``, the MuJoCo model of a robot run."""
        file = self.path / MODEL_NAME
        file.write_text(xml, encoding="utf-8")
        return file

    def write_trajectory(self, times: np.ndarray, qpos: np.ndarray) -> Path:
        """Write ``trajectory.npz``: ``time`` (T,) [s] and ``qpos`` (T, nq) of a robot run."""
        file = self.path / TRAJECTORY_NAME
        np.savez(file, time=np.asarray(times), qpos=np.asarray(qpos))
        return file

    def recorder(self, columns: Sequence[str], background: bool = False) -> RunRecorder:
        """The streamed recording (``recording.csv`` live, ``recording.parquet`` on close;
        ``background``: the CSV blocks written by a writer thread; no CSV file inside
        :func:`scratch_run_folders`)."""
        return RunRecorder(self.path, columns, background=background,
                           write_csv=not _SCRATCH.get())

    @property
    def packets_path(self) -> Path:
        """Where a networked run writes its packet log."""
        return self.path / PACKETS_NAME

    def write_summary(self, summary: Mapping[str, Any]) -> Path:
        """Write ``summary.json`` with the format version first.

        NaN and ±inf become ``null``; numpy values plain numbers and lists, paths strings.

        Raises
        ------
        TypeError
            For a value JSON cannot hold (nothing is written then).
        """
        document = {FORMAT_KEY: FORMAT_VERSION,
                    **{k: v for k, v in summary.items() if k != FORMAT_KEY}}
        return write_json(self.path / SUMMARY_NAME, document)

    def update_summary(self, changes: Mapping[str, Any]) -> dict[str, Any]:
        """Add or replace top-level entries of ``summary.json`` through the same check as
        :meth:`write_summary`; returns the whole summary as written (plain JSON data)."""
        summary = read_summary(self.path) | dict(changes)
        self.write_summary(summary)
        return read_summary(self.path)

    def write_timing(self, timing: Mapping[str, Any]) -> Path:
        """Write ``timing.json``, the packet timing figures of a networked run."""
        return write_json(self.path / TIMING_NAME, timing)

    def write_profile(self, profile: Mapping[str, Any]) -> Path:
        """Write ``profile.json``: where a command's wall time went, stage by stage
        (:meth:`pneumaquad.io.stage_clock.StageClock.report`)."""
        return write_json(self.path / PROFILE_NAME, profile)


def _recording_file(folder: Path) -> Path:
    parquet = folder / PARQUET_NAME
    return parquet if parquet.exists() else folder / CSV_NAME


def read_recording(folder_or_file: Path) -> dict[str, np.ndarray]:
    """Read a recording as one float64 array per column.

    Parameters
    ----------
    folder_or_file
        A run folder (Parquet preferred, the CSV when the run ended before writing it;
        the folder's format is checked) or a ``.parquet``/``.csv`` file.

    Raises
    ------
    FileNotFoundError
        Without a recording.
    ValueError
        For an unreadable file; :class:`RunFolderVersionError` for a newer format.
    """
    path = Path(folder_or_file)
    if path.is_dir():
        read_summary(path)
        path = _recording_file(path)
    if not path.exists():
        raise FileNotFoundError(f"no recording at {folder_or_file}")
    return read_table(path)


def detect_run_kind(raw: Mapping[str, Any]) -> RunKind:
    """``"rig"`` for parameters with a ``[rig]`` table, ``"robot"`` for a ``[leg]`` table.

    Raises
    ------
    RunFolderError
        When neither table is there.
    """
    if "rig" in raw:
        return "rig"
    if "leg" in raw:
        return "robot"
    raise RunFolderError(
        f"{PARAMETERS_NAME} has neither a [rig] table (rig run) nor a [leg] table (robot run)"
    )


@dataclass(frozen=True)
class RunFolder:
    """A run folder as read by :func:`read_run`.

    Attributes
    ----------
    path : Path
    version : int
        Its format (:data:`FORMAT_VERSION` or older; 1 without the key).
    kind : {"rig", "robot"}
        Which simulator wrote it (from the tables of ``parameters.toml``).
    parameters : str
        The text of ``parameters.toml`` (validate it with the matching loader).
    recording : dict of str to numpy.ndarray
        Columns ``"quantity [unit]"`` in SI, from the Parquet file or else the CSV.
    recording_file : Path
        Which of the two it came from.
    summary : dict
        ``summary.json`` (empty when the run ended before writing it).
    timing : dict or None
        ``timing.json`` of a networked run.
    notes : list of str
        What is missing or unreadable among the optional files.
    """

    path: Path
    version: int
    kind: RunKind
    parameters: str
    recording: dict[str, np.ndarray]
    recording_file: Path
    summary: dict[str, Any]
    timing: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def units(self) -> dict[str, str]:
        """Column name → SI unit, from the Parquet file's column metadata (or the CSV
        header's ``quantity [unit]`` names)."""
        return read_table_metadata(self.recording_file).units

    @property
    def parameters_file(self) -> Path:
        """``parameters.toml`` (e.g. for a parameter loader)."""
        return self.path / PARAMETERS_NAME

    @property
    def model_file(self) -> Path | None:
        """``model.xml`` of a robot run, None without one."""
        file = self.path / MODEL_NAME
        return file if file.is_file() else None

    @property
    def trajectory_file(self) -> Path | None:
        """``trajectory.npz`` of a robot run, None without one."""
        file = self.path / TRAJECTORY_NAME
        return file if file.is_file() else None


def read_run(path: str | os.PathLike[str]) -> RunFolder:
    """Read a run folder in one call: recording (with units), parameters and summary.

    Also available as ``pneumaquad.read_run`` and, under its earlier name, as
    :data:`read_run_folder`. An interrupted run reads like any other (its summary says
    ``"interrupted": true``); a run killed before it closed has only ``recording.csv``
    (its unterminated last line dropped) and no summary, which is read as format 1 with a
    note.

    Parameters
    ----------
    path : str or os.PathLike
        The run folder.

    Returns
    -------
    RunFolder
        Its recording (``recording``, columns ``quantity [unit]`` in SI; ``units`` maps
        each column to its unit), the resolved parameters (``parameters``, the text of
        ``parameters.toml``), ``summary``, ``kind``, format ``version``, ``timing`` of a
        networked run and ``notes`` on what was missing.

    Raises
    ------
    RunFolderError
        If the folder does not exist, lacks ``parameters.toml`` or a recording, or a file
        is malformed; :class:`RunFolderVersionError` if it was written in a newer format.
    """
    path = Path(path)
    if not path.exists():
        raise RunFolderError(f"run folder {path} does not exist")
    if not path.is_dir():
        raise RunFolderError(f"{path} is not a folder (expected a run folder)")
    summary = read_summary(path)
    version = _format_of(summary, path / SUMMARY_NAME)
    notes = [] if summary else [f"{SUMMARY_NAME} is missing: the run ended before writing it."]
    file = path / PARAMETERS_NAME
    if not file.is_file():
        raise RunFolderError(f"{path} is not a run folder: it has no {PARAMETERS_NAME}")
    try:
        parameters = file.read_text(encoding="utf-8")
        kind = detect_run_kind(tomllib.loads(parameters))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise RunFolderError(f"{file} is not valid TOML: {error}") from None
    recording_file = _recording_file(path)
    try:
        recording = read_table(recording_file)
    except FileNotFoundError:
        raise RunFolderError(
            f"{path} has no recording ({PARQUET_NAME} or {CSV_NAME})") from None
    except (OSError, ValueError) as error:
        raise RunFolderError(f"the recording in {path} cannot be read: {error}") from None
    if "time [s]" not in recording:
        raise RunFolderError(f"the recording in {path} has no 'time [s]' column")
    timing = None
    if (path / TIMING_NAME).is_file():
        try:
            timing = _read_json(path / TIMING_NAME)
        except RunFolderError as error:
            notes.append(f"{TIMING_NAME} cannot be read: {error}")
    return RunFolder(path, version, kind, parameters, recording, recording_file, summary,
                     timing, notes)


#: :func:`read_run` under its earlier name, kept for existing callers.
read_run_folder = read_run
