"""Reading TOML configuration files (scenarios, sweeps, calibrations) and checking them.

One way to read a file (:func:`read_toml`) and one reader of its tables
(:class:`ConfigReader`) for every kind of file flexarm takes, so that every
problem is reported alike: one line that starts with the file and names the
dotted key, e.g. ``sweep.toml: monte_carlo.n: must be an integer >= 1. Got 0
instead.`` A kind of file gives the reader its error classes
(:class:`flexarm.errors.ScenarioError`, :class:`flexarm.errors.SweepError`, ...),
all :class:`flexarm.errors.ConfigError` with ``source``, ``key`` and ``reason``.

No compiled code and no SciPy: the command line checks a file before anything
heavy is imported.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import tomllib
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any, NoReturn

from .errors import ConfigError, ConfigFileError, KeyPathError

__all__ = [
    "KEY_PATTERN",
    "ConfigReader",
    "TomlValue",
    "copy_value",
    "format_key",
    "read_toml",
    "set_key",
    "split_key",
    "table_at",
]

TomlValue = str | int | float | bool | list["TomlValue"] | dict[str, "TomlValue"]
"""A value a TOML file can hold (dates and times excepted)."""

_PARAMETER = re.compile(r"The '(\w+)' parameter")

KEY_PATTERN = re.compile(
    r"[A-Za-z_][A-Za-z0-9_]*(?:\[\d+\])*(?:\.[A-Za-z_][A-Za-z0-9_]*(?:\[\d+\])*)*"
)
"""A dotted key into a file's tables: names joined by dots, each with optional
``[index]`` suffixes (``"arm.links[1].length"``)."""

_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")


def read_toml(
    path: str | os.PathLike[str],
    error: type[ConfigFileError] = ConfigError,
    what: str = "configuration file",
) -> dict[str, Any]:
    """The raw mapping of a TOML file (not yet checked).

    Parameters
    ----------
    path : str or path-like
    error : type of ConfigFileError
        Raised (the source being the path) if the file cannot be read or is not
        valid TOML.
    what : str
        What the file should have been, for the message of a directory.
    """
    source = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise error(source, None, "no such file") from None
    except IsADirectoryError:
        raise error(source, None, f"a directory, not a {what}") from None
    except OSError as exc:
        raise error(source, None, f"cannot read the file: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(source, None, f"not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise error(source, None, "not valid TOML: not UTF-8 text") from None


class ConfigReader:
    """Checks the tables of one file and reports problems against its source.

    Parameters
    ----------
    source : str
        Named at the start of every message (the file name).
    error, type_error : type of ConfigError
        Raised for a wrong value and for a wrong type (a kind of file may report
        both as one class).
    whole : str
        What the file is called where a key of its top level is unknown.
    """

    def __init__(
        self,
        source: str,
        error: type[ConfigFileError] = ConfigError,
        type_error: type[ConfigFileError] | None = None,
        whole: str = "the file",
    ) -> None:
        self.source = source
        self.error = error
        self.type_error = error if type_error is None else type_error
        self.whole = whole

    def fail(self, key: str | None, reason: str, *, show_key: bool = True) -> NoReturn:
        """Raise the file's error for a wrong value at ``key``."""
        raise self.error(self.source, key, reason, show_key=show_key)

    def fail_type(self, key: str | None, reason: str) -> NoReturn:
        """Raise the file's error for an entry of the wrong type at ``key``."""
        raise self.type_error(self.source, key, reason)

    def sections(self, data: object, allowed: tuple[str, ...] | None = None) -> Mapping[str, Any]:
        """``data``, the whole file, if it is a table (else a type error); with ``allowed``,
        an entry of another name is refused as an unknown section or key."""
        if not isinstance(data, Mapping):
            self.fail_type(None, f"must be a table of sections. Got {type(data).__name__} instead.")
        if allowed is not None:
            takes = f"{self.whole} takes {', '.join(allowed)}"
            for name, value in data.items():
                if name not in allowed:
                    what = "section" if isinstance(value, Mapping) else "key"
                    self.fail(None, f"unknown {what} '{name}' ({takes})")
        return data

    def table(self, data: Mapping[str, Any], key: str, prefix: str = "") -> dict[str, Any]:
        """``data[key]`` (``{}`` if absent) as a table, else a type error naming it."""
        return self.as_table(data.get(key, {}), f"{prefix}{key}")

    def as_table(self, value: object, key: str) -> dict[str, Any]:
        """``value`` if it is a table, else a type error naming ``key``."""
        if not isinstance(value, Mapping):
            self.fail_type(key, f"must be a table ([{key}]). Got {value!r} instead.")
        return dict(value)

    def keys(
        self,
        table: Mapping[str, Any],
        prefix: str,
        allowed: tuple[str, ...],
        what: str | None = None,
    ) -> None:
        """Refuse any key of ``table`` (the table at ``prefix``) not in ``allowed``;
        ``what`` names the taker (default the table, or the whole file)."""
        taker = what or prefix or self.whole
        for key in table:
            if key not in allowed:
                where = f"{prefix}.{key}" if prefix else key
                self.fail(
                    where,
                    f"unknown key '{where}' ({taker} takes {', '.join(allowed)})",
                    show_key=False,
                )

    @contextmanager
    def library(self, prefix: str, table: Mapping[str, Any] | None = None) -> Iterator[None]:
        """Report the library's TypeError/ValueError against the key it names."""
        try:
            yield
        except ConfigFileError:
            raise
        except (TypeError, ValueError) as exc:
            m = _PARAMETER.search(str(exc))
            key = prefix
            if m is not None and table is not None and m[1] in table:
                key = f"{prefix}.{m[1]}"
            if isinstance(exc, TypeError):
                self.fail_type(key, str(exc))
            self.fail(key, str(exc))

    def build(self, cls: type, table: Mapping[str, Any], prefix: str, *, kind: bool = False) -> Any:
        """``cls(**table)`` for a dataclass, with unknown and missing keys named
        (``kind``: the table also holds the ``kind`` key that chose ``cls``)."""
        fields = [f for f in dataclasses.fields(cls) if f.init]
        allowed = tuple(f.name for f in fields)
        params = {k: v for k, v in table.items() if not (kind and k == "kind")}
        self.keys(params, prefix, allowed, cls.__name__)
        required = [
            f.name
            for f in fields
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        for name in required:
            if name not in params:
                needs = ", ".join(required)
                self.fail(prefix, f"missing key '{prefix}.{name}' ({cls.__name__} needs {needs})")
        with self.library(prefix, params):
            return cls(**params)

    def kind(
        self,
        table: Mapping[str, Any],
        prefix: str,
        options: tuple[str, ...],
        default: str | None = None,
    ) -> str:
        """The table's ``kind`` (``default``, else the first option, if absent), one of
        ``options``."""
        value = table.get("kind", options[0] if default is None else default)
        if not isinstance(value, str) or value not in options:
            self.fail(f"{prefix}.kind", f"must be one of {options}. Got {value!r} instead.")
        return value

    def integer(self, value: object, key: str, minimum: int) -> int:
        """``value`` as an int ``>= minimum``."""
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail_type(key, f"must be an integer >= {minimum}. Got {value!r} instead.")
        if value < minimum:
            self.fail(key, f"must be an integer >= {minimum}. Got {value!r} instead.")
        return int(value)

    def real(self, value: object, key: str) -> float:
        """``value`` as a finite float (an int is accepted)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.fail_type(key, f"must be a real number. Got {value!r} instead.")
        x = float(value)
        if not math.isfinite(x):
            self.fail(key, f"must be finite. Got {value!r} instead.")
        return x

    def string(self, value: object, key: str) -> str:
        """``value`` if it is a non-empty string."""
        if not isinstance(value, str) or not value:
            self.fail_type(key, f"must be a non-empty string. Got {value!r} instead.")
        return value

    def value(self, value: object, key: str) -> TomlValue:
        """``value`` as a plain TOML value (NumPy scalars to Python, tuples to lists).

        Dates and times and other objects are refused: what is read must travel as
        JSON (to a journal, to a cluster).
        """
        if isinstance(value, bool | str):
            return value
        if isinstance(value, int | float):
            return value
        item = getattr(value, "item", None)  # a NumPy scalar
        if callable(item) and type(value).__module__ == "numpy" and getattr(value, "ndim", 1) == 0:
            return self.value(item(), key)
        if isinstance(value, list | tuple):
            return [self.value(v, f"{key}[{k}]") for k, v in enumerate(value)]
        if isinstance(value, Mapping):
            out: dict[str, TomlValue] = {}
            for name, v in value.items():
                if not isinstance(name, str):
                    self.fail_type(key, f"keys must be strings. Got {name!r} instead.")
                out[name] = self.value(v, f"{key}.{name}")
            return out
        self.fail_type(
            key,
            "must be a number, a string, a boolean, an array or a table. "
            f"Got {type(value).__name__} {value!r} instead.",
        )


# ------------------------------------------------------------------ dotted keys
def split_key(key: str) -> tuple[str | int, ...]:
    """``"arm.links[1].length"`` -> ``("arm", "links", 1, "length")``.

    Raises
    ------
    KeyPathError
        If ``key`` is not a dotted key (:data:`KEY_PATTERN`).
    """
    if not isinstance(key, str) or not KEY_PATTERN.fullmatch(key):
        raise KeyPathError(str(key), "not a dotted key ('sensor.noise_std', 'arm.links[1].length')")
    return tuple(m[1] if m[1] is not None else int(m[2]) for m in _PART.finditer(key))


def format_key(parts: tuple[str | int, ...]) -> str:
    """``("arm", "links", 1, "length")`` -> ``"arm.links[1].length"``."""
    text = ""
    for p in parts:
        text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else p)
    return text


def copy_value(value: TomlValue) -> TomlValue:
    """A deep copy of a file's value (tables, arrays and scalars: what TOML and JSON
    hold), without ``copy.deepcopy``'s bookkeeping."""
    if isinstance(value, Mapping):
        return {k: copy_value(v) for k, v in value.items()}
    if isinstance(value, list):
        return [copy_value(v) for v in value]
    return value


