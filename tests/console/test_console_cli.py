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


def test_a_non_loopback_bind_needs_allow_remote() -> None:
    from typer.testing import CliRunner

    from pneumaquad.cli.main import app

    runner = CliRunner()
    for command in (["console", "--host", "0.0.0.0", "--duration", "1"],
                    ["serve", "dynamics", "--bind", "192.168.1.7", "--duration", "1"]):
        refused = runner.invoke(app, command)
        assert refused.exit_code == 2, refused.output
        assert "--allow-remote" in " ".join(refused.output.split())
    for host in ("127.0.0.1", "localhost", "::1", "127.0.0.2"):
        from pneumaquad.cli.common import check_bind

        check_bind(host, allow_remote=False, option="--host")  # loopback: accepted
