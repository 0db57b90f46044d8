"""``flexarm.ident`` loads lazily: importing it (or the ``identify`` command's modules)
brings in no Numba, SciPy or Matplotlib; every public name still resolves on access."""

from __future__ import annotations

import subprocess
import sys

import pytest

import flexarm.ident

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
        "assert 'flexarm.ident.regression' not in sys.modules\n"
        "assert 'flexarm.studies.joint_identification' not in sys.modules"
    )
    assert loaded_after(code) == []


@pytest.mark.parametrize("name", flexarm.ident.__all__)
def test_every_public_name_resolves(name):
    assert getattr(flexarm.ident, name) is not None
    assert name in dir(flexarm.ident)


def test_subpackages_are_attributes():
    assert flexarm.ident.accumulators.ExactSamples.mode == "exact"
    assert "fits" in dir(flexarm.ident)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = flexarm.ident.nope


def test_option_names_match_their_implementations():
    from flexarm.ident import binning, convergence, kernels, options

    assert kernels.KERNELS is options.KERNELS and binning.BINNABLE is options.BINNABLE
    assert tuple(convergence.FUNCTIONS) == options.REGRESSION_FUNCTIONS
    assert convergence.DISTRIBUTIONS is options.DISTRIBUTIONS
