"""Running a study: the cases not yet recorded, batch by batch, each row kept as it ends.

:func:`run_study` draws the cases (:func:`.sampling.study_cases`), skips those the study
folder holds already (a killed study started again loses at most its running batches),
hands the rest to an executor in batches of ``spec.batch`` cases and appends each batch's
rows to the folder as it finishes (:class:`.results.ResultStore`). A failed case is a row
with its error; the study goes on. When the run ends, or stops on Ctrl-C, the parts are
gathered into ``results.parquet``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from .case_runs import CaseInterruptedError
from .executors import Executor, Task, serial_executor
from .progress import StudyProgress
from .results import RUNS_FOLDER, ResultStore, read_results
from .sampling import Case, study_cases
from .spec import StudySpec

__all__ = ["StudyRun", "run_study", "study_tasks"]


@dataclass(frozen=True)
class StudyRun:
    """What one run of a study did.

    Attributes
    ----------
    folder : Path
    total : int
        Cases of the study.
    skipped : int
        Cases recorded before this run.
    ran : int
        Cases this run recorded.
    failed : int
        Failed cases of the whole study so far.
    wall_time : float
        This run's wall time [s].
    stopped : bool
        Whether Ctrl-C stopped it before the end.
    """

    folder: Path
    total: int
    skipped: int
    ran: int
    failed: int
    wall_time: float
    stopped: bool

    @property
    def cases_per_second(self) -> float:
        """Cases this run recorded per second of its wall time."""
        return self.ran / self.wall_time if self.wall_time > 0 else float("nan")


def study_tasks(spec: StudySpec, cases: list[Case], folder: Path) -> list[Task]:
    """The batches of ``cases`` (in index order, ``spec.batch`` at most each)."""
    runs = str(folder / RUNS_FOLDER) if spec.keep_runs else None
    return [Task(spec.run, spec.metrics, tuple(cases[i:i + spec.batch]), runs)
            for i in range(0, len(cases), spec.batch)]


def _failed_so_far(folder: Path) -> int:
    table = read_results(folder, columns=["status"])
    if table is None:
        return 0
    return sum(1 for status in table.column("status").to_pylist() if status != "ok")


def run_study(spec: StudySpec, folder: Path, executor: Executor = serial_executor,
              progress: StudyProgress | None = None, limit: int | None = None) -> StudyRun:
    """Run the cases of ``spec`` the folder does not hold yet.

    Parameters
    ----------
    spec : StudySpec
    folder : Path
        The study folder (created; a folder of another study is refused).
    executor : callable
        :func:`.executors.serial_executor` (this process),
        :func:`.executors.pool_executor` or :func:`.executors.ray_executor`.
    progress : StudyProgress, optional
        Told of every finished batch; its counts start from the folder's.
    limit : int, optional
        Run at most this many of the missing cases (the first ones), e.g. to try a study.

    Returns
    -------
    StudyRun

    Raises
    ------
    ParameterError
        The folder holds another study.
    """
    started = time.perf_counter()
    store = ResultStore(folder, spec)
    cases = study_cases(spec)
    done = store.finished()
    missing = [case for case in cases if case.index not in done]
    if limit is not None:
        missing = missing[:limit]
    if progress is not None:
        progress.done, progress.failed = len(done), _failed_so_far(folder)
    ran, stopped = 0, False
    try:
        for task, outcomes in executor(study_tasks(spec, missing, folder)):
            store.append(task.cases, outcomes)
            ran += len(outcomes)
            if progress is not None:
                progress.update(len(outcomes), sum(o.status != "ok" for o in outcomes))
    except (KeyboardInterrupt, CaseInterruptedError):
        stopped = True
    finally:
        store.consolidate()
        if progress is not None:
            progress.close()
    return StudyRun(Path(folder), len(cases), len(done), ran, _failed_so_far(folder),
                    time.perf_counter() - started, stopped)
