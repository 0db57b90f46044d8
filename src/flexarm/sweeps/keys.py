"""Dotted keys into a scenario mapping, and the identity of a run.

A swept parameter is named by a dotted key into the scenario schema
(:mod:`flexarm.sim.scenario`): ``"sensor.noise_std"``, ``"controller.kp"``,
``"arm.joints.stiffness"``, with an index into an array of tables,
``"arm.links[1].length"``, and with an index at the end, one item of an array of
numbers the base scenario holds, ``"arm.gravity[1]"``. :func:`with_changes`
writes a run's values into a copy of the base scenario; :func:`run_id` names the
result by a hash of the whole mapping, so that the same run has the same id in
every sweep and on every machine (the journal of a sweep is keyed by it).

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
from collections.abc import Callable, Iterator, Mapping

from .._config import KEY_PATTERN, copy_value, format_key, split_key, table_at
from ..errors import KeyPathError
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

_NESTED_DEFAULT_KIND: dict[tuple[str, ...], str] = {("arm", "joints"): JOINT_KINDS[0]}
_KEEP_ON_KIND_CHANGE: dict[tuple[str, ...], tuple[str, ...]] = {
    ("sensor",): ("noise_std", "rate_noise_std", "quantization", "rate_quantization")
}


def parse_key(key: str) -> tuple[str | int, ...]:
    """``"arm.links[1].length"`` -> ``("arm", "links", 1, "length")``.

    Raises
    ------
    KeyPathError
        If ``key`` is not a dotted key (:data:`KEY_PATTERN`) or
        names no section of the scenario schema.
    """
    if not isinstance(key, str) or not KEY_PATTERN.fullmatch(key):
        raise KeyPathError(
            str(key),
            "not a dotted key into the scenario ('sensor.noise_std', 'arm.links[1].length')",
        )
    parts = split_key(key)
    if parts[0] not in SECTIONS:
        raise KeyPathError(key, f"unknown section '{parts[0]}' (sections: {', '.join(SECTIONS)})")
    if len(parts) < 2:
        raise KeyPathError(key, f"name a key inside the section ('{key}.KEY'), not the section")
    return parts


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
    data = copy_value(dict(base))
    assert isinstance(data, dict)
    parsed = [(key, parse_key(key), value) for key, value in changes.items()]
    kinds = [c for c in parsed if c[1][-1] == "kind"]
    for key, parts, value in kinds:
        if len(parts) == 2:
            data = apply_overrides(data, {str(parts[0]): {"kind": value}})
            continue
        table = table_at(data, parts, key)
        default = _NESTED_DEFAULT_KIND.get(tuple(str(p) for p in parts[:-1]))
        if value != table.get("kind", default):
            keep = _KEEP_ON_KIND_CHANGE.get(tuple(str(p) for p in parts[:-1]), ())
            for name in [n for n in table if n not in keep]:
                del table[name]
        table["kind"] = copy_value(value)
    for key, parts, value in parsed:
        if isinstance(parts[-1], int):
            _set_item(data, parts, key, value)
        elif parts[-1] != "kind":
            table_at(data, parts, key)[str(parts[-1])] = copy_value(value)
    return data


def _set_item(data: dict[str, Value], parts: tuple[str | int, ...], key: str, value: Value) -> None:
    """Set item ``parts[-1]`` of the array of numbers the base holds at ``parts[:-1]``
    (``"arm.gravity[1]"``: the vertical component of the base's gravity)."""
    where = format_key(parts[:-1])
    name, index = parts[-2], parts[-1]
    assert isinstance(index, int)
    holder = table_at(data, parts[:-1], key) if isinstance(name, str) else None
    array = None if holder is None or not isinstance(name, str) else holder.get(name)
    if not isinstance(array, list) or any(isinstance(v, dict | list) for v in array):
        raise KeyPathError(
            key,
            f"'{where}' is not an array of numbers in the base scenario: give the whole "
            f"array there (e.g. [arm] gravity = [0.0, -9.81]) to sweep one of its items",
        )
    if index >= len(array):
        raise KeyPathError(key, f"the array has {len(array)} items: no '{key}'")
    array[index] = copy_value(value)


def canonical_json(value: object) -> str:
    """Compact JSON with sorted keys: the same text for equal mappings."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def run_id(scenario: Mapping[str, Value]) -> str:
    """A run's identity: 16 hex digits of the SHA-256 of its full scenario mapping.

    Stable across processes, machines and flexarm versions (Python's ``hash``
    is not); ``1`` and ``1.0`` are different values and give different ids.
    """
    return hashlib.sha256(canonical_json(scenario).encode()).hexdigest()[:16]
