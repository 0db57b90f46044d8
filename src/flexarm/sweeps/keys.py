"""Dotted keys into a scenario mapping, and the identity of a run.

A swept parameter is named by a dotted key into the scenario schema
(:mod:`flexarm.sim.scenario`): ``"sensor.noise_std"``, ``"controller.kp"``,
``"arm.joints.stiffness"``, and with an index into an array of tables,
``"arm.links[1].length"``. :func:`with_changes` writes a run's values into a
copy of the base scenario; :func:`run_id` names the result by a hash of the
whole mapping, so that the same run has the same id in every sweep and on every
machine (the journal of a sweep is keyed by it).

Examples
--------
>>> parse_key("arm.links[1].length")
('arm', 'links', 1, 'length')
>>> base = {"controller": {"kind": "pd", "zeta": 0.5}, "sensor": {"noise_std": 1e-3}}
>>> with_changes(base, {"controller.kind": "joint-pd", "controller.kp": 100.0,
...                     "sensor.kind": "tip"})
{'controller': {'kind': 'joint-pd', 'kp': 100.0}, 'sensor': {'noise_std': 0.001, 'kind': 'tip'}}
>>> run_id({"simulation": {"seed": 1}}) == run_id({"simulation": {"seed": 1}})
True
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable, Iterator, Mapping

from ..sim.scenario_schema import JOINT_KINDS, SECTIONS, apply_overrides
from .reader import Value

__all__ = [
    "KEY_PATTERN",
    "KeyPathError",
    "canonical_json",
    "flatten",
    "format_key",
    "parse_key",
    "run_id",
    "with_changes",
]

KEY_PATTERN = re.compile(
    r"[A-Za-z_][A-Za-z0-9_]*(?:\[\d+\])*(?:\.[A-Za-z_][A-Za-z0-9_]*(?:\[\d+\])*)*"
)
"""A dotted key: names joined by dots, each with optional ``[index]`` suffixes."""

_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")
_NESTED_DEFAULT_KIND: dict[tuple[str, ...], str] = {("arm", "joints"): JOINT_KINDS[0]}
_KEEP_ON_KIND_CHANGE: dict[tuple[str, ...], tuple[str, ...]] = {
    ("sensor",): ("noise_std", "rate_noise_std", "quantization", "rate_quantization")
}


class KeyPathError(ValueError):
    """A key that cannot be set in the base scenario (``reason`` says why)."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


def parse_key(key: str) -> tuple[str | int, ...]:
    """``"arm.links[1].length"`` -> ``("arm", "links", 1, "length")``.

    Raises
    ------
    KeyPathError
        If ``key`` is not a dotted key (:data:`KEY_PATTERN`) or names no section
        of the scenario schema.
    """
    if not KEY_PATTERN.fullmatch(key):
        raise KeyPathError(
            key, "not a dotted key into the scenario ('sensor.noise_std', 'arm.links[1].length')"
        )
    parts: tuple[str | int, ...] = tuple(
        m[1] if m[1] is not None else int(m[2]) for m in _PART.finditer(key)
    )
    if parts[0] not in SECTIONS:
        raise KeyPathError(key, f"unknown section '{parts[0]}' (sections: {', '.join(SECTIONS)})")
    if len(parts) < 2:
        raise KeyPathError(key, f"name a key inside the section ('{key}.KEY'), not the section")
    return parts


def format_key(parts: tuple[str | int, ...]) -> str:
    """The inverse of :func:`parse_key`."""
    text = ""
    for p in parts:
        text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else p)
    return text


def flatten(
    table: Mapping[str, object],
    is_leaf: Callable[[Mapping[str, object]], bool] | None = None,
    prefix: str = "",
) -> Iterator[tuple[str, object]]:
    """``(dotted key, value)`` for each leaf of a nested table.

    TOML reads ``sensor.noise_std = [...]`` as a table ``sensor`` holding
    ``noise_std``, and ``"sensor.noise_std" = [...]`` as one key with a dot: both
    give ``"sensor.noise_std"``. A value is a leaf unless it is a table for
    which ``is_leaf`` is false (a Monte Carlo entry
    ``{distribution = "uniform", ...}`` is a table and a leaf).

    Examples
    --------
    >>> list(flatten({"sensor": {"noise_std": [0, 1]}, "controller.kp": [1]}))
    [('sensor.noise_std', [0, 1]), ('controller.kp', [1])]
    """
    for name, value in table.items():
        key = f"{prefix}.{name}" if prefix else name
        if isinstance(value, Mapping) and not (is_leaf is not None and is_leaf(value)):
            yield from flatten(value, is_leaf, key)
        else:
            yield key, value


