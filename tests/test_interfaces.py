"""Interfaces between the layers: typed, keyword-built, lazily imported.

* NamedTuples of arrays handed to compiled code are built by keyword (a swapped
  field cannot be written silently);
* the public signatures of the simulator, the controllers, the sensors and the
  results name their types (no ``Any``);
* ``import flexarm`` loads no Numba, no SciPy and no Matplotlib, and the
  subpackages are reachable as attributes.
"""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

import pytest

SRC = pathlib.Path(__file__).resolve().parents[1] / "src" / "flexarm"
MODULES = sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def _named_tuples() -> set[str]:
    names = set()
    for path in MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and any(
                isinstance(b, ast.Name) and b.id == "NamedTuple" for b in node.bases
            ):
                names.add(node.name)
    return names


NAMED_TUPLES = _named_tuples()


def test_the_named_tuples_are_found():
    assert {"ArmArrays", "Workspace", "SensorArrays", "LoopState", "CompiledFuzzySystem"} <= (
        NAMED_TUPLES
    )


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_named_tuples_are_built_by_keyword(path):
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call):
            f = node.func
            name = (
                f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""
            )
            if name in NAMED_TUPLES:
                assert not node.args, f"{path.name}:{node.lineno}: {name}(...) built by position"


PUBLIC = [
    "figures.py",
    "sim/closed_loop.py",
    "sim/open_loop.py",
    "sim/results.py",
    "control/controllers.py",
    "control/adaptive.py",
    "sensing/sensors.py",
    "sim/animation.py",
    "control/interop.py",
    "control/custom.py",
    "envs/config.py",
    "envs/env.py",
    "envs/vector.py",
    *sorted(
        str(p.relative_to(SRC))
        for p in (SRC / "studies").rglob("*.py")
        if p.name != "__init__.py" and not p.name.startswith("_")
    ),
]


def _annotations(fn: ast.FunctionDef) -> list[ast.expr]:
    args = fn.args
    every = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
    found = [a.annotation for a in every if a is not None and a.annotation is not None]
    return [*found, fn.returns] if fn.returns is not None else found


@pytest.mark.parametrize("module", PUBLIC)
def test_public_signatures_have_no_any(module):
    tree = ast.parse((SRC / module).read_text())
    scopes = [tree, *(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name[0] != "_")]
    bad = []
    for scope in scopes:
        for item in scope.body:
            if isinstance(item, ast.FunctionDef) and not item.name.startswith("_"):
                bad += [f"{item.name}: {ast.unparse(a)}" for a in _annotations(item)]
            elif isinstance(item, ast.AnnAssign) and scope is not tree:
                bad.append(f"{ast.unparse(item.target)}: {ast.unparse(item.annotation)}")
    assert not [b for b in bad if "Any" in b.split(": ", 1)[1]], bad


def _run(code: str) -> str:
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return res.stdout.strip()


def test_import_flexarm_loads_no_numba_scipy_or_matplotlib():
    out = _run(
        "import sys, flexarm\n"
        "print(sorted(m for m in ('numba', 'scipy', 'matplotlib') if m in sys.modules))"
    )
    assert out == "[]"


def test_the_command_line_parser_loads_nothing_heavy():
    """``flexarm --help`` builds every command's parser without Numba, SciPy or
    Matplotlib: commands import the library when they run."""
    out = _run(
        "import sys\n"
        "from flexarm.cli import build_parser\n"
        "build_parser().format_help()\n"
        "print(sorted(m for m in ('numba', 'scipy', 'matplotlib') if m in sys.modules))"
    )
    assert out == "[]"


def test_subpackages_and_names_load_on_first_access():
    out = _run(
        "import sys, flexarm\n"
        "assert 'flexarm.ident' not in sys.modules\n"
        "est = flexarm.ident.SemiRecursiveKernelRegression\n"
        "arm = flexarm.FlexibleArm.paper()\n"
        "print(est.__name__, arm.n_dof, flexarm.simulate.__module__,"
        " flexarm.simulate_open_loop.__module__, 'numba' in sys.modules)"
    )
    assert out == (
        "SemiRecursiveKernelRegression 4 flexarm.sim.closed_loop flexarm.sim.open_loop True"
    )


def test_building_an_arm_needs_no_numba():
    """Building an arm and its NumPy reference load no Numba; the default backend of
    its dynamics (the packed kernels) loads it on first use."""
    out = _run(
        "import sys, flexarm\n"
        "arm = flexarm.FlexibleArm.paper(n_modes=2)\n"
        "arm.mass_matrix(arm.arrays.stiffness * 0, backend='numpy')\n"
        "print('numba' in sys.modules)"
    )
    assert out == "False"


def test_dir_lists_the_lazy_names():
    import flexarm

    for name in ("FlexibleArm", "simulate", "simulate_open_loop", "ident", "sim", "model"):
        assert name in dir(flexarm)
    with pytest.raises(AttributeError, match="no attribute 'nonesuch'"):
        flexarm.nonesuch  # noqa: B018


def test_the_lazy_names_are_read_from_the_type_checking_block():
    from flexarm._lazy import declared_names

    source = (
        "if TYPE_CHECKING:\n"
        "    from .a import B as B\n"
        "    from .c.d import e as e, F as F\n"
        "from .g import H\n"  # run at import time: not a lazy name
    )
    assert declared_names(source, "pkg") == {"B": "a", "e": "c.d", "F": "c.d"}
    with pytest.raises(ImportError, match=r"'from \.x import Y' must re-export as 'Y as Y'"):
        declared_names("if TYPE_CHECKING:\n    from .x import Y\n", "pkg")
    with pytest.raises(ImportError, match="may hold only"):
        declared_names("if TYPE_CHECKING:\n    import numpy as np\n", "pkg")


def test_a_lazy_package_without_a_list_of_submodules_exposes_its_public_modules():
    import flexarm.ident

    modules = {p.stem for p in (SRC / "ident").glob("*.py") if p.name != "__init__.py"}
    public = {m for m in modules if not m.startswith("_")}
    assert public and public <= set(dir(flexarm.ident))
    assert {"_estimator", "_output"} <= modules
    assert (modules - public).isdisjoint(dir(flexarm.ident))
    assert public.isdisjoint(flexarm.ident.__all__)  # modules, not public names
