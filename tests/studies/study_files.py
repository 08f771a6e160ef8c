"""Study files of the study tests: short rig steps, so a case takes milliseconds."""

from __future__ import annotations

from pathlib import Path

#: An 8-case Latin hypercube of the rig's friction: short open-loop steps.
FRICTION_STUDY = """
[study]
name = "friction-8"
sampling = "latin-hypercube"
cases = 8
seed = 11
batch = 3
metrics = ["rise time 10-90 % [s]", "motion onset delay [s]", "stiction peak force [N]",
           "air consumed [NL]"]

[run]
kind = "rig-step"
voltage = "6.5 V"
step_time = "0.3 s"
duration = "0.8 s"

[vary."friction.static_force"]
distribution = "uniform"
low = "3.5 lbf"
high = "5.0 lbf"

[vary."rig.load_mass"]
distribution = "quartiles"
quartiles = ["0.1 kg", "0.15 kg", "0.2 kg", "0.3 kg", "0.5 kg"]
"""


def write_study(folder: Path, text: str = FRICTION_STUDY) -> Path:
    """A study file in ``folder`` (the 8-case friction study by default)."""
    path = folder / "friction.toml"
    path.write_text(text, encoding="utf-8")
    return path
