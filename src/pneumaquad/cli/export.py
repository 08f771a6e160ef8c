"""``pneumaquad export``: the models for other tools (docs/fmu.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumaquad.cli.common import (
    ParamsOption,
    SetOption,
    command_group,
    console,
    stderr_console,
)

export_app = command_group(help="Export models for other tools: the actuator as an FMI 2.0 "
                           "co-simulation FMU.", no_args_is_help=True)


def fmu_target(output: Path | None, params: str) -> Path:
    """The FMU file to write: ``--output`` (a file, or a folder to write into), or
    ``<set name>.fmu`` in the working folder."""
    name = f"{Path(params).stem}.fmu"
    if output is None:
        return Path(name)
    return output / name if output.is_dir() else output


@export_app.command("fmu")
def export_fmu_command(
    params: ParamsOption = "crr-gamma",
    overrides: SetOption = None,
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="FMU file to write (default: <set name>.fmu here); an "
        "existing folder: the FMU goes into it.")] = None,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Replace the --output file if it exists.")] = False,
) -> None:
    """Export one actuator (valve, cylinder, friction, supply) as an FMI 2.0 co-simulation
    FMU: inputs valve voltage [V], piston position [m] and velocity [m/s]; outputs force [N],
    chamber pressures [Pa] and temperatures [K], mass flows [kg/s], air consumed [kg]; the
    parameter set's values as FMU parameters with their units. It runs in a Python with
    pneumaquad and pythonfmu installed (pip install "pneumaquad[fmu]"); docs/fmu.md."""
    target = fmu_target(output, params)
    if target.exists() and not overwrite:
        raise typer.BadParameter(f"{target} exists; pass --overwrite to replace it, or choose "
                                 "another file", param_hint="--output")
    try:
        import pythonfmu  # noqa: F401  (builds the FMU: an optional dependency)
    except ModuleNotFoundError:
        stderr_console.print("error: exporting an FMU needs pythonfmu: pip install "
                             "'pneumaquad\\[fmu]'", highlight=False)
        raise typer.Exit(2) from None
    from pneumaquad.interop.fmu_export import export_fmu
    from pneumaquad.interop.fmu_model import INPUTS, OUTPUTS

    written = export_fmu(params, target, overrides or [])
    model_name, parameters = described_model(written)
    console.print(f"FMU: [bold]{written}[/bold] ({model_name}, FMI 2.0 co-simulation, "
                  f"{len(INPUTS)} inputs, {len(OUTPUTS)} outputs, {parameters} parameters)",
                  highlight=False)
    console.print("runs in a Python with pneumaquad and pythonfmu installed "
                  "(pip install 'pneumaquad\\[fmu]'); docs/fmu.md", highlight=False)


def described_model(fmu: Path) -> tuple[str, int]:
    """The model name and the number of parameters an FMU's model description declares."""
    import zipfile
    from xml.etree import ElementTree

    with zipfile.ZipFile(fmu) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    parameters = root.findall("ModelVariables/ScalarVariable[@causality='parameter']")
    return root.get("modelName", ""), len(parameters)
