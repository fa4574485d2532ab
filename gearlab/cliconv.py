"""The CLI's help in the conventions of Typer's and click's own apps: `-h` beside `--help`;
arguments written SCENARIO (required), [SCENARIO] (optional), RUN_DIRS... (several); a value's
type as PATH, TEXT, INTEGER, FLOAT (a repeatable option: its element's type); no type beside a
flag (--quick/--no-quick takes no value).

`conventional(app)` makes every command of a Typer app (those added later included) use them.
"""

from __future__ import annotations

from typing import Any, get_args, get_origin

import typer
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

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


class ConventionalArgument(TyperArgument):
    def display_type_rich(self, ctx) -> str | None:
        return _type_name(self)

    def _usage_display_name(self) -> str:
        name = self.display_name_raw
        return name if self.required else f"[{name}]"


class ConventionalOption(TyperOption):
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
