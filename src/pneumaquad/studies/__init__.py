"""Studies: many runs of one experiment with varied parameters (docs/studies.md).

A study is a TOML file (:mod:`.spec`): a base run (a rig step or sine, a robot stand-up
or walk), the ``--set`` keys it varies (a grid, a list, or distributions sampled by Latin
hypercube or Sobol, :mod:`.distributions`, :mod:`.sampling`), and the summary figures to
collect. :func:`run_study` runs it in this process, a local process pool or on Ray
(:mod:`.executors`), keeping each finished case in a Parquet dataset (:mod:`.results`);
:mod:`.report` writes its HTML report with a sensitivity table (:mod:`.sensitivity`).
"""

from .executors import default_workers, pool_executor, ray_executor, serial_executor
from .progress import StudyProgress
from .results import read_results
from .sampling import Case, case_seed, study_cases
from .spec import StudySpec, VariedParameter, load_study, parse_study
from .study_run import StudyRun, run_study

__all__ = [
    "Case",
    "StudyProgress",
    "StudyRun",
    "StudySpec",
    "VariedParameter",
    "case_seed",
    "default_workers",
    "load_study",
    "parse_study",
    "pool_executor",
    "ray_executor",
    "read_results",
    "run_study",
    "serial_executor",
    "study_cases",
]
