"""``flexarm.ident`` loads lazily: importing it (or the ``identify`` command's modules)
brings in no Numba, SciPy or Matplotlib; every public name still resolves on access."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

import flexarm.ident
import flexarm.ident.hammerstein
import flexarm.ident.regression

HEAVY = ("numba", "scipy", "matplotlib")


def loaded_after(code: str) -> list[str]:
    """The heavy modules present in a fresh interpreter after running ``code``."""
    probe = f"import sys\n{code}\nprint(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    ).stdout
    return eval(out.strip().splitlines()[-1])  # a printed list of names


def test_import_flexarm_ident_is_light():
    code = (
        "import flexarm, flexarm.ident\n"
        "flexarm.ident.KERNELS, flexarm.ident.load_columns, flexarm.ident.Silverman\n"
        "flexarm.ident.silverman_bandwidth([0.0, 1.0, 3.0])"
    )
    assert loaded_after(code) == []


def test_an_estimator_loads_on_first_use():
    code = "import flexarm\nflexarm.ident.SemiRecursiveKernelRegression().fit([0.0, 1.0], [1, 2])"
    assert "numba" in loaded_after(code)


def test_identify_command_modules_are_light():
    """The command modules import the estimators inside the functions that run them."""
    code = (
        "import pathlib, types, flexarm\n"
        "pkg = types.ModuleType('flexarm.cli')\n"
        "pkg.__path__ = [str(pathlib.Path(flexarm.__file__).parent / 'cli')]\n"
        "sys.modules['flexarm.cli'] = pkg\n"
        "import flexarm.cli.identify as m\n"
        "from flexarm.cli._common import Parser\n"
        "p = Parser(prog='flexarm')\n"
        "m.add_parser(p.add_subparsers(parser_class=Parser))\n"
        "assert 'flexarm.ident.regression.estimators' not in sys.modules\n"
        "assert 'flexarm.ident.hammerstein.identifier' not in sys.modules\n"
        "assert 'flexarm.studies.joint_identification' not in sys.modules"
    )
    assert loaded_after(code) == []


def declared(package: ModuleType) -> dict[str, tuple[str, str]]:
    """What type checkers see of a lazy package: name -> (module, name) of each
    ``from .module import name as name`` under ``if TYPE_CHECKING``."""
    tree = ast.parse(Path(package.__file__).read_text())
    found = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom) and imp.level == 1
                for alias in imp.names:
                    found[alias.asname] = (f"{package.__name__}.{imp.module}", alias.name)
    return found


PACKAGES = [flexarm.ident, flexarm.ident.regression, flexarm.ident.hammerstein]


@pytest.mark.parametrize("package", PACKAGES, ids=lambda m: m.__name__)
def test_the_lazy_names_are_the_declared_ones(package):
    assert sorted(declared(package)) == package.__all__


@pytest.mark.parametrize(
    ("package", "name"),
    [(pkg, name) for pkg in PACKAGES for name in pkg.__all__],
    ids=lambda v: getattr(v, "__name__", v),
)
def test_every_public_name_resolves(package, name):
    """Each lazy name is the object its declared module defines under that name."""
    module, defined = declared(package)[name]
    obj = getattr(package, name)
    assert obj is getattr(importlib.import_module(module), defined)
    assert getattr(obj, "__name__", name) == name  # a class or function is the one named
    assert name in dir(package)


def test_the_families_export_the_same_objects_as_flexarm_ident():
    for package in PACKAGES[1:]:
        for name in package.__all__:
            if name in flexarm.ident.__all__:
                assert getattr(package, name) is getattr(flexarm.ident, name), name


def test_subpackages_are_attributes():
    assert flexarm.ident.regression.accumulators.ExactSamples.mode == "exact"
    assert flexarm.ident.hammerstein.white.lags.WHITE_MAX_ORDER == 4
    assert "fits" in dir(flexarm.ident) and "correlated" in dir(flexarm.ident.hammerstein)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = flexarm.ident.nope
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = flexarm.ident.regression.nope


def test_option_names_match_their_implementations():
    from flexarm.ident import options
    from flexarm.ident.regression import binning, convergence, kernels

    assert kernels.KERNELS is options.KERNELS and binning.BINNABLE is options.BINNABLE
    assert tuple(convergence.FUNCTIONS) == options.REGRESSION_FUNCTIONS
    assert convergence.DISTRIBUTIONS is options.DISTRIBUTIONS