def table_at(
    data: dict[str, TomlValue], parts: tuple[str | int, ...], key: str, *, create: bool = True
) -> dict[str, TomlValue]:
    """The table of ``data`` that holds the last part of ``parts`` (tables created on
    the way where ``create``), for the dotted ``key`` the parts came from.

    Raises
    ------
    KeyPathError
        If the path indexes beyond an array, into something that is not an array or a
        table, or (without ``create``) through a table that does not exist.
    """
    node: TomlValue = data
    for k, part in enumerate(parts[:-1]):
        where = format_key(parts[: k + 1])
        if isinstance(part, int):
            if not isinstance(node, list):
                raise KeyPathError(key, f"'{where}' indexes something that is not an array")
            if part >= len(node):
                raise KeyPathError(key, f"the array has {len(node)} items: no '{where}'")
            node = node[part]
        else:
            if not isinstance(node, dict):
                raise KeyPathError(key, f"'{format_key(parts[:k])}' is not a table")
            if not create and part not in node:
                raise KeyPathError(key, f"there is no '{where}'")
            node = node.setdefault(part, {})
    if isinstance(parts[-1], int):
        raise KeyPathError(key, "set an array item's keys ('arm.links[1].length'), not the item")
    if not isinstance(node, dict):
        raise KeyPathError(key, f"'{format_key(parts[:-1])}' is not a table")
    return node


def set_key(data: dict[str, TomlValue], key: str, value: TomlValue) -> None:
    """Set the dotted ``key`` of ``data`` in place (tables created on the way)."""
    parts = split_key(key)
    table_at(data, parts, key)[str(parts[-1])] = copy_value(value)
