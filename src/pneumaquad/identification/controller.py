"""Controller identification from closed-loop recordings: the PID's gains, its derivative
filter and a loop delay, by one of two methods.

* ``"command"``: where the recordings hold the valve command, the PID is fitted to it
  directly (`pneumaquad.identification.controller_command`): linear least squares in
  the gains, a search over the filter time constant and the lag. It needs no model of
  the plant.
* ``"output-error"``: with reference and position only, the rig of the parameter set is
  simulated in closed loop and the gains are fitted to the position
  (`pneumaquad.identification.controller_output_error`). It is only as good as the
  plant model.

``"auto"`` takes the first where every recording has a command, else the second.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from pneumaquad.params.schema import MAX_MEASUREMENT_DELAY, RigSetup

from .controller_command import fit_pid_from_command
from .controller_data import (
    METHODS,
    START_STATES,
    ClosedLoopRecording,
    ControllerFit,
    closed_loop_recording,
)
from .controller_output_error import Progress, fit_pid_output_error
from .preprocess import IdentificationError

__all__ = ["METHODS", "fit_controller"]


def fit_controller(
    recordings: Sequence[Mapping[str, np.ndarray]],
    setup: RigSetup,
    *,
    method: str = "auto",
    fit_filter: bool = True,
    delay: float | None = None,
    max_delay: float = 0.05,
    fit_offset: bool = False,
    start: str = "auto",
    labels: Sequence[str] | None = None,
    progress: Progress | None = None,
) -> ControllerFit:
    """Identify the rig's PID from closed-loop recordings.

    Parameters
    ----------
    recordings : sequence of mapping
        Recordings (columns ``"quantity [unit]"``, SI) with time, reference position and
        position, and for the ``"command"`` method the valve command; any uniform rate.
    setup : RigSetup
        The parameter set: valve offset and limits, integral clamp, controller period
        (``simulation.control_step``), the filter time constant held where the data do
        not determine one, and for ``"output-error"`` the plant and the start gains.
    method : {"auto", "command", "output-error"}
        See the module.
    fit_filter : bool
        Fit the derivative filter time constant where the data determine it.
    delay : float, optional
        Measurement delay [s] to assume; None searches 0 … ``max_delay``.
    max_delay : float
        Longest delay searched [s], at most 0.1 s.
    fit_offset : bool
        ``"command"`` method: fit the valve offset instead of taking the set's.
    start : {"auto", "parameters", "recording"}
        ``"output-error"`` method: the simulation's start state.
    labels : sequence of str, optional
        Names of the recordings in messages (their files).
    progress : callable, optional
        ``"output-error"`` method: called with a line on each stage.

    Returns
    -------
    ControllerFit

    Raises
    ------
    IdentificationError
        Unusable recordings (`closed_loop_recording`), an unknown method or start, the
        ``"command"`` method without a command, a delay outside [0, 0.1 s].
    """
    if method not in METHODS:
        raise IdentificationError(f"method {method!r}: expected one of {', '.join(METHODS)}")
    if start not in START_STATES:
        raise IdentificationError(f"start {start!r}: expected one of {', '.join(START_STATES)}")
    for name, value in (("delay", delay), ("max_delay", max_delay)):
        if value is not None and not 0.0 <= value <= MAX_MEASUREMENT_DELAY:
            raise IdentificationError(
                f"{name} {value:g} s: expected 0 to {MAX_MEASUREMENT_DELAY:g} s")
    if not recordings:
        raise IdentificationError("no recording to fit")
    names = list(labels) if labels is not None else [
        f"recording {i + 1}" for i in range(len(recordings))]
    loops: list[ClosedLoopRecording] = [
        closed_loop_recording(recording, name)
        for recording, name in zip(recordings, names, strict=True)]
    with_command = all(loop.command is not None for loop in loops)
    if method == "command" and not with_command:
        lacking = [name for name, loop in zip(names, loops, strict=True) if loop.command is None]
        raise IdentificationError(
            f"the command method needs the valve command ('command [V]'), which "
            f"{', '.join(lacking)} lack(s); use the output-error method")
    if method == "command" or (method == "auto" and with_command):
        return fit_pid_from_command(loops, setup, fit_filter=fit_filter, delay=delay,
                                    max_delay=max_delay, fit_offset=fit_offset)
    return fit_pid_output_error(loops, setup, fit_filter=fit_filter, delay=delay,
                                max_delay=max_delay, start=start, progress=progress)
