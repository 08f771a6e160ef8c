"""Where batches of cases run: this process, a local process pool, or a Ray cluster.

Every executor runs the same function on the same batches (:func:`run_task`), so a case's
row does not depend on the executor. Workers stay warm: a process loads the compiled code
(:func:`.case_runs.warm_up`) before its first batch and keeps it for every later one. An
executor yields each batch's outcomes as the batch finishes, in any order, and keeps only
a few batches per worker in flight, so a stop loses at most those.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from typing import Any

from pneumaquad.params.errors import ParameterError, Problem

from .case_runs import CaseInterruptedError, CaseOutcome, run_batch, warm_up
from .run_options import RunSpec
from .sampling import Case

__all__ = ["Task", "default_workers", "pool_executor", "ray_executor", "run_task",
           "serial_executor"]

#: Kinds whose compiled code this process has loaded already.
_WARM: set[str] = set()
#: Batches in flight per worker (one running, one waiting).
IN_FLIGHT_PER_WORKER = 2


@dataclass(frozen=True)
class Task:
    """One batch of cases: what a worker needs to run it."""

    run: RunSpec
    metrics: tuple[str, ...]
    cases: tuple[Case, ...]
    runs_folder: str | None


def run_task(task: Task) -> list[CaseOutcome]:
    """Run one batch in this process, loading the compiled code first if it has not."""
    if task.run.kind not in _WARM:
        warm_up(task.run.kind)
        _WARM.add(task.run.kind)
    return run_batch(task.run, task.metrics, task.cases, task.runs_folder)


Executor = Callable[[Iterable[Task]], Iterator[tuple[Task, list[CaseOutcome]]]]


def default_workers() -> int:
    """The CPUs this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def serial_executor(tasks: Iterable[Task]) -> Iterator[tuple[Task, list[CaseOutcome]]]:
    """Run every batch in this process, in order (a batch that fails as a whole, outside
    any case, is recorded as failed cases, as a pool records a batch its worker lost)."""
    for task in tasks:
        try:
            outcomes = run_task(task)
        except CaseInterruptedError:
            raise
        except Exception as error:
            outcomes = _failed_batch(task, error, "the batch failed")
        yield task, outcomes


def _worker_started() -> None:
    """A pool worker leaves Ctrl-C to the study (its running case still stops cleanly:
    the simulation's own handler is installed while it runs)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _failed_batch(task: Task, error: BaseException,
                  what: str = "worker lost the batch") -> list[CaseOutcome]:
    """A batch that failed as a whole: each case recorded as failed with the reason."""
    text = f"{type(error).__name__}: {error}"
    return [CaseOutcome(case.index, "failed", f"{what}: {text}",
                        dict.fromkeys(task.metrics, float("nan"))) for case in task.cases]


def pool_executor(workers: int) -> Executor:
    """A local pool of ``workers`` processes (spawned, warm after their first batch)."""

    def execute(tasks: Iterable[Task]) -> Iterator[tuple[Task, list[CaseOutcome]]]:
        context = multiprocessing.get_context("spawn")
        pending = iter(tasks)
        running: dict[Future, Task] = {}
        with ProcessPoolExecutor(workers, mp_context=context,
                                 initializer=_worker_started) as pool:
            try:
                while True:
                    while len(running) < IN_FLIGHT_PER_WORKER * workers:
                        task = next(pending, None)
                        if task is None:
                            break
                        running[pool.submit(run_task, task)] = task
                    if not running:
                        return
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for future in finished:
                        task = running.pop(future)
                        error = future.exception()
                        if error is None:
                            yield task, future.result()
                        elif isinstance(error, (KeyboardInterrupt, CaseInterruptedError)):
                            raise error
                        else:
                            yield task, _failed_batch(task, error)
            finally:
                for future in running:
                    future.cancel()

    return execute


def ray_executor(address: str, workers: int) -> Executor:
    """Batches as Ray tasks: ``address`` "local" starts a local cluster of ``workers``
    CPUs; otherwise it is the address of a running cluster (``ray://host:10001`` or
    ``host:6379``). Each Ray worker process stays warm across its tasks.

    Raises
    ------
    ParameterError
        When Ray is not installed (``pip install 'pneumaquad[cluster]'``).
    """
    try:
        import ray
    except ImportError:
        raise ParameterError([Problem("--ray", address, "needs Ray installed: pip install "
                                      "'pneumaquad[cluster]'")]) from None

    def execute(tasks: Iterable[Task]) -> Iterator[tuple[Task, list[CaseOutcome]]]:
        started_here = not ray.is_initialized()
        if started_here:
            options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            if address == "local":
                ray.init(num_cpus=workers, **options)
            else:
                ray.init(address=address, **options)
        remote = ray.remote(num_cpus=1)(run_task)
        slots = max(1, int(ray.cluster_resources().get("CPU", workers)))
        pending = iter(tasks)
        running: dict[Any, Task] = {}
        try:
            while True:
                while len(running) < IN_FLIGHT_PER_WORKER * slots:
                    task = next(pending, None)
                    if task is None:
                        break
                    running[remote.remote(task)] = task
                if not running:
                    return
                finished, _ = ray.wait(list(running), num_returns=1)
                for reference in finished:
                    task = running.pop(reference)
                    try:
                        outcomes = ray.get(reference)
                    except ray.exceptions.RayError as error:
                        outcomes = _failed_batch(task, error)
                    yield task, outcomes
        finally:
            for reference in running:
                ray.cancel(reference, force=True)
            if started_here:
                ray.shutdown()

    return execute
