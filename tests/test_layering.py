"""Data flows one way: lower layers never import upper ones; modules declare __all__."""

from __future__ import annotations

import ast
import pathlib

import pytest

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "flexarm"

# Lower number = lower layer. A module may import only modules of its own layer or below.
LAYERS = {
    "_validation": 0,
    "modes": 1,
    "link": 1,
    "joints": 1,
    "fuzzy": 1,
    "kernels": 2,
    "signals": 0,
    "trajectories": 1,
    "shapers": 1,
    "delays": 1,
    "metrics": 1,
    "arm": 3,
    "sensors": 4,
    "controllers": 4,
    "results": 4,
    "simloop": 4,
    "simulate": 5,
    "scenario": 6,
    "cli": 9,
    "__main__": 9,
    "__init__": 9,
}


def flexarm_imports(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level >= 1:
                if node.module:
                    found.add(node.module.split(".")[0])
                else:
                    found.update(a.name.split(".")[0] for a in node.names)
            elif node.module and node.module.startswith("flexarm"):
                parts = node.module.split(".")
                found.add(parts[1] if len(parts) > 1 else "__init__")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("flexarm."):
                    found.add(a.name.split(".")[1])
    return found


MODULES = sorted(p for p in SRC.glob("*.py"))


def test_every_module_has_a_layer():
    missing = [p.stem for p in MODULES if p.stem not in LAYERS]
    assert not missing, f"assign a layer in tests/test_layering.py: {missing}"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.stem)
def test_no_upward_imports(path):
    layer = LAYERS[path.stem]
    for name in flexarm_imports(path):
        if name in LAYERS and name != "__init__":
            assert LAYERS[name] <= layer, f"{path.stem} (layer {layer}) imports {name}"


@pytest.mark.parametrize("path", [p for p in MODULES if p.stem != "__main__"], ids=lambda p: p.stem)
def test_module_declares_all(path):
    tree = ast.parse(path.read_text())
    names = {
        t.id
        for node in tree.body
        if isinstance(node, ast.Assign)
        for t in node.targets
        if isinstance(t, ast.Name)
    }
    assert "__all__" in names
