"""A study as a TOML file (docs/studies.md): read it and check all of it before any run.

Layout::

    [study]
    name = "thesis-variability-step"
    sampling = "latin-hypercube"   # or "sobol", "saltelli", "grid", "list"
    cases = 256                    # drawn designs (sobol, saltelli: a power of two)
    seed = 2011
    metrics = ["rise time 10-90 % [s]", "motion onset delay [s]"]

    [run]
    kind = "rig-step"              # rig-step, rig-sine, robot-stand, robot-walk
    params = "thesis-rig"
    set = ["rig.load_mass=0.2 kg"] # fixed overrides of every case
    voltage = "6.5 V"              # the run's options

    [vary."friction.static_force"] # any --set key, or run.<option>
    distribution = "uniform"       # uniform, normal, log-normal, quartiles
    low = "3.5 lbf"
    high = "5.0 lbf"

A grid or a list varies ``values = [...]`` instead of a distribution. Every problem ends
in :class:`~pneumaquad.params.errors.ParameterError` naming the spec key, the value and
what was expected, before anything runs.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pneumaquad.params.errors import MISSING, ParameterError, Problem
from pneumaquad.params.loader import load_rig, load_robot
from pneumaquad.rig.metrics import GENERAL_METRICS, STEP_METRICS, TRACKING_METRICS

from .distributions import Distribution, Quantity, parse_distribution, parse_study_quantity
from .run_options import RUN_KINDS, RunSpec, parse_run_options

__all__ = ["MAX_CASES", "SAMPLINGS", "StudySpec", "VariedParameter", "load_study",
           "parse_study"]

#: Sampling designs: how the varied values become cases.
SAMPLINGS = ("latin-hypercube", "sobol", "saltelli", "grid", "list")
#: Samplings that draw from distributions (the others list values).
DRAWN = ("latin-hypercube", "sobol", "saltelli")
#: Most cases of one study.
MAX_CASES = 1_000_000
#: Metrics a rig run's summary gives, by run kind.
RIG_METRICS = {"rig-step": GENERAL_METRICS + STEP_METRICS,
               "rig-sine": GENERAL_METRICS + TRACKING_METRICS}
#: Cases per task: rigs run together in one compiled call; a robot case alone.
DEFAULT_BATCH = {"rig-step": 16, "rig-sine": 16, "robot-stand": 1, "robot-walk": 1}

_STUDY_KEYS = ("name", "description", "sampling", "cases", "seed", "metrics", "batch",
               "keep_runs")


@dataclass(frozen=True)
class VariedParameter:
    """One varied key and where its values come from.

    Parameters
    ----------
    key : str
        A ``--set`` key (``"friction.static_force"``) or ``"run.<option>"``.
    unit : str
        Unit the values are written and stored in (``""``: a plain number or text).
    distribution : Distribution or None
        For Latin hypercube and Sobol sampling.
    values : tuple or None
        For a grid or a list: numbers [unit], or texts/booleans for a choice.
    integer : bool
        Whether the values were written as plain integers (``substeps``, ``run.seed``):
        their overrides and run options stay integers.
    """

    key: str
    unit: str
    distribution: Distribution | None = None
    values: tuple[Any, ...] | None = None
    integer: bool = False

    @property
    def column(self) -> str:
        """Its column in the results: ``"friction.static_force [lbf]"``."""
        return f"{self.key} [{self.unit}]" if self.unit else self.key

    @property
    def is_number(self) -> bool:
        """Whether its values are numbers (else texts or booleans: a choice)."""
        return self.values is None or all(isinstance(v, float) for v in self.values)

    def spec_value(self, value: Any) -> Any:
        """A case's value as a spec would write it: ``"4.2 lbf"``, 0.75, 3, ``"lugre"``."""
        if isinstance(value, float):
            if self.integer:
                return int(value)
            return f"{value!r} {self.unit}" if self.unit else value
        return value

    def override(self, value: Any) -> str:
        """The case's ``--set`` item: ``friction.static_force="4.2 lbf"``."""
        if isinstance(value, float) and self.integer:
            return f"{self.key}={int(value)}"
        if isinstance(value, float):
            return f"{self.key}={Quantity(value, self.unit).override_text()}"
        if isinstance(value, bool):
            return f"{self.key}={'true' if value else 'false'}"
        return f'{self.key}="{value}"'


@dataclass(frozen=True)
class StudySpec:
    """A checked study (module docstring); ``text`` is the TOML it was read from."""

    name: str
    description: str
    sampling: str
    cases: int
    seed: int
    batch: int
    keep_runs: bool
    run: RunSpec
    varied: tuple[VariedParameter, ...]
    metrics: tuple[str, ...]
    text: str


