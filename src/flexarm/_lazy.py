"""Lazy attributes for packages (PEP 562), so that importing a package is cheap.

``import flexarm`` loads no Numba, no SciPy solver and no Matplotlib: a package's
public names and subpackages are imported on first access
(``flexarm.FlexibleArm``, ``flexarm.ident``), as SciPy does.

A package lists its public names once, as what type checkers see::

    __getattr__, __dir__, __all__ = attach(__name__)

    if TYPE_CHECKING:
        from .sensors import TipSensor as TipSensor

and :func:`attach` reads that block of the package's source for the names and
the modules that define them; its public modules (no leading underscore) are its
attributes too, or those it names.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import ModuleType

__all__ = ["attach", "declared_names"]


def declared_names(source: str, package: str) -> dict[str, str]:
    """Public name -> module (relative to ``package``) of each
    ``from .module import name as name`` under the top-level ``if TYPE_CHECKING:``
    of ``source``, the package's ``__init__``."""
    names: dict[str, str] = {}
    for node in ast.parse(source).body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for imp in node.body:
            if not (isinstance(imp, ast.ImportFrom) and imp.level == 1 and imp.module):
                raise ImportError(
                    f"{package}: the TYPE_CHECKING block may hold only "
                    f"'from .module import name as name' lines, not {ast.unparse(imp)!r}"
                )
            for alias in imp.names:
                if alias.asname != alias.name:
                    raise ImportError(
                        f"{package}: {ast.unparse(imp)!r} must re-export as "
                        f"'{alias.name} as {alias.name}'"
                    )
                names[alias.name] = imp.module
    return names


def attach(
    package: str,
    submodules: Sequence[str] | None = None,
    names: Mapping[str, str] | None = None,
) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """``(__getattr__, __dir__, __all__)`` for ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    submodules : sequence of str, optional
        Subpackages and modules reachable as attributes (``flexarm.ident``); by
        default every module and subpackage of ``package`` whose name has no
        leading underscore.
    names : mapping of str to str, optional
        Public name -> the module (relative to ``package``) that defines it; by
        default those of the package's ``if TYPE_CHECKING:`` block
        (:func:`declared_names`).
    """
    pkg = sys.modules[package]
    if names is None:
        if pkg.__file__ is None:  # pragma: no cover - a namespace package has no __init__
            raise ImportError(f"{package} has no __init__ to read its names from")
        names = declared_names(Path(pkg.__file__).read_text(encoding="utf-8"), package)
    if submodules is None:
        found = pkgutil.iter_modules(pkg.__path__)
        submodules = [info.name for info in found if not info.name.startswith("_")]
    subs = frozenset(submodules)
    public = sorted({*subs, *names})
    defined = dict(names)

    def __getattr__(name: str) -> object:
        if name in defined:
            module: ModuleType = importlib.import_module(f"{package}.{defined[name]}")
            return getattr(module, name)
        if name in subs:
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return public

    return __getattr__, __dir__, [n for n in public if n not in subs]
