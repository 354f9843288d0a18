"""Command-line options generated from an option dataclass: each default and help written once.

A field declared with `option` carries its one-line help (and, where the command line needs
them, choices, a text parser, another flag name) in its metadata; `add_options` turns the
fields into argparse options with the dataclass default, and `from_args` builds the dataclass
back from the parsed namespace. A field name ``eval_seeds`` becomes the flag ``--eval-seeds``.

    @dataclass
    class Options:
        workers: int = option(2, "seeds trained at once")
        backend: str = option("local", "local processes or a Ray cluster", choices=("local", "ray"))

    add_options(parser, Options)            # --workers WORKERS, --backend {local,ray}
    opts = from_args(Options, parser.parse_args(argv))

How a field's type becomes an option: ``bool`` a switch (``--x`` / ``--no-x``, or ``--x`` only
with ``negatable=False``; ``invert=True`` names a switch that turns a default-on field off, such
as ``--quiet`` for ``progress``); a ``parse`` function reads the text (a tuple default is shown
comma-separated and parsed like a given value); otherwise the default's type (``int``,
``float``, ``str``), and for a None default the hint's (``float | None`` reads a float). With
``nargs`` ("+", "*") the option takes several values, each read like one value (the type of the
tuple default's items), and the dataclass receives them as a tuple.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import typing
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path, PurePath
from typing import Any

__all__ = [
    "add_options",
    "comma_integers",
    "flag_of",
    "from_args",
    "option",
    "whole_number",
]

_UNSET: Any = dataclasses.MISSING


def option(
    default: Any,
    help: str,
    *,
    choices: Sequence[str] | None = None,
    parse: Callable[[str], Any] | None = None,
    flag: str | None = None,
    invert: bool = False,
    cli_default: Any = _UNSET,
    required: bool = False,
    metavar: str | None = None,
    nargs: str | None = None,
) -> Any:
    """A dataclass field with its command-line description (a plain `dataclasses.field` is
    offered by no command line).

    ``help`` is the one-line help; ``choices`` the allowed values; ``parse`` reads the option's
    text (ValueError → a one-line usage error); ``flag`` another flag name than the field's;
    ``invert`` a switch that stores ``not default``; ``cli_default`` the command line's default
    where the caller derives the value later (e.g. None: "the algorithm's file"); ``required``
    an option without default on the command line (the dataclass default serves programmatic
    callers); ``nargs`` ("+" or "*") an option of several values (a tuple default).
    """
    metadata = {
        "help": help,
        "choices": choices,
        "parse": parse,
        "flag": flag,
        "invert": invert,
        "cli_default": cli_default,
        "required": required,
        "metavar": metavar,
        "nargs": nargs,
    }
    return dataclasses.field(default=default, metadata=metadata)


def whole_number(text: str) -> int:
    """An integer, also written as a float ("2e6"); a fraction is an error, not truncated."""
    value = float(text)
    if not math.isfinite(value) or value != int(value):
        raise ValueError(f"{text!r} is not a whole number")
    return int(value)


def path_argument(text: str) -> Path:
    """A file or folder path; an empty text is an error (it would mean the current folder)."""
    if not text.strip():
        raise ValueError("must name a file or folder, got an empty path")
    return Path(text)


def comma_integers(text: str) -> tuple[int, ...]:
    """ "100,101" → (100, 101); empty items are skipped."""
    try:
        return tuple(int(s) for s in str(text).split(",") if s.strip())
    except ValueError:
        raise ValueError(f"expected comma-separated integers, got {text!r}") from None


def flag_of(f: dataclasses.Field) -> str:
    """The command-line flag of a dataclass field."""
    return f.metadata.get("flag") or "--" + f.name.replace("_", "-")


def _default(f: dataclasses.Field) -> Any:
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None


def _text_type(parse: Callable[[str], Any], flag: str) -> Callable[[str], Any]:
    """``parse`` for argparse: its ValueError message becomes the one-line usage error."""

    def read(text: str) -> Any:
        try:
            return parse(text)
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    read.__name__ = flag.lstrip("-")
    return read


def _optional_type(hint: Any) -> Callable[[str], Any] | None:
    """``int``/``float`` of an ``int | None`` / ``float | None`` hint; None (text) otherwise."""
    kinds = [t for t in typing.get_args(hint) if t is not type(None)]
    return kinds[0] if len(kinds) == 1 and kinds[0] in (int, float) else None


def _fields(cls: type, names: Iterable[str] | None) -> list[dataclasses.Field]:
    by_name = {f.name: f for f in dataclasses.fields(cls)}
    if names is None:
        return [f for f in by_name.values() if "help" in f.metadata]
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise ValueError(f"{cls.__name__} has no fields {unknown}")
    return [by_name[n] for n in names]


def add_options(
    parser: argparse.ArgumentParser,
    cls: type,
    names: Iterable[str] | None = None,
    *,
    negatable: bool = True,
) -> list[str]:
    """Add an option for each field of the dataclass ``cls`` declared with `option` (or for
    ``names`` only, in that order); returns the field names added, for `from_args`."""
    hints = typing.get_type_hints(cls)
    added = []
    for f in _fields(cls, names):
        meta = f.metadata
        if "help" not in meta:
            raise TypeError(f"{cls.__name__}.{f.name} is no `option` field (it has no help)")
        flag, default = flag_of(f), _default(f)
        if meta["cli_default"] is not _UNSET:
            default = meta["cli_default"]
        kwargs: dict[str, Any] = {"help": meta["help"], "dest": f.name}
        if hints[f.name] is bool:
            if meta["invert"]:
                kwargs.update(
                    action="store_true",
                    default=not default,
                    dest=flag.lstrip("-").replace("-", "_"),
                )
            elif negatable:
                kwargs.update(action=argparse.BooleanOptionalAction, default=default)
            else:
                kwargs.update(action="store_true", default=default)
        else:
            if meta.get("nargs") is not None:  # several values, each read like one
                kwargs["nargs"] = meta["nargs"]
                item = meta["parse"] or (type(default[0]) if default else str)
                kwargs["type"] = _text_type(item, flag) if meta["parse"] else item
                default = list(default)
            elif meta["parse"] is not None:
                kwargs["type"] = _text_type(meta["parse"], flag)
                if isinstance(default, tuple):  # shown as typed; argparse parses it
                    default = ",".join(map(str, default))
            elif isinstance(default, PurePath):  # "" would silently mean the current folder
                kwargs["type"] = _text_type(path_argument, flag)
            elif default is not None:
                kwargs["type"] = type(default)
            else:  # `float | None` reads a float, as argparse's type=float does
                kwargs["type"] = _optional_type(hints[f.name])
            if meta["required"]:
                kwargs["required"] = True
                default = None
            kwargs["default"] = default
            if meta["choices"] is not None:
                kwargs["choices"] = list(meta["choices"])
            if meta["metavar"] is not None:
                kwargs["metavar"] = meta["metavar"]
        parser.add_argument(flag, **kwargs)
        added.append(f.name)
    return added


def from_args(
    cls: type, namespace: argparse.Namespace | dict[str, Any], names: Iterable[str], **fixed: Any
) -> Any:
    """``cls(**values)`` from the options `add_options` added for ``names``, plus ``fixed``."""
    values = vars(namespace) if isinstance(namespace, argparse.Namespace) else dict(namespace)
    by_name = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for name in names:
        f = by_name[name]
        if f.metadata.get("invert"):
            kwargs[name] = not values[flag_of(f).lstrip("-").replace("-", "_")]
        elif f.metadata.get("nargs") is not None:
            kwargs[name] = tuple(values[name])
        else:
            kwargs[name] = values[name]
    return cls(**kwargs, **fixed)
