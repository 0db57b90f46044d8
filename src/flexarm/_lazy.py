"""Lazy attributes for packages (PEP 562), so that importing a package is cheap.

``import flexarm`` loads no Numba, no SciPy solver and no Matplotlib: a package's
public names and subpackages are imported on first access
(``flexarm.FlexibleArm``, ``flexarm.ident``), as SciPy does.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from types import ModuleType

__all__ = ["attach"]


def attach(
    package: str, submodules: Sequence[str], names: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """``(__getattr__, __dir__, __all__)`` for ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    submodules : sequence of str
        Subpackages and modules reachable as attributes (``flexarm.ident``).
    names : mapping of str to str
        Public name -> the module (relative to ``package``) that defines it.
    """
    subs = frozenset(submodules)
    public = sorted({*subs, *names})

    def __getattr__(name: str) -> object:
        if name in names:
            module: ModuleType = importlib.import_module(f"{package}.{names[name]}")
            return getattr(module, name)
        if name in subs:
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return public

    return __getattr__, __dir__, [n for n in public if n not in subs]
