"""Data flows one way: lower layers never import upper ones; modules declare __all__."""

from __future__ import annotations

import ast
import pathlib

import pytest

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "flexarm"

# Lower number = lower layer. A module may import only modules of its own layer or below.
LAYERS = {
    "_validation": 0,
    "_io": 0,
    "modes": 1,
    "link": 1,
    "joints": 1,
    "fuzzy": 1,
    "fuzzy.sets": 1,
    "fuzzy.compiled": 1,
    "fuzzy.system": 1,
    "fuzzy.paper": 1,
    "kernels": 2,
    "signals": 0,
    "trajectories": 1,
    "shapers": 1,
    "delays": 1,
    "metrics": 1,
    "arm": 3,
    "sensors": 4,
    "controllers": 4,
    "adaptive": 4,
    "results": 4,
    "simloop": 4,
    "simulate": 5,
    "linearize": 5,
    "scenario": 6,
    "reproduce": 7,
    "cli": 9,
    "cli._common": 8,
    "cli.modes": 9,
    "cli.simulate": 9,
    "cli.identify": 9,
    "cli._hammerstein": 9,
    "cli.reproduce": 9,
    "__main__": 9,
    "__init__": 9,
    # flexarm.ident: data -> estimators; needs only _validation.
    "ident": 2,
    "ident.kernels": 1,
    "ident._params": 1,
    "ident.regression": 2,
    "ident.binning": 2,
    "ident.convergence": 2,
    "ident.systems": 1,
    "ident.hammerstein": 2,
    "joint_identification": 6,
}


def module_name(path: pathlib.Path) -> str:
    """Dotted name below flexarm: "arm", "ident" (a package's __init__), "ident.kernels"."""
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts.pop()
    return ".".join(parts)


def _known(dotted: str) -> str:
    """The longest prefix of ``dotted`` with a layer (``ident.kernels.x`` -> ``ident.kernels``)."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in LAYERS:
            return ".".join(parts[:k])
    return parts[0]


def flexarm_imports(path: pathlib.Path) -> set[str]:
    """Layer names of the flexarm modules ``path`` imports, relative imports resolved."""
    package = list(path.relative_to(SRC).parent.parts)
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level >= 1:
                base = package[: len(package) - (node.level - 1)]
                if node.module:
                    found.add(_known(".".join([*base, node.module])))
                else:
                    found.update(_known(".".join([*base, a.name])) for a in node.names)
            elif node.module and node.module.startswith("flexarm"):
                rest = node.module.split(".")[1:]
                found.add(_known(".".join(rest)) if rest else "__init__")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("flexarm."):
                    found.add(_known(a.name.split(".", 1)[1]))
    return found


MODULES = sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_module_has_a_layer():
    missing = [module_name(p) for p in MODULES if module_name(p) not in LAYERS]
    assert not missing, f"assign a layer in tests/test_layering.py: {missing}"


@pytest.mark.parametrize("path", MODULES, ids=module_name)
def test_no_upward_imports(path):
    name_ = module_name(path)
    layer = LAYERS[name_]
    for name in flexarm_imports(path):
        if name in LAYERS and name not in ("__init__", name_):
            assert LAYERS[name] <= layer, f"{name_} (layer {layer}) imports {name}"


@pytest.mark.parametrize("path", [p for p in MODULES if p.stem != "__main__"], ids=module_name)
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
