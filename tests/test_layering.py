"""The package layout is the data flow: lower layers never import upper ones.

parameters -> models -> simulator <- controllers, sensors, references -> results
-> metrics, plots, reports; data -> estimators -> identified model. Each top-level
package is one layer; packages of one layer are independent of each other; inside
a package, modules are ordered too. Every module declares ``__all__``.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "flexarm"

# Layers, lowest first. A module may import its own package and the packages of
# lower layers; packages of the same layer (e.g. model, fuzzy, ident) do not import
# each other.
LAYERS: list[tuple[str, ...]] = [
    ("_version", "errors"),  # the version; the error types
    # lazy names, array types, checks, atomic output, Numba, limits on memory and time, files
    ("_lazy", "_types", "_validation", "_io", "_compile", "_budget", "_config"),
    ("figures",),  # figure files (format, resolution, atomic writes) and the plots' style
    ("model", "fuzzy", "ident"),  # the plant; fuzzy inference; estimators from data
    ("sensing",),  # what a controller can see: sensors and transport delays
    ("control",),  # references, shapers, control laws, linear analysis
    ("sim",),  # the simulator, its results and metrics, scenario files
    ("sweeps",),  # grid and Monte Carlo sweeps of scenarios, on every core or a Dask cluster
    ("calibration",),  # an arm's parameters fitted to measured runs
    # the paper's reproduction, the robot-joint identification study; Gymnasium environments
    ("studies", "envs"),
    ("cli",),  # the command line
    ("__main__", "__init__", "modes"),  # the package's entry points and facades
]
RANK = {name: k for k, names in enumerate(LAYERS) for name in names}

# Inside a package: a module may import the modules listed before it (or its own
# package's __init__ when that is lower still). Packages not listed are unordered.
# A sub-package is one entry of its parent's list; its own modules are ordered by
# the entry of its dotted name ("model.dynamics"), if it has one.
WITHIN: dict[str, list[str]] = {
    "model": [
        "validity",
        "_roots",
        "beam",
        "link",
        "joints",
        "arrays",
        "kernel_checks",
        "plant",
        "drives",
        "foreshortening",
        "gravity",
        "statics",
        "packing",
        "kinematics",
        "lagrangian",
        "dynamics",  # the compiled dynamics, a sub-package ordered below
        "_buffer",
        "packed",
        "backends",
        "prescribed",
        "arm",
        "damped_modes",
    ],
    "model.dynamics": [
        "_link_terms",
        "_gravity",
        "_dense",
        "_recursive",
        "_two_links",
        "_points",
        "_forward",
    ],
    "sensing": ["delays", "sensors", "_channels", "channels", "instruments"],
    "control": [
        "options",
        "signals",
        "gravity_compensation",
        "_piecewise",
        "_path_kernels",
        "_gains",
        "_lqg_layout",
        "trajectories",
        "sag",
        "_ei",
        "shapers",
        "statespace",
        "controllers",
        "adaptive",
        "feedforward",
        "linearize",
        "design",
        "sampling",
        "reflected",
        "_lqg_design",
        "lqg",
        "interop",
        "custom",
    ],
    "sim": [
        "metrics",
        "animation",  # before results: SimulationResult.animate calls it
        "results",
        "chunks",
        "_rk4",
        "integrator",
        "_reference_kernels",
        "loop",
        "references",
        "settings",
        "scipy_loop",
        "closed_loop",
        "batch",
        "step_check",
        "open_loop",
        "prescribed",
        "scenario_schema",
        "scenario",
    ],
    "sweeps": [
        "reader",
        "keys",
        "distributions",
        "spec",
        "records",
        "table",
        "journal",
        "execute",
        "cluster",
        "driver",
    ],
    "calibration": ["units", "records", "config", "model", "fit", "result"],
    "fuzzy": ["sets", "_kernels", "compiled", "system", "paper"],
    "envs": ["config", "step", "core", "env", "vector"],
    "ident": ["options", "_estimator", "_output", "data", "regression", "hammerstein", "fits"],
    "ident.regression": [
        "kernels",
        "bandwidth",
        "binning",
        "accumulators",
        "_setup",
        "chunked",
        "_state",
        "estimators",
        "convergence",
    ],
    "ident.regression.accumulators": [
        "blocks",
        "_loops",
        "_threads",
        "base",
        "series",
        "grid",
        "exact",
        "binned",
    ],
    "ident.hammerstein": [
        "systems",
        "whiteness",
        "_loops",
        "prediction",
        "solution",
        "white",
        "correlated",
        "linear",
        "comparison",
        "report",
        "_params",
        "_state",
        "bootstrap",
        "_attributes",
        "identifier",
    ],
    "ident.hammerstein.white": ["arma", "correlation", "lags"],
    "ident.hammerstein.correlated": ["_loops", "hatbasis", "arx", "selection", "solve"],
}


def module_name(path: pathlib.Path) -> str:
    """Dotted name below flexarm: "model.arm", "ident" (a package's __init__)."""
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts.pop()
    return ".".join(parts)


def flexarm_imports(path: pathlib.Path) -> set[str]:
    """Dotted names (below flexarm) of the flexarm modules ``path`` imports."""
    package = list(path.relative_to(SRC).parent.parts)
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level >= 1:
                base = package[: len(package) - (node.level - 1)]
                if node.module:
                    found.add(".".join([*base, node.module]))
                else:  # "from . import x": x is a module, or a name of the package
                    for a in node.names:
                        here = SRC.joinpath(*base, a.name)
                        is_module = here.is_dir() or here.with_suffix(".py").is_file()
                        found.add(".".join([*base, a.name] if is_module else base) or "__init__")
            elif node.module and node.module.startswith("flexarm"):
                rest = node.module.split(".")[1:]
                found.add(".".join(rest) if rest else "__init__")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("flexarm."):
                    found.add(a.name.split(".", 1)[1])
    return {name for name in found if name}


def allowed(importer: str, imported: str) -> bool:
    """Whether module ``importer`` may import ``imported`` (dotted, below flexarm).

    Inside a package, the order that counts is the one of the innermost package
    holding both (``WITHIN`` keys may be dotted: ``"ident.hammerstein"``).
    """
    a, b = importer.split("."), imported.split(".")
    if a[0] != b[0]:
        return RANK[b[0]] < RANK[a[0]]
    k = 1  # a[:k] == b[:k]: the innermost package holding both
    while k < min(len(a), len(b)) and a[k] == b[k]:
        k += 1
    order = WITHIN.get(".".join(a[:k]))
    if order is None or k == len(a) or k == len(b):
        return True  # unordered package, or its __init__ (which gathers the package)
    if b[k] not in order:
        return False
    return a[k] not in order or order.index(b[k]) <= order.index(a[k])


MODULES = sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_package_has_a_layer():
    missing = sorted({module_name(p).split(".")[0] for p in MODULES} - set(RANK))
    assert not missing, f"assign a layer in tests/test_layering.py: {missing}"


def test_every_module_of_an_ordered_package_is_placed():
    missing = [
        module_name(p)
        for p in MODULES
        for parts in [module_name(p).split(".")]
        for k in range(1, len(parts))
        if ".".join(parts[:k]) in WITHIN and parts[k] not in WITHIN[".".join(parts[:k])]
    ]
    assert not missing, f"place these in WITHIN in tests/test_layering.py: {missing}"


@pytest.mark.parametrize("path", MODULES, ids=module_name)
def test_no_upward_imports(path):
    name = module_name(path)
    for imported in flexarm_imports(path):
        assert allowed(name, imported), f"{name} imports {imported}: an upward import"


@pytest.mark.parametrize(
    ("importer", "imported", "ok"),
    [
        ("sim.closed_loop", "model.dynamics", True),
        ("model.arm", "sim.loop", False),  # upward across packages
        ("model.arm", "fuzzy", False),  # peers of one layer
        ("model.beam", "model.arm", False),  # upward inside a package
        ("model.arm", "model.beam", True),
        # inside a sub-package, and across its border
        ("model.dynamics._forward", "model.dynamics._dense", True),
        ("model.dynamics._dense", "model.dynamics._forward", False),
        ("model.dynamics", "model.dynamics._forward", True),  # the package gathers it
        ("model.packed", "model.dynamics._forward", True),
        ("model.dynamics._dense", "model.packed", False),
        ("model.dynamics._dense", "model.arrays", True),
        ("cli", "studies.reproduction", True),
        # ordered sub-packages: the innermost package holding both decides
        ("ident.hammerstein.white.lags", "ident.regression.estimators", True),
        ("ident.regression.kernels", "ident.hammerstein.systems", False),
        ("ident.hammerstein.white.lags", "ident.hammerstein.white.correlation", True),
        ("ident.hammerstein.solution", "ident.hammerstein.white.arma", False),
    ],
)
def test_the_rule_itself(importer, imported, ok):
    assert allowed(importer, imported) is ok


@pytest.mark.parametrize("path", [p for p in MODULES if p.stem != "__main__"], ids=module_name)
def test_module_declares_all(path):
    tree = ast.parse(path.read_text())
    targets = [
        t
        for node in tree.body
        if isinstance(node, ast.Assign | ast.AnnAssign)
        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
    ]
    names = {
        n.id
        for t in targets
        for n in (t.elts if isinstance(t, ast.Tuple) else [t])
        if isinstance(n, ast.Name)
    }
    assert "__all__" in names


@pytest.mark.parametrize("path", MODULES, ids=module_name)
def test_modules_are_short_enough_to_read(path):
    n = len(path.read_text().splitlines())
    assert n <= 650, f"{module_name(path)} has {n} lines: split it by concept"
