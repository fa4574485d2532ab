"""The CLI's help in the conventions of Typer's and click's own apps: `-h` beside `--help`;
arguments written SCENARIO (required), [SCENARIO] (optional), RUN_DIRS... (several); a value's
type as PATH, TEXT, INTEGER, FLOAT (a repeatable option: its element's type); no type beside a
flag (--quick/--no-quick takes no value).

`conventional(app)` makes every command of a Typer app (those added later included) use them.

A path, text or flag given on the command line is taken as it is (`Path(value)`, the text, the
bool) without the Pydantic adapter Typer >= 0.2x builds for each parameter: that adapter's import
was 0.15 s of CPU of `gearlab validate` (issue 42). Any other type or value goes to Typer's own
coercion, which gives the same result for these.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, get_args, get_origin

import typer
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

try:  # Typer >= 0.2x coerces each value through a Pydantic adapter (typer._coercion)
    from typer._coercion import RuntimeParam, build_runtime_param
    from typer._param_types import coerce_cli_path
except ImportError:  # an older Typer: click's own types, no Pydantic; nothing to take over
    RuntimeParam = None

HELP_NAMES = ["-h", "--help"]

_CLICK_NAMES = {"str": "TEXT", "int": "INTEGER", "float": "FLOAT", "bool": "BOOLEAN"}


def _type_name(param) -> str:
    """PATH, TEXT, INTEGER, FLOAT of a parameter's value (a list's element)."""
    descriptor = getattr(param, "type_descriptor", None)
    annotation: Any = getattr(descriptor, "annotation", None)
    if get_origin(annotation) is list:
        annotation = get_args(annotation)[0]
    if getattr(descriptor, "is_path", False) or getattr(annotation, "__name__", "") in ("Path", "PurePath"):
        return "PATH"
    if getattr(descriptor, "is_choice", False) and getattr(descriptor, "choices", None):
        return "[" + "|".join(str(getattr(c, "value", c)) for c in descriptor.choices) + "]"
    return _CLICK_NAMES.get(getattr(annotation, "__name__", ""), "TEXT")


_PLAIN = object()  # not a plain value: Typer's own coercion decides


def _plain_value(descriptor, value, param, ctx):
    """*value* as Typer's adapter would give it, where that is the value itself (a flag's
    bool, a text's str) or `Path(value)` then Typer's own checks of a path; else _PLAIN."""
    annotation, info = descriptor.annotation, descriptor.parameter_info
    if descriptor.file_annotation is not None or getattr(info, "parser", None) is not None:
        return _PLAIN
    if annotation is bool and isinstance(value, bool):
        return value
    if annotation is str and type(value) is str:
        return value
    if annotation is Path and getattr(info, "path_type", None) is None and isinstance(value, (str, Path)):
        return coerce_cli_path(Path(value), info, path_type=Path, param=param, ctx=ctx)
    return _PLAIN


if RuntimeParam is not None:

    class _PlainFirst(RuntimeParam):
        """A parameter's coercion: plain values here, the rest by Typer's adapter (built on first need)."""

        def __init__(self, descriptor) -> None:
            super().__init__(parameter_info=descriptor.parameter_info, annotation=descriptor.annotation)
            object.__setattr__(self, "descriptor", descriptor)
            object.__setattr__(self, "full", None)

        def _coerce_value(self, value, param, ctx):
            plain = _plain_value(self.descriptor, value, param, ctx)
            if plain is not _PLAIN:
                return plain
            if self.full is None:
                object.__setattr__(self, "full", build_runtime_param(self.descriptor))
            return self.full._coerce_value(value, param=param, ctx=ctx)


def _plain_first(param):
    """A parameter's get_runtime_param: plain values first (_PlainFirst)."""
    if param._runtime_param is None:
        param._runtime_param = _PlainFirst(param.type_descriptor)
    return param._runtime_param


class ConventionalArgument(TyperArgument):
    if RuntimeParam is not None:
        get_runtime_param = _plain_first

    def display_type_rich(self, ctx) -> str | None:
        return _type_name(self)

    def _usage_display_name(self) -> str:
        name = self.display_name_raw
        return name if self.required else f"[{name}]"


class ConventionalOption(TyperOption):
    if RuntimeParam is not None:
        get_runtime_param = _plain_first

    def display_type_rich(self, ctx) -> str | None:
        if self.is_bool_flag or self.is_flag:
            return None
        return self.metavar if self.metavar is not None else _type_name(self)


def _conform(params) -> None:
    for param in params:
        if type(param) is TyperArgument:
            param.__class__ = ConventionalArgument
            if param.metavar is None and param.name:
                param.metavar = param.name.upper() + ("..." if param.nargs != 1 else "")
        elif type(param) is TyperOption:
            param.__class__ = ConventionalOption


class _Conforming:
    """A command or group whose parameters, its own and those click adds (--help), follow the conventions."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        _conform(self.params)

    def get_params(self, ctx):
        params = super().get_params(ctx)
        _conform(params)
        return params


class ConventionalCommand(_Conforming, TyperCommand):
    def __init__(self, *args, **kwargs):
        kwargs["context_settings"] = {"help_option_names": HELP_NAMES, **(kwargs.get("context_settings") or {})}
        super().__init__(*args, **kwargs)


class ConventionalGroup(_Conforming, TyperGroup):
    pass


def conventional(app: typer.Typer) -> typer.Typer:
    """Every command of *app*, those added after this call included, in the conventions above."""
    add = app.command

    def command(*args, **kwargs):
        kwargs.setdefault("cls", ConventionalCommand)
        return add(*args, **kwargs)

    app.command = command  # type: ignore[method-assign]
    return app
