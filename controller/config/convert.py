"""Frozen dataclasses to and from plain data (dicts, lists, numbers, strings, booleans:
JSON and TOML alike), with a one-line error naming the source and the key for anything
that is not one of the dataclass's fields or not of the field's type."""

from __future__ import annotations

import dataclasses
import math
import types
import typing

from upm.core.errors import UsageError


class ConfigError(UsageError):
    """A configuration file or dict with an unknown key or a value of the wrong type
    (one line: the source, the key and what is wrong)."""


def to_plain(value):
    """A dataclass (nested, with tuples) as dicts and lists, JSON-ready."""
    if dataclasses.is_dataclass(value):
        return {f.name: to_plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple):
        return [to_plain(v) for v in value]
    return value


def from_plain(cls, data, source: str, base=None, path: str = ""):
    """An instance of dataclass ``cls`` from ``data`` (a dict): its fields as given, the
    others as in ``base`` (an instance of ``cls``; default: ``cls()``).

    Raises
    ------
    ConfigError
        ``"SOURCE: unknown key 'a.b' ..."`` or ``"SOURCE: a.b must be ..., not ..."``.
    """
    base = cls() if base is None else base
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: {path or 'the configuration'} must be a table of "
                          f"keys, not {_shown(data)}")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    values = {}
    for key, item in data.items():
        where = f"{path}.{key}" if path else str(key)
        if key not in names:
            raise ConfigError(f"{source}: unknown key {where!r} (the keys of "
                              f"{'[' + path + ']' if path else 'the configuration'}: "
                              f"{', '.join(names)})")
        values[key] = _value(hints[key], item, source, where, getattr(base, key))
    return dataclasses.replace(base, **values)


def _value(kind, item, source: str, where: str, base):
    """``item`` as a value of type ``kind`` (a field's annotation)."""
    if dataclasses.is_dataclass(kind):
        return from_plain(kind, item, source, base, where)
    args = typing.get_args(kind)
    origin = typing.get_origin(kind)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        if item is None and type(None) in args:
            return None
        return _value(inner[0], item, source, where, base)
    if origin is tuple:
        if not isinstance(item, (list, tuple)):
            raise ConfigError(f"{source}: {where} must be a list ({_described(kind)}), not "
                              f"{_shown(item)}")
        element = args[0]
        out = []
        for i, x in enumerate(item):
            default = element() if dataclasses.is_dataclass(element) else None
            out.append(_value(element, x, source, f"{where}[{i}]", default))
        return tuple(out)
    if kind is bool:
        if not isinstance(item, bool):
            raise ConfigError(f"{source}: {where} must be true or false, not {_shown(item)}")
        return item
    if kind is int:
        if isinstance(item, bool) or not isinstance(item, int):
            raise ConfigError(f"{source}: {where} must be a whole number, not {_shown(item)}")
        return item
    if kind is float:
        if isinstance(item, bool) or not isinstance(item, (int, float)):
            raise ConfigError(f"{source}: {where} must be a number, not {_shown(item)}")
        if not math.isfinite(item):
            raise ConfigError(f"{source}: {where} must be a finite number, not {item!r}")
        return float(item)
    if kind is str:
        if not isinstance(item, str):
            raise ConfigError(f"{source}: {where} must be a string, not {_shown(item)}")
        return item
    raise TypeError(f"no conversion for {kind!r} ({where})")


def _described(kind) -> str:
    args = typing.get_args(kind)
    element = args[0] if args else None
    if dataclasses.is_dataclass(element):
        return "of tables"
    return {float: "of numbers", int: "of whole numbers", str: "of strings"}.get(element, "")


def _shown(item) -> str:
    if isinstance(item, dict):
        return "a table"
    if isinstance(item, (list, tuple)):
        return "a list"
    if isinstance(item, str):
        return repr(item)
    return f"{item!r}" if isinstance(item, (bool, int, float)) else type(item).__name__
