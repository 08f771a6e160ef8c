"""The thesis's published closed-loop results, reproduced and compared (thesis 4.3, 5.5).

* :mod:`~pneumaquad.validation.published`: the figures the thesis prints, their sources
  and the targets read from them;
* :mod:`~pneumaquad.validation.rig_loop` and :mod:`~pneumaquad.validation.leg_loop`: the
  protocols that measure them on the rig and on the front-right leg;
* :mod:`~pneumaquad.validation.calibration`: the thesis controller set, PID gains
  calibrated to those figures (``thesis-rig-thesis-pid``, ``crr-quadruped-thesis-pid``);
* :mod:`~pneumaquad.validation.comparison` and
  :mod:`~pneumaquad.validation.comparison_page`: ``pneumaquad report --thesis-comparison``,
  which writes docs/thesis-comparison.md.
"""