def _walk(data: dict[str, Value], parts: tuple[str | int, ...], key: str) -> dict[str, Value]:
    """The table that holds the last part of ``parts``, tables created on the way."""
    node: Value = data
    for k, part in enumerate(parts[:-1]):
        where = format_key(parts[: k + 1])
        if isinstance(part, int):
            if not isinstance(node, list):
                raise KeyPathError(key, f"'{where}' indexes something that is not an array")
            if part >= len(node):
                raise KeyPathError(
                    key, f"the base scenario's array has {len(node)} items: no '{where}'"
                )
            node = node[part]
        else:
            if not isinstance(node, dict):
                raise KeyPathError(key, f"'{format_key(parts[:k])}' is not a table")
            node = node.setdefault(part, {})
    if isinstance(parts[-1], int):
        raise KeyPathError(key, "set an array item's keys ('arm.links[1].length'), not the item")
    if not isinstance(node, dict):
        raise KeyPathError(key, f"'{format_key(parts[:-1])}' is not a table")
    return node


def _copy(value: Value) -> Value:
    """A deep copy of a scenario value (tables, arrays and scalars: what TOML and JSON
    hold), without ``copy.deepcopy``'s bookkeeping (a sweep copies its base per run)."""
    if isinstance(value, Mapping):
        return _copy_table(value)
    if isinstance(value, list):
        return [_copy(v) for v in value]
    return value


def _copy_table(table: Mapping[str, Value]) -> dict[str, Value]:
    return {k: _copy(v) for k, v in table.items()}


def with_changes(base: Mapping[str, Value], changes: Mapping[str, Value]) -> dict[str, Value]:
    """A deep copy of ``base`` with each dotted key of ``changes`` set.

    Where a change sets a table's ``kind`` to another kind than the base's
    (defaults included), that table's other keys from the base are dropped: they
    were parameters of the other kind (as ``flexarm simulate --controller``
    does, :func:`~flexarm.sim.scenario_schema.apply_overrides`); the sensor keeps
    its noise keys, which every kind takes. Kinds are set first, then the other
    keys in order.

    Raises
    ------
    KeyPathError
        If a key cannot be set (a bad key, an index beyond the base's array, a
        key inside something that is not a table).
    """
    data: dict[str, Value] = _copy_table(base)
    parsed = [(key, parse_key(key), value) for key, value in changes.items()]
    kinds = [c for c in parsed if c[1][-1] == "kind"]
    for key, parts, value in kinds:
        if len(parts) == 2:
            data = apply_overrides(data, {str(parts[0]): {"kind": value}})
            continue
        table = _walk(data, parts, key)
        default = _NESTED_DEFAULT_KIND.get(tuple(str(p) for p in parts[:-1]))
        if value != table.get("kind", default):
            keep = _KEEP_ON_KIND_CHANGE.get(tuple(str(p) for p in parts[:-1]), ())
            for name in [n for n in table if n not in keep]:
                del table[name]
        table["kind"] = _copy(value)
    for key, parts, value in parsed:
        if parts[-1] != "kind":
            _walk(data, parts, key)[str(parts[-1])] = _copy(value)
    return data


def canonical_json(value: object) -> str:
    """Compact JSON with sorted keys: the same text for equal mappings."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def run_id(scenario: Mapping[str, Value]) -> str:
    """A run's identity: 16 hex digits of the SHA-256 of its full scenario mapping.

    Stable across processes, machines and flexarm versions (Python's ``hash``
    is not); ``1`` and ``1.0`` are different values and give different ids.
    """
    return hashlib.sha256(canonical_json(scenario).encode()).hexdigest()[:16]