def load_study(path: str | Path) -> StudySpec:
    """Read and check a study file (:func:`parse_study`).

    Raises
    ------
    ParameterError
        A missing or unreadable file, invalid TOML, or any problem of the spec.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ParameterError([Problem("<file>", str(path), f"could not be read "
                                      f"({error.strerror})")]) from None
    return parse_study(text, str(path))


def _require(table: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in table:
        raise ParameterError([Problem(f"{where}.{key}", MISSING, "this key is required")])
    return table[key]


def _refuse_unknown(table: Mapping[str, Any], known: tuple[str, ...], where: str) -> None:
    for key in table:
        if key not in known:
            close = difflib.get_close_matches(key, known, n=1, cutoff=0.7)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ParameterError([Problem(f"{where}.{key}".lstrip("."), table[key],
                                          f"is not a known key (known: {', '.join(known)})"
                                          f"{hint}")])


def _integer(table: Mapping[str, Any], key: str, default: int | None, low: int, high: int,
             what: str) -> int:
    value = table.get(key, default) if default is not None else _require(table, key, "study")
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ParameterError([Problem(f"study.{key}", value, f"should be {what}")])
    return value


def _run(table: Any, source: str) -> RunSpec:
    if not isinstance(table, dict):
        raise ParameterError([Problem("run", table, "should be a table")], source)
    kind = _require(table, "kind", "run")
    if kind not in RUN_KINDS:
        raise ParameterError([Problem("run.kind", kind,
                                      f"should be one of {', '.join(RUN_KINDS)}")], source)
    default_params, _ = RUN_KINDS[kind]
    params = table.get("params", default_params)
    overrides = table.get("set", [])
    if not isinstance(overrides, list) or not all(isinstance(item, str) for item in overrides):
        raise ParameterError([Problem("run.set", overrides, 'should be a list of "key=value" '
                                      "texts, like --set")], source)
    options = {k: v for k, v in table.items() if k not in ("kind", "params", "set")}
    parse_run_options(kind, options)
    return RunSpec(kind, str(params), tuple(overrides), options)


def _varied(key: str, table: Any, sampling: str) -> VariedParameter:
    where = f'vary."{key}"'
    if not isinstance(table, dict):
        raise ParameterError([Problem(where, table, "should be a table")])
    if sampling in ("grid", "list"):
        _refuse_unknown(table, ("values",), where)
        texts = _require(table, "values", where)
        if not isinstance(texts, list) or not texts:
            raise ParameterError([Problem(f"{where}.values", texts,
                                          "should be a non-empty list")])
        if all((isinstance(t, (int, float)) and not isinstance(t, bool)) or
               (isinstance(t, str) and parse_quantity_or_none(t)) for t in texts):
            quantities = [parse_study_quantity(t, f"{where}.values") for t in texts]
            units = {q.unit for q in quantities}
            if len(units) > 1:
                raise ParameterError([Problem(f"{where}.values", texts, "should write every "
                                              f"value in one unit (found {sorted(units)})")])
            integer = all(isinstance(t, int) and not isinstance(t, bool) for t in texts)
            return VariedParameter(key, units.pop(), None,
                                   tuple(q.number for q in quantities), integer)
        if not all(isinstance(t, (str, bool)) for t in texts):
            raise ParameterError([Problem(f"{where}.values", texts, "should be all quantities"
                                          " (numbers with one unit) or all texts/booleans")])
        return VariedParameter(key, "", None, tuple(texts))
    if "values" in table:
        raise ParameterError([Problem(f"{where}.values", table["values"],
                                      f"needs sampling grid or list (this study samples "
                                      f"{sampling}); give a distribution instead")])
    distribution = parse_distribution(where, table)
    return VariedParameter(key, distribution.unit, distribution, None)


def parse_quantity_or_none(text: str) -> Quantity | None:
    """The quantity of ``text`` if it reads as a number (with or without unit), else None."""
    try:
        return parse_study_quantity(text, "")
    except ParameterError:
        return None


def _metrics(study: Mapping[str, Any], run: RunSpec) -> tuple[str, ...]:
    allowed = RIG_METRICS.get(run.kind)
    names = study.get("metrics", list(allowed) if allowed else MISSING)
    if names is MISSING:
        raise ParameterError([Problem("study.metrics", MISSING, f"is required for a {run.kind}"
                                      " study: summary.json figures, nested ones as "
                                      '"walking.success"')])
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise ParameterError([Problem("study.metrics", names, "should be a non-empty list of "
                                      "summary figure names")])
    for name in names:
        if allowed is not None and name not in allowed:
            close = difflib.get_close_matches(name, allowed, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ParameterError([Problem("study.metrics", name, f"is not a figure of a "
                                          f"{run.kind} summary{hint}")])
    return tuple(names)


def _case_count(study: Mapping[str, Any], sampling: str,
                varied: tuple[VariedParameter, ...]) -> int:
    if sampling in DRAWN:
        cases = _integer(study, "cases", None, 1, MAX_CASES, f"an integer from 1 to {MAX_CASES}")
        if sampling != "latin-hypercube" and cases & (cases - 1):
            raise ParameterError([Problem("study.cases", cases, f"should be a power of two "
                                          f"for {sampling} sampling (its balance holds at "
                                          f"2^m points)")])
        if sampling == "saltelli":  # N base points, each with D + 2 evaluations
            cases *= len(varied) + 2
            if cases > MAX_CASES:
                raise ParameterError([Problem("study.cases", study["cases"], f"makes "
                                              f"{cases} runs; should make at most "
                                              f"{MAX_CASES}")])
        return cases
    counts = [len(v.values or ()) for v in varied]
    count = math.prod(counts) if sampling == "grid" else counts[0]
    if sampling == "list" and len(set(counts)) > 1:
        raise ParameterError([Problem("vary", {v.key: len(v.values or ()) for v in varied},
                                      "should give every key the same number of values "
                                      "for a list study")])
    if "cases" in study and study["cases"] != count:
        raise ParameterError([Problem("study.cases", study["cases"], f"should be left out or "
                                      f"equal the {count} cases of the {sampling}")])
    if count > MAX_CASES:
        raise ParameterError([Problem("vary", count, f"should make at most {MAX_CASES} cases")])
    return count


def _check_against_parameters(run: RunSpec, varied: tuple[VariedParameter, ...]) -> None:
    """Load the base parameters with each varied key at a typical value: unknown keys and
    values of the wrong kind are refused before anything runs."""
    load = load_rig if run.is_rig else load_robot
    load(run.params, run.overrides)
    options = dict(run.options)
    for parameter in varied:
        typical = (parameter.values[0] if parameter.values is not None
                   else float(parameter.distribution.from_unit_interval(0.5)))
        if parameter.key.startswith("run."):
            options[parameter.key[4:]] = parameter.spec_value(typical)
            continue
        try:
            load(run.params, [*run.overrides, parameter.override(typical)])
        except ParameterError as error:
            problems = [Problem(f'vary."{parameter.key}"', p.value, p.expected)
                        if p.key == parameter.key else p for p in error.problems]
            raise ParameterError(problems) from None  # named after the study file
    parsed = parse_run_options(run.kind, options)
    if run.kind == "robot-walk":
        from .case_runs import walk_settings

        walk_settings(parsed)


def parse_study(text: str, source: str = "study") -> StudySpec:
    """Check a study's TOML text (module docstring) into a :class:`StudySpec`.

    Besides its own keys, the base parameters are loaded with every varied key set to a
    typical value (the first value, or the distribution's median), so an unknown key or a
    value of the wrong unit is refused here, naming the key.

    Raises
    ------
    ParameterError
        Naming the key, the value and what was expected; ``source`` in the message.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ParameterError([Problem("<file>", source, f"is not valid TOML: {error}")],
                             source) from None
    try:
        _refuse_unknown(data, ("study", "run", "vary"), "")
        study = _require(data, "study", "<file>")
        _refuse_unknown(study, _STUDY_KEYS, "study")
        run = _run(_require(data, "run", "<file>"), source)
        sampling = study.get("sampling", "latin-hypercube")
        if sampling not in SAMPLINGS:
            raise ParameterError([Problem("study.sampling", sampling,
                                          f"should be one of {', '.join(SAMPLINGS)}")])
        vary = _require(data, "vary", "<file>")
        if not isinstance(vary, dict) or not vary:
            raise ParameterError([Problem("vary", vary, "should hold at least one varied key")])
        varied = tuple(_varied(key, table, sampling) for key, table in vary.items())
        cases = _case_count(study, sampling, varied)
        keep_runs = study.get("keep_runs", False)
        if not isinstance(keep_runs, bool):
            raise ParameterError([Problem("study.keep_runs", keep_runs, "should be true or "
                                          "false")])
        spec = StudySpec(
            name=str(study.get("name", Path(source).stem)),
            description=str(study.get("description", "")),
            sampling=sampling, cases=cases,
            seed=_integer(study, "seed", 0, 0, 2**63 - 1, "an integer >= 0"),
            batch=_integer(study, "batch", DEFAULT_BATCH[run.kind], 1, 4096,
                           "an integer from 1 to 4096"),
            keep_runs=keep_runs, run=run, varied=varied, metrics=_metrics(study, run),
            text=text)
        _check_against_parameters(run, varied)
    except ParameterError as error:
        raise ParameterError(error.problems, error.source or source) from None
    return spec
