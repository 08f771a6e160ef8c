"""``pneumaquad console`` as a command: serves for a while, then stops cleanly."""

from __future__ import annotations

import pytest
import typer
from typer.testing import CliRunner

pytest.importorskip("viser")

from pneumaquad.cli.console import console_command


def test_console_command_serves_on_loopback_and_stops() -> None:
    app = typer.Typer()
    app.command("console")(console_command)
    app.command("other")(lambda: None)  # a group, as in the real CLI
    result = CliRunner().invoke(
        app, ["console", "--port", "0", "--duration", "1", "--configuration", "fixed"]
    )
    assert result.exit_code == 0, result.output
    assert "Operator console on http://localhost:" in result.output
    assert "Console stopped." in result.output
    assert "warning" not in result.output
