"""Short rig and robot run folders shared by the report tests (built once per session)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from pneumaquad.demo.reports import write_lab_style_csv
from pneumaquad.params import load_rig, load_robot
from pneumaquad.reporting.rig_experiment import run_rig_experiment
from pneumaquad.rig import signals

INCH = 0.0254
PSI = 6894.757293168361
#: Description with markup characters: the report must show it escaped.
RIG_DESCRIPTION = 'step train <b>bold</b> & "quoted"'
#: Levels [m] and dwell [s] of the closed-loop step train (two steps, 2.1 s).
LEVELS = (0.4 * INCH, 1.4 * INCH, 0.8 * INCH)
DWELL = 0.7


@pytest.fixture(scope="session")
def rig_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2.1 s closed-loop step train of the thesis rig."""
    folder = tmp_path_factory.mktemp("runs") / "rig-steps"
    setup = load_rig("thesis-rig")
    reference = signals.step_train(LEVELS, DWELL, setup.simulation.control_step)
    run_rig_experiment(setup, folder, reference, True, RIG_DESCRIPTION)
    return folder


@pytest.fixture(scope="session")
def robot_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Front-right gamma following the fast sine for 0.5 s after a 0.2 s settle."""
    from pneumaquad.reporting.robot_plots import plot_joints
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.experiment import run_phases
    from pneumaquad.robot.scenarios import leg_validation_phases
    from pneumaquad.robot.simulation import RobotSimulation

    folder = tmp_path_factory.mktemp("runs") / "leg-gamma"
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    phases = leg_validation_phases(simulation, "gamma", "fast-sine", settle=0.2)
    phases[-1].duration = 0.5
    run = run_phases(simulation, phases, folder, "front-right gamma: fast-sine (short)")
    plot_joints(run.recording, ["front_right_gamma"], folder / "joints.png")
    return folder


def write_measured_csv(
    recording: dict[str, np.ndarray],
    folder: Path,
    shift: float = 0.0,
    atmosphere: float = 101325.0,
) -> tuple[Path, Path]:
    """Write a recording as lab-style CSV (ms, in, psig) plus its TOML mapping, no noise.

    ``shift`` [s] delays the 'measured' signals: measured(t) = simulated(t - shift).
    """
    return write_lab_style_csv(recording, folder, shift, position_noise=0.0,
                               pressure_noise=0.0, name="measured", atmosphere=atmosphere)


#: Units of the other system, as a report would write them: in parentheses (axis
#: labels), in brackets (keys) or alone in a table cell.
_UNIT = r"(?:(?<=\()|(?<=\[)|(?<=<td>)|(?<= ))({})(?=\)|\]|</td>|,| \()"
FOREIGN = {
    "si": re.compile(_UNIT.format("psia|psig|psi|lbf|in|in/s|in²|0.001 in|0.001 in²|V/in|"
                                  "V/\\(in s\\)|V s/in|lbf s/in|s/in|V/lbf|NL/in")),
    "us": re.compile(_UNIT.format("m|mm|µm|Pa|kPa|kPa abs|kPa gauge|N|m/s|mm/s|m²|mm²|V/m|"
                                  "V/\\(m s\\)|V s/m|N s/m|s/m|N/m|V/N|NL/m")),
}
#: What a report in each system must show (its own units are used at all).
OWN = {"si": ("kPa abs",), "us": ("psia",)}


def figure_texts(figure: Figure) -> list[str]:
    """Every label, title and legend entry of a figure (and of its secondary axes)."""
    texts = [figure._suptitle.get_text()] if figure._suptitle is not None else []
    axes = list(figure.axes)
    axes += [child for axis in figure.axes for child in axis.child_axes]
    for axis in axes:
        texts += [axis.get_xlabel(), axis.get_ylabel(), axis.title.get_text()]
        legend = axis.get_legend()
        if legend is not None:
            texts += [text.get_text() for text in legend.get_texts()]
    return [text for text in texts if text]


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[Figure]]:
    """The figures saved while the test runs (kept to look at)."""
    figures: list[Figure] = []
    original = Figure.savefig

    def savefig(self: Figure, *args, **kwargs):
        figures.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    yield figures


def page_text(report: Path) -> str:
    """report.html without its embedded images, and every Markdown file beside it."""
    text = re.sub(r"data:image/[a-z]+;base64,[A-Za-z0-9+/=]+", "",
                  report.read_text(encoding="utf-8"))
    return text + "".join(p.read_text(encoding="utf-8") for p in report.parent.glob("*.md"))


def assert_only_units(system: str, texts: list[str], where: str) -> None:
    """``texts`` (figure labels, a page) show units of ``system`` ("si", "us") only, and
    show its absolute pressure unit."""
    joined = "\n".join(texts)
    foreign = sorted({joined[max(0, m.start() - 30):m.end() + 5]
                      for m in FOREIGN[system].finditer(joined)})
    assert not foreign, f"{where} of a {system} report shows {foreign}"
    for unit in OWN[system]:
        assert re.search(_UNIT.format(re.escape(unit)), joined), (
            f"{where} of a {system} report has no {unit}")
