"""Every command's help keeps its bracketed units (``[s]``, ``[m/s]``): help texts are plain
text, not Rich markup, which would swallow them."""

from __future__ import annotations

import re

import pytest
import typer
from typer.testing import CliRunner

from pneumaquad.cli.common import name_placeholders
from pneumaquad.cli.main import app

GROUP = typer.main.get_command(app)


def _commands(group, path: tuple[str, ...] = ()):
    for name, command in group.commands.items():
        if hasattr(command, "commands"):  # a group (typer's own click)
            yield from _commands(command, (*path, name))
        else:
            yield (*path, name), command


COMMANDS = list(_commands(GROUP))


def test_every_command_is_found():
    names = {" ".join(path) for path, _ in COMMANDS}
    assert {"rig step", "robot walk", "robot stand", "params show", "serve dynamics"} <= names


@pytest.mark.parametrize(("path", "command"), COMMANDS,
                         ids=[" ".join(path) for path, _ in COMMANDS])
def test_bracketed_units_survive_in_the_help(path, command):
    bracketed = [(param.name, found) for param in command.params
                 for found in re.findall(r"\[[^\]]+\]", getattr(param, "help", None) or "")]
    bracketed += [("<command>", found)
                  for found in re.findall(r"\[[^\]]+\]", command.help or "")]
    shown = CliRunner().invoke(app, [*path, "--help"], terminal_width=200)
    assert shown.exit_code == 0, shown.output
    text = " ".join(shown.output.split())
    for name, unit in bracketed:
        assert unit in text, f"{' '.join(path)} {name}: {unit} lost from the help"


#: The command the entry point runs: placeholders named (pneumaquad.cli.main.main).
NAMED = name_placeholders(typer.main.get_command(app))


@pytest.mark.parametrize("path", [path for path, _ in _commands(NAMED)],
                         ids=[" ".join(path) for path, _ in _commands(NAMED)])
def test_help_placeholders_say_what_to_type(path, capsys):
    """No Python type in the help (``<str>``, ``<list[Path]>``): options show SET,
    KEY=VALUE, QUANTITY, NUMBER, PATH..., arguments their name in capitals."""
    with pytest.raises(SystemExit) as ended:
        NAMED.main(args=[*path, "--help"], prog_name="pneumaquad", standalone_mode=True)
    assert ended.value.code == 0
    text = capsys.readouterr().out
    assert "Usage: pneumaquad" in text
    python_types = re.findall(r"<(?:str|float|int|bool|path|Path|list\[[^\]]*\])>", text)
    assert python_types == [], f"{' '.join(path)}: {python_types}"


@pytest.mark.parametrize(("path", "command"), COMMANDS,
                         ids=[" ".join(path) for path, _ in COMMANDS])
def test_every_option_and_argument_says_what_it_is(path, command):
    """``video --fps/--width/--height`` had no description once: every parameter has one."""
    silent = [param.name for param in command.params
              if param.name != "help" and not (getattr(param, "help", None) or "").strip()]
    assert silent == [], f"{' '.join(path)}: no help for {silent}"
