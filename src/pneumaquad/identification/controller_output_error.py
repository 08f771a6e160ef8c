"""PID gains from reference and position alone: output-error identification on the rig.

The rig of a parameter set is simulated in closed loop with candidate gains, following the
recorded reference, and the gains are those that bring the simulated piston position
closest to the recorded one at the recording's instants (``scipy.optimize.least_squares``
on the position residual [m]). The unknowns are the logarithms of Kp, Ki and Kd (and of
the derivative filter time constant τ_d where the data determine it), which keeps them
positive; the Jacobian comes from central differences whose simulations run together in
one compiled loop (`pneumaquad.rig.simulate.simulate_rigs`), as do the start search over
a grid of gain scales and the loop delay search.

The simulation runs at the parameter set's control step T_c. It starts at rest one sample
period before the first row, in the set's initial state or at the first recorded row; a
control step takes the reference of the first row at or after its end (a row's reference
is held over the period before its time stamp, like its command), and the simulated
position is interpolated to the recorded instants. The plant is the parameter set's:
what the fit gives is the controller that makes that model follow the recording, so a
plant that differs (friction, valve) shows in the gains.

Stick-slip makes the residual a rugged function of the gains (a gain that lets the piston
stick once more moves the rest of the run), with local minima a fit from a poor start
falls into. The fit therefore grows its horizon: it starts on the first fifth of each
recording, where it searches the start gains and the delay, then refits on two fifths,
seven tenths and all of it, each from the last one's gains. A delay is searched by
fitting the gains at each delay tried: with gains that are not its own a delay search
is drawn to a wrong one (a slow loop is matched by a longer delay).

Standard errors: ``covariance_from_jacobian`` in the log parameters, times the value.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from pneumaquad.analysis.fits import (
    FitResult,
    check_standard_errors,
    covariance_from_jacobian,
    r_squared,
)
from pneumaquad.params.loader import validated_update
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.simulate import RigDivergedError, simulate_rigs

from .controller_data import (
    FILTER_KEY,
    GAIN_KEYS,
    START_STATES,
    ClosedLoopRecording,
    ControllerFit,
    position_noise,
)
from .preprocess import IdentificationError

__all__ = ["HORIZONS", "START_STATES", "fit_pid_output_error", "simulation_reference"]

#: Relative step of the central differences (in the log parameters) [-].
DIFFERENCE_STEP = 1e-3
#: Scales of the set's gains tried before the fit (each of Kp, Ki, Kd) [-].
START_SCALES = (0.4, 1.0, 2.5)
#: Smallest gains and filter time constant the fit may reach (Kp [V/m], Ki [V/(m s)],
#: Kd [V s/m], τ_d [s]) and the largest (the parameter files' ranges).
LOWER = (1e-2, 1e-3, 1e-4, 1e-4)
UPPER = (1e5, 1e7, 1e4, 0.1)
#: Shares of each recording fitted in turn [-] (the start and delay search on the first).
HORIZONS = (0.2, 0.4, 0.7, 1.0)
#: Residual RMS over the recording's position noise above which the fit says that the
#: plant does not follow the recording [-].
NOISE_RATIO = 3.0
#: Least share of the position's variance the fitted loop must reproduce [-].
MIN_R_SQUARED = 0.95

Progress = Callable[[str], None]
#: Per delay [control steps]: residual sum of squares [m^2] and fitted log parameters.
DelayFits = dict[int, tuple[float, np.ndarray]]


def simulation_reference(recording: ClosedLoopRecording, control_step: float) -> np.ndarray:
    """The recorded reference on the simulation's control steps [m].

    The simulation starts one sample period before the first row; control step j (ending
    at t_0 - T + (j + 1)·T_c) takes the reference of the first row at or after its end.
    """
    start = recording.time[0] - recording.period
    steps = max(1, math.ceil((recording.time[-1] - start) / control_step - 1e-6))
    ends = start + control_step * np.arange(1, steps + 1)
    rows = np.searchsorted(recording.time, ends - 1e-6 * control_step, side="left")
    return recording.reference[np.minimum(rows, recording.samples - 1)]


@dataclass(frozen=True)
class _Candidate:
    """Gains [V/m, V/(m s), V s/m], filter τ_d [s] and delay [control steps] to simulate."""

    gains: tuple[float, float, float]
    tau: float
    delay: int


class _LoopModel:
    """The recordings' closed loops on the rig of a parameter set over a horizon (a share
    of each recording), many candidates per compiled call."""

    def __init__(self, recordings: Sequence[ClosedLoopRecording], setup: RigSetup,
                 start: str) -> None:
        changes: dict[str, object] = {}
        if setup.simulation.integrator != "fixed":
            changes["simulation.integrator"] = "fixed"
        self.recordings = list(recordings)
        self.control_step = setup.simulation.control_step
        self.stroke = setup.actuator.cylinder.stroke
        self.start = start
        self.bases = []
        for recording in recordings:
            update = dict(changes)
            if start == "recording":
                update["rig.initial_position"] = float(np.clip(recording.position[0], 0.0,
                                                               self.stroke))
                if recording.cap_pressure is not None and recording.rod_pressure is not None:
                    update["rig.initial_cap_pressure"] = float(recording.cap_pressure[0])
                    update["rig.initial_rod_pressure"] = float(recording.rod_pressure[0])
            self.bases.append(validated_update(setup, update, source="controller fit start"))
        self.full = [simulation_reference(r, self.control_step) for r in recordings]
        self.simulations = 0
        self.set_horizon(1.0)

    def set_horizon(self, share: float) -> None:
        """Fit the first ``share`` of each recording's duration from now on."""
        self.rows = []
        for recording in self.recordings:
            elapsed = recording.time - recording.time[0]
            self.rows.append(int(np.count_nonzero(elapsed <= share * elapsed[-1] + 1e-9)))
        self.steps = max(
            min(reference.size, math.ceil((r.time[n - 1] - r.time[0] + r.period)
                                          / self.control_step - 1e-6))
            for r, n, reference in zip(self.recordings, self.rows, self.full, strict=True))
        self.references = [np.pad(reference[:self.steps],
                                  (0, max(0, self.steps - reference.size)), mode="edge")
                           for reference in self.full]
        self.observed = np.concatenate(
            [r.position[:n] for r, n in zip(self.recordings, self.rows, strict=True)])

    def residuals(self, candidates: Sequence[_Candidate]) -> np.ndarray:
        """(candidates, samples) simulated minus recorded position [m] over the horizon,
        one compiled run for all candidates and recordings."""
        setups, signals = [], []
        for candidate in candidates:
            kp, ki, kd = candidate.gains
            controller = {
                "controller.proportional_gain": kp,
                "controller.integral_gain": ki,
                "controller.derivative_gain": kd,
                "controller.derivative_filter_time_constant": candidate.tau,
                "controller.measurement_delay": candidate.delay * self.control_step,
            }
            for base, reference in zip(self.bases, self.references, strict=True):
                setups.append(validated_update(base, controller, source="controller fit"))
                signals.append(reference)
        positions = self._simulate(setups, np.array(signals))
        self.simulations += len(setups)
        out = np.empty((len(candidates), self.observed.size))
        count = len(self.recordings)
        for index in range(len(candidates)):
            simulated = [self._at_rows(recording, rows, positions[index * count + i])
                         for i, (recording, rows)
                         in enumerate(zip(self.recordings, self.rows, strict=True))]
            out[index] = np.concatenate(simulated) - self.observed
        return out

    def _simulate(self, setups: list[RigSetup], signals: np.ndarray) -> list[np.ndarray]:
        """Simulated positions per setup; a rig that diverges is run alone and its rows
        from the divergence on count as ten strokes off."""
        try:
            results = simulate_rigs(setups, signals, closed_loop=True, chunk_steps=self.steps)
            return [result.recording["position [m]"] for result in results]
        except RigDivergedError:
            positions = []
            for setup, signal in zip(setups, signals, strict=True):
                try:
                    result = simulate_rigs([setup], signal[None, :], closed_loop=True,
                                           chunk_steps=self.steps)[0]
                    positions.append(result.recording["position [m]"])
                except RigDivergedError as error:
                    kept = error.result.recording["position [m]"]
                    positions.append(np.concatenate(
                        [kept, np.full(self.steps - kept.size, 10.0 * self.stroke)]))
            return positions

    def _at_rows(self, recording: ClosedLoopRecording, rows: int,
                 position: np.ndarray) -> np.ndarray:
        start = recording.time[0] - recording.period
        times = start + self.control_step * np.arange(1, position.size + 1)
        return np.interp(recording.time[:rows], times, position)


