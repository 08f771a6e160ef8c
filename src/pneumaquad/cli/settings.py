"""Command-line options built from a settings dataclass and its described fields.

:func:`settings_options` gives a command one option per field described in a table of
:class:`pneumaquad.params.settings.Setting` (name, help text, range, unit scale), with the
dataclass's default, and calls the command with the settings object built from them. The
defaults, ranges and help texts are therefore those of the library; nothing is repeated
here. A number option is checked against its range before the command runs (exit status
2, the message names the option, the value and the range); a bool field becomes a
``--name/--no-name`` switch; a field holding another settings object or None becomes a
switch plus that object's described fields.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any, TypeVar

import typer

from pneumaquad.cli.common import number_in, option_range
from pneumaquad.params.settings import Setting

__all__ = ["option_names", "settings_options"]

Command = TypeVar("Command", bound=Callable[..., Any])


@dataclass(frozen=True)
class _Option:
    """One generated option: its parameter and where its value goes."""

    parameter: inspect.Parameter
    field: str
    setting: Setting
    nested: tuple[type, list[_Option]] | None = None


def _identifier(name: str, setting: Setting) -> str:
    return (setting.option or name).replace("-", "_")


def _flag(name: str, setting: Setting) -> str:
    return "--" + _identifier(name, setting).replace("_", "-")


def option_names(described: Mapping[str, Setting], fields: tuple[str, ...]) -> str:
    """The options of ``fields`` for a message: ``"--duty-factor, --lift-fraction or
    --margin"`` (nested fields are looked up in their parents' tables too)."""
    flags = {}
    for name, setting in described.items():
        flags[name] = _flag(name, setting)
        flags.update({inner: _flag(inner, nested) for inner, nested in setting.nested.items()})
    shown = [flags.get(name, name) for name in fields]
    return shown[0] if len(shown) == 1 else f"{', '.join(shown[:-1])} or {shown[-1]}"


def _default(item: dataclasses.Field) -> Any:
    if item.default is not dataclasses.MISSING:
        return item.default
    if item.default_factory is not dataclasses.MISSING:
        return item.default_factory()
    raise TypeError(f"settings field {item.name!r} has no default to offer as an option's")


def _settings_class(annotation: Any) -> type:
    """The dataclass in an ``X | None`` annotation."""
    for candidate in typing.get_args(annotation):
        if dataclasses.is_dataclass(candidate):
            return candidate
    raise TypeError(f"{annotation!r} holds no settings dataclass")


def _switch(name: str, setting: Setting, default: bool) -> inspect.Parameter:
    identifier = _identifier(name, setting)
    on = _flag(name, setting)
    off = "--" + (setting.off_option or f"no-{on.removeprefix('--')}")
    annotation = Annotated[bool, typer.Option(f"{on}/{off}", help=setting.help + ".")]
    return inspect.Parameter(identifier, inspect.Parameter.KEYWORD_ONLY, default=default,
                             annotation=annotation)


def _options(settings_type: type, described: Mapping[str, Setting],
             defaults_from: Any = None) -> list[_Option]:
    """The options of the described fields of ``settings_type`` (defaults from the
    dataclass, or from the object ``defaults_from``)."""
    fields = {item.name: item for item in dataclasses.fields(settings_type)}
    hints = typing.get_type_hints(settings_type)
    options = []
    for name, setting in described.items():
        default = (_default(fields[name]) if defaults_from is None
                   else getattr(defaults_from, name))
        if setting.nested:
            inner = _settings_class(hints[name])
            parameter = _switch(name, setting, default is not None)
            nested = _options(inner, setting.nested, default if default is not None
                              else inner())
            options.append(_Option(parameter, name, setting, (inner, nested)))
            options += nested
            continue
        if hints[name] is bool:
            options.append(_Option(_switch(name, setting, default), name, setting))
            continue
        help_text = setting.help
        callback = None
        units: dict[str, Any] = {}
        if setting.bounds is not None:
            help_text += f", {setting.bounds.expectation}"
            callback = option_range(setting.bounds)
            if setting.bounds.unit:  # "0.2" or "20 cm" alike
                units = {"parser": number_in(setting.bounds.unit), "metavar": "QUANTITY"}
        annotation = Annotated[hints[name], typer.Option(help=help_text + ".",
                                                         callback=callback, **units)]
        shown = default / setting.scale if setting.scale != 1.0 else default
        parameter = inspect.Parameter(_identifier(name, setting),
                                      inspect.Parameter.KEYWORD_ONLY, default=shown,
                                      annotation=annotation)
        options.append(_Option(parameter, name, setting))
    return options


def _build(settings_type: type, options: list[_Option], values: dict[str, Any]) -> Any:
    """The settings object from the option values of ``options`` (popped from ``values``)."""
    arguments = {}
    nested_names = {o.parameter.name for option in options if option.nested
                    for o in option.nested[1]}
    for option in options:
        if option.parameter.name in nested_names:
            continue  # built with its parent
        value = values.pop(option.parameter.name)
        if option.nested is not None:
            inner, nested = option.nested
            built = _build(inner, nested, values)
            arguments[option.field] = built if value else None
        elif option.setting.scale != 1.0:
            arguments[option.field] = value * option.setting.scale
        else:
            arguments[option.field] = value
    return settings_type(**arguments)


def settings_options(settings_type: type, described: Mapping[str, Setting],
                     parameter: str = "settings") -> Callable[[Command], Command]:
    """Decorator: replace the command's ``parameter`` by one option per described field.

    Parameters
    ----------
    settings_type : type
        The settings dataclass (its defaults become the options' defaults).
    described : mapping of str to Setting
        The fields to offer, in the order of ``--help``.
    parameter : str
        The command's parameter that receives the built settings object.
    """
    options = _options(settings_type, described)

    def decorate(command: Command) -> Command:
        signature = inspect.signature(command, eval_str=True)
        rest = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY)
                for p in signature.parameters.values() if p.name != parameter]

        @functools.wraps(command)
        def wrapper(**values: Any) -> Any:
            settings = _build(settings_type, options, values)
            return command(**{parameter: settings}, **values)

        parameters = [option.parameter for option in options] + rest
        wrapper.__signature__ = signature.replace(parameters=parameters)  # type: ignore[attr-defined]
        wrapper.__annotations__ = {p.name: p.annotation for p in parameters}
        wrapper.__annotations__["return"] = signature.return_annotation
        return typing.cast(Command, wrapper)

    return decorate
