"""Your own controller by name: ``"module:factory"``.

A scenario file's ``[controller] kind = "mypkg.mymod:make"`` and
``flexarm simulate --controller mypkg.mymod:make`` build the law
``make(arm, **options)``: ``module`` is imported (from the scenario file's
directory, the current directory or ``sys.path``), ``factory`` is looked up in
it and called with the arm and the controller table's other keys as keyword
arguments, and must return a :class:`flexarm.control.controllers.Controller`
(usually a :class:`~flexarm.control.controllers.CompiledController` around a
``numba.njit`` law; ``examples/my_controller.py`` is one).

Every failure is one line naming the spec: the module cannot be imported, has
no such attribute, the attribute is not callable, rejects the arguments, or
returns something else than a controller. This module loads no compiled code
until a controller is built (the command line's parser reads :data:`FACTORY_SPEC`).
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os
import re
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from ..errors import InvalidTypeError, InvalidValueError
from ..model.plant import Plant

if TYPE_CHECKING:
    from .controllers import Controller

__all__ = ["FACTORY_SPEC", "call_factory", "is_factory_spec", "load_factory"]

FACTORY_SPEC = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*$")
"""``module:factory``: a dotted module name, a colon, an attribute name."""

Factory = Callable[..., object]


def is_factory_spec(value: object) -> bool:
    """Whether ``value`` is a ``"module:factory"`` string (not a built-in controller name).

    Examples
    --------
    >>> is_factory_spec("mypkg.mymod:make"), is_factory_spec("pd"), is_factory_spec(3)
    (True, False, False)
    """
    return isinstance(value, str) and FACTORY_SPEC.match(value) is not None


def _import(name: str, search: Sequence[str | os.PathLike[str]]) -> object:
    """Import module ``name``; a top-level package not on ``sys.path`` is looked for
    in ``search`` (without changing ``sys.path``)."""
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        top = name.split(".")[0]
        if exc.name != top or not search:
            raise
        spec = importlib.machinery.PathFinder.find_spec(top, [os.fspath(p) for p in search])
        if spec is None or spec.loader is None:
            raise
        module = importlib.util.module_from_spec(spec)
        sys.modules[top] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[top]
            raise
        return importlib.import_module(name)


def load_factory(spec: str, search: Sequence[str | os.PathLike[str]] = ()) -> Factory:
    """The callable that ``spec`` (``"module:factory"``) names.

    Parameters
    ----------
    spec : str
        ``"mypkg.mymod:make"``.
    search : sequence of path
        Directories in which to look for the module's top-level package when it
        is not importable from ``sys.path`` (tried in order).

    Raises
    ------
    ValueError
        A malformed spec, a module that cannot be imported (or fails to), or a
        missing attribute.
    TypeError
        An attribute that is not callable.
    """
    if not is_factory_spec(spec):
        raise InvalidValueError(
            f"A controller factory must be 'module:factory' (e.g. 'mypkg.mymod:make'). "
            f"Got {spec!r} instead."
        )
    module_name, attr = spec.split(":")
    try:
        module = _import(module_name, search)
    except ModuleNotFoundError as exc:
        raise InvalidValueError(
            f"cannot import module '{module_name}' of controller factory '{spec}': {exc}"
        ) from None
    except Exception as exc:
        raise InvalidValueError(
            f"importing module '{module_name}' of controller factory '{spec}' failed: "
            f"{type(exc).__name__}: {exc}"
        ) from None
    if not hasattr(module, attr):
        raise InvalidValueError(
            f"module '{module_name}' has no attribute '{attr}' (controller factory '{spec}')"
        )
    factory = getattr(module, attr)
    if not callable(factory):
        raise InvalidTypeError(
            f"controller factory '{spec}' is not callable. Got {type(factory).__name__} instead."
        )
    return factory  # type: ignore[no-any-return]


def call_factory(
    factory: Factory, spec: str, arm: Plant, options: Mapping[str, object] | None = None
) -> Controller:
    """``factory(arm, **options)``, checked to be a :class:`Controller`.

    Parameters
    ----------
    factory : callable
        From :func:`load_factory`.
    spec : str
        Its name, for messages.
    arm : FlexibleArm
        The plant, the first positional argument.
    options : mapping, optional
        Keyword arguments (a scenario's controller table without ``kind``).

    Raises
    ------
    TypeError
        The factory rejects the arguments, or returns something else than a
        flexarm Controller.
    ValueError
        The factory rejects a value (its message is passed on), or fails with
        another error.
    """
    from .controllers import Controller  # Numba: only when a controller is built

    kwargs = dict(options or {})
    try:
        controller = factory(arm, **kwargs)
    except TypeError as exc:
        if "argument" in str(exc) and "parameter" not in str(exc):
            given = ", ".join(kwargs) or "no options"
            raise InvalidTypeError(
                f"controller factory '{spec}' rejected its arguments (the arm and {given}): {exc}"
            ) from None
        raise
    except ValueError:
        raise
    except Exception as exc:
        raise InvalidValueError(
            f"controller factory '{spec}' failed: {type(exc).__name__}: {exc}"
        ) from None
    if not isinstance(controller, Controller):
        raise InvalidTypeError(
            f"controller factory '{spec}' must return a flexarm Controller (e.g. a "
            f"CompiledController). Got {type(controller).__name__} instead."
        )
    return controller