def _candidate(x: np.ndarray, tau: float | None, delay: int) -> _Candidate:
    values = np.exp(x)
    return _Candidate((float(values[0]), float(values[1]), float(values[2])),
                      float(values[3]) if tau is None else tau, delay)


def _fit_gains(model: _LoopModel, start: np.ndarray, tau: float | None, delay: int,
               final: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Least squares in the log parameters at a fixed delay; ``tau`` None fits τ_d (the
    fourth unknown). Returns (x, residuals, Jacobian at x, or None unless ``final``)."""
    unknowns = start.size
    lower = np.log(LOWER[:unknowns])
    upper = np.log(UPPER[:unknowns])
    start = np.clip(start, lower + 1e-9, upper - 1e-9)
    cache: dict[bytes, np.ndarray] = {}

    def residual(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in cache:
            cache[key] = model.residuals([_candidate(x, tau, delay)])[0]
        return cache[key]

    def jacobian(x: np.ndarray) -> np.ndarray:
        shifted = []
        for i in range(unknowns):
            for sign in (1.0, -1.0):
                y = x.copy()
                y[i] += sign * DIFFERENCE_STEP
                shifted.append(_candidate(y, tau, delay))
        rows = model.residuals(shifted)
        return ((rows[0::2] - rows[1::2]) / (2.0 * DIFFERENCE_STEP)).T

    solution = optimize.least_squares(residual, start, jac=jacobian, bounds=(lower, upper),
                                      method="trf", x_scale=1.0, xtol=1e-9, ftol=1e-10,
                                      gtol=1e-10, max_nfev=100 if final else 30)
    return solution.x, residual(solution.x), jacobian(solution.x) if final else None


def _coarse_delays(delays: Sequence[int]) -> list[int]:
    """The delays [control steps] fitted first: the ends and about eight between them,
    closer together at short delays."""
    low, high = delays[0], delays[-1]
    if high - low <= 8:
        return list(range(low, high + 1))
    inner = np.geomspace(1.0, high - low, 8)
    return sorted({low, high, *(low + round(float(v)) for v in inner)})


def _search_delay(model: _LoopModel, setup: RigSetup, tau: float, delays: Sequence[int],
                  say: Progress) -> tuple[int, DelayFits]:
    """The delay [control steps] whose fitted gains fit best over the model's horizon.

    The gains are fitted at `_coarse_delays` in increasing order, then at the midpoints
    of the gaps beside the best until its neighbours are one step away; each fit starts
    from the better of two: the gains of the delay fitted last, and the best start gains
    at this delay (`_start`). Returns the best delay and the fits.
    """
    fits: DelayFits = {}

    def fit(delay: int, previous: np.ndarray | None) -> None:
        starts = [_start(model, setup, tau, delay)[0]]
        if previous is not None:
            starts.append(previous)
        for x in starts:
            x, residual, _ = _fit_gains(model, x, tau, delay, final=False)
            cost = float(residual @ residual)
            if delay not in fits or cost < fits[delay][0]:
                fits[delay] = (cost, x)
        say(f"{model.start} state, delay {delay * model.control_step * 1e3:g} ms: residual "
            f"RMS {math.sqrt(fits[delay][0] / model.observed.size) * 1e6:.3g} um")

    previous = None
    for delay in _coarse_delays(delays):
        fit(delay, previous)
        previous = fits[delay][1]
    while True:
        best = min(fits, key=lambda d: fits[d][0])
        below = max((d for d in fits if d < best), default=None)
        above = min((d for d in fits if d > best), default=None)
        todo = [(best + other) // 2 if other < best else (best + other + 1) // 2
                for other in (below, above) if other is not None and abs(other - best) > 1]
        if not todo:
            return best, fits
        for delay in todo:
            fit(delay, fits[best][1])


def _start(model: _LoopModel, setup: RigSetup, tau: float,
           delay: int) -> tuple[np.ndarray, float]:
    """Log start gains: the best of the set's gains scaled by `START_SCALES` each over the
    model's horizon, and its residual sum of squares [m^2]."""
    controller = setup.controller
    base = np.array([max(controller.proportional_gain, 10 * LOWER[0]),
                     max(controller.integral_gain, 10 * LOWER[1]),
                     max(controller.derivative_gain, 10 * LOWER[2])])
    scales = np.array(np.meshgrid(START_SCALES, START_SCALES, START_SCALES)).T.reshape(-1, 3)
    grid = [np.log(base * row) for row in scales]
    rows = model.residuals([_candidate(x, tau, delay) for x in grid])
    costs = np.einsum("ij,ij->i", rows, rows)
    best = int(np.argmin(costs))
    return grid[best], float(costs[best])


def fit_pid_output_error(
    recordings: Sequence[ClosedLoopRecording],
    setup: RigSetup,
    *,
    fit_filter: bool = True,
    delay: float | None = None,
    max_delay: float = 0.05,
    start: str = "auto",
    progress: Progress | None = None,
) -> ControllerFit:
    """Identify the PID by re-simulating the closed loop (the output-error method).

    Parameters
    ----------
    recordings : sequence of ClosedLoopRecording
        Reference and position (a command, if any, is not used).
    setup : RigSetup
        The plant (and the start values of the gains); its integrator is taken as
        ``"fixed"``.
    fit_filter : bool
        Fit the derivative filter time constant (held at the set's value where the data
        do not determine it); False holds it.
    delay : float, optional
        Measurement delay [s] to assume; None searches 0 … ``max_delay`` in control steps.
    max_delay : float
        Longest delay searched [s].
    start : {"auto", "parameters", "recording"}
        The simulation's start state: the set's ``rig.initial_*`` state (the simulator's
        own runs start there), at rest at the first recorded position (and pressures
        where recorded), or whichever of the two fits the first horizon better with the
        start gains.
    progress : callable, optional
        Called with a line on each stage.

    Returns
    -------
    ControllerFit

    Raises
    ------
    IdentificationError
        An unknown ``start``.
    """
    say = progress or (lambda _line: None)
    if start not in START_STATES:
        raise IdentificationError(f"start {start!r}: expected one of {', '.join(START_STATES)}")
    control_step = setup.simulation.control_step
    tau_held = setup.controller.derivative_filter_time_constant
    delays = (list(range(round(max_delay / control_step) + 1)) if delay is None
              else [round(delay / control_step)])
    states = ("parameters", "recording") if start == "auto" else (start,)
    searches = [_first_horizon(_LoopModel(recordings, setup, state), setup, tau_held, delays,
                               say) for state in states]
    current, fits, model = min(searches, key=lambda item: item[1][item[0]][0])
    x = fits[current][1]
    say(f"start: the {model.start} state, delay {current * control_step * 1e3:g} ms")
    for share in HORIZONS[1:]:
        model.set_horizon(share)
        x, _, _ = _fit_gains(model, x, tau_held, current, final=False)
        say(f"{share:.0%} of the recording: gains " + ", ".join(f"{v:.4g}" for v in np.exp(x)))
    if len(delays) > 1:
        current, x = _confirm_delay(model, x, tau_held, current, delays)
    notes: list[str] = []
    tau: float | None = None if fit_filter else tau_held
    if tau is None:
        x = np.append(x, math.log(min(max(tau_held, LOWER[3]), UPPER[3])))
    x, residual, jacobian = _fit_gains(model, x, tau, current)
    covariance = covariance_from_jacobian(jacobian, residual)
    if tau is None:
        value, error = math.exp(x[3]), math.exp(x[3]) * math.sqrt(abs(covariance[3, 3]))
        inside = LOWER[3] * (1.0 + 1e-6) < value < UPPER[3] * (1.0 - 1e-6)
        if not (inside and math.isfinite(error) and error <= 0.25 * max(value, control_step)):
            notes.append(
                f"the data do not determine the derivative filter (τ_d = {value * 1e3:.3g} ± "
                f"{error * 1e3:.2g} ms): held at the parameter set's {tau_held * 1e3:.3g} ms")
            tau = tau_held
            x, residual, jacobian = _fit_gains(model, x[:3], tau, current)
            covariance = covariance_from_jacobian(jacobian, residual)
    fit = _result(x, residual, covariance, model, tau is None)
    plant = _plant_note(fit, recordings)
    if plant:
        notes.append(plant)
    if not math.isclose(recordings[0].period, control_step, rel_tol=1e-3):
        notes.append(
            f"the recording's sample period {recordings[0].period * 1e3:.4g} ms differs from "
            f"the control step {control_step * 1e3:.4g} ms: the loop is simulated at the "
            "control step and compared at the recorded instants")
    return ControllerFit(
        fit=fit, method="output error",
        filter_time_constant=float(math.exp(x[3]) if tau is None else tau),
        filter_fitted=tau is None, measurement_delay=current * control_step,
        delay_fitted=delay is None, lag=(1 + current) * control_step,
        sample_period=recordings[0].period, control_step=control_step, notes=tuple(notes),
        details={f"residual per delay, first {HORIZONS[0]:.0%} [m^2]": {
                     f"{d * control_step * 1e3:g} ms": c for d, (c, _) in sorted(fits.items())},
                 "start": model.start,
                 "simulations": sum(item[2].simulations for item in searches)})


def _first_horizon(model: _LoopModel, setup: RigSetup, tau: float, delays: Sequence[int],
                   say: Progress) -> tuple[int, DelayFits, _LoopModel]:
    """The best delay and the gains fitted at each delay tried, on the first horizon."""
    model.set_horizon(HORIZONS[0])
    if len(delays) > 1:
        best, fits = _search_delay(model, setup, tau, delays, say)
        return best, fits, model
    delay = delays[0]
    x, residual, _ = _fit_gains(model, _start(model, setup, tau, delay)[0], tau, delay,
                                final=False)
    return delay, {delay: (float(residual @ residual), x)}, model


def _plant_note(fit: FitResult, recordings: Sequence[ClosedLoopRecording]) -> str:
    """A sentence when the residual is more than `NOISE_RATIO` times the recording's
    position noise (`position_noise`): the plant does not follow the recording; else
    empty."""
    noise = position_noise(recordings)
    if fit.residual_rms <= NOISE_RATIO * noise + 1e-6:
        return ""
    if noise == 0.0:
        return (f"the residual RMS is {fit.residual_rms * 1e6:.3g} um on a noise-free "
                "recording: the parameter set's rig does not follow it exactly")
    return (f"the residual RMS {fit.residual_rms * 1e6:.3g} um is "
            f"{fit.residual_rms / noise:.3g} times the position noise estimated from the "
            f"recording ({noise * 1e6:.3g} um): the parameter set's rig does not follow the "
            "recording as closely as its noise allows, and the gains make up for the "
            "difference of the plants (check its friction and valve against the rig's)")


def _confirm_delay(model: _LoopModel, x: np.ndarray, tau: float, delay: int,
                   delays: Sequence[int]) -> tuple[int, np.ndarray]:
    """The delay next to ``delay`` whose fitted gains fit the whole horizon better, as
    long as one does (the first horizon may not have told neighbours apart)."""
    _, residual, _ = _fit_gains(model, x, tau, delay, final=False)
    cost = float(residual @ residual)
    while True:
        moved = False
        for neighbour in (delay - 1, delay + 1):
            if neighbour not in delays:
                continue
            y, residual, _ = _fit_gains(model, x, tau, neighbour, final=False)
            if float(residual @ residual) < cost:
                cost, x, delay, moved = float(residual @ residual), y, neighbour, True
                break
        if not moved:
            return delay, x


def _result(x: np.ndarray, residual: np.ndarray, covariance: np.ndarray, model: _LoopModel,
            with_filter: bool) -> FitResult:
    """The fit with standard errors (delta method from the log parameters) and checks."""
    values = np.exp(x)
    errors = values * np.sqrt(np.abs(np.diag(covariance)))
    keys = list(GAIN_KEYS) + ([FILTER_KEY] if with_filter else [])
    gains = FitResult(
        name="PID by output error",
        parameters={key: float(values[i]) for i, key in enumerate(GAIN_KEYS)},
        standard_errors={key: float(errors[i]) for i, key in enumerate(GAIN_KEYS)},
        r_squared=r_squared(residual, model.observed),
        residual_rms=float(np.sqrt(np.mean(residual**2))),
        n_points=int(residual.size),
        residual_unit="m",
    )
    problems = list(check_standard_errors(gains).problems)
    for i, key in enumerate(GAIN_KEYS):
        if x[i] <= math.log(LOWER[i]) + 1e-6 or x[i] >= math.log(UPPER[i]) - 1e-6:
            problems.append(f"{gains.name}: {key} = {values[i]:.4g} is at the search bound")
    if not gains.r_squared >= MIN_R_SQUARED:
        problems.append(
            f"{gains.name}: the simulated loop reproduces {gains.r_squared:.1%} of the "
            f"position's variance (less than {MIN_R_SQUARED:.0%}): the parameter set's rig "
            "does not behave like the recorded one")
    return FitResult(
        name=gains.name,
        parameters={key: float(values[i]) for i, key in enumerate(keys)},
        standard_errors={key: float(errors[i]) for i, key in enumerate(keys)},
        r_squared=gains.r_squared, residual_rms=gains.residual_rms,
        n_points=gains.n_points, residual_unit="m", problems=tuple(problems))
