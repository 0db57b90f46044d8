"""The paper's adaptive law as a fuzzy system, and a surface plot."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from .._validation import check_int, check_option
from ..errors import InvalidTypeError, InvalidValueError
from ..figures import SINGLE_COLUMN, new_figure, styled
from .compiled import evaluate_many
from .sets import LeftShoulder, RightShoulder, Rule, Triangle, Variable
from .system import DEFUZZIFIERS, FuzzySystem

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

__all__ = ["paper_system", "plot_surface"]

FloatArray = NDArray[np.float64]


# -------------------------------------------------------------- the paper system


def paper_system(defuzzifier: str = "centroid") -> FuzzySystem:
    """The paper's fuzzy adaptive law ``lambda(delta1, delta2)`` (module docstring).

    The inputs are the link deformations in m, the output ``lambda`` in
    ``[0, 1]`` is dimensionless. No rule-free region exists (every input pair
    fires at least one rule), so the default (NaN) is never returned for
    finite inputs.

    Parameters
    ----------
    defuzzifier : {"centroid", "bisector", "mean-of-maxima"}
        The paper uses the centroid.
    """
    check_option(defuzzifier, "defuzzifier", "paper_system", DEFUZZIFIERS)
    deltas = [
        Variable(
            name,
            (-5.0, 5.0),  # m
            {
                "N": LeftShoulder(-5.0, 0.0),
                "ZERO": Triangle(-5.0, 0.0, 5.0),
                "P": RightShoulder(0.0, 5.0),
            },
        )
        for name in ("delta1", "delta2")
    ]
    lam = Variable(
        "lambda",
        (0.0, 1.0),
        {
            "ZERO": Triangle(0.0, 0.0, 0.5),
            "PM": Triangle(0.0, 0.5, 1.0),
            "PMAX": Triangle(0.5, 1.0, 1.0),
        },
    )
    table = {
        "N": ("PMAX", "PM", "PMAX"),
        "ZERO": ("PM", "ZERO", "PM"),
        "P": ("PMAX", "PM", "PMAX"),
    }
    rules = tuple(
        Rule((d1, d2), cons)
        for d1, row in table.items()
        for d2, cons in zip(("N", "ZERO", "P"), row, strict=True)
    )
    return FuzzySystem(tuple(deltas), lam, rules, defuzzifier=defuzzifier)


_PAPER_LABELS = {"delta1": "δ1 (m)", "delta2": "δ2 (m)", "lambda": "λ (-)"}
"""Axis labels of the paper's variables: link deformations in m, λ dimensionless."""


@styled
def plot_surface(
    fls: FuzzySystem,
    ax: Axes | None = None,
    n: int = 101,
    *,
    labels: tuple[str, str, str] | None = None,
) -> tuple[Axes, Artist]:
    """Draw the output of a two-input system over its input universes.

    Parameters
    ----------
    fls : FuzzySystem
        A system with exactly two inputs.
    ax : matplotlib Axes, optional
        A 3-D axes gets a surface, a 2-D axes a filled contour (with a colour bar
        labelled with the output). ``None`` makes a new figure with a 3-D axes, one
        column of a paper wide (not registered with pyplot).
    n : int
        Grid points per input.
    labels : tuple of str, optional
        Axis labels of the two inputs and the output, "quantity (unit)". Default:
        the paper's for its variables (``"δ1 (m)"``, ``"δ2 (m)"``, ``"λ (-)"``,
        :func:`paper_system`), else the variables' names.

    Returns
    -------
    (ax, artist)
        The axes and the surface (``Poly3DCollection``) or contour set.
    """
    if not isinstance(fls, FuzzySystem) or len(fls.inputs) != 2:
        raise InvalidValueError(
            "The 'fls' parameter of plot_surface must be a FuzzySystem with two inputs. "
            f"Got {fls!r} instead."
        )
    n = check_int(n, "n", "plot_surface", minimum=2)
    if labels is None:
        names = (fls.inputs[0].name, fls.inputs[1].name, fls.output.name)
        label = [_PAPER_LABELS.get(name, name) for name in names]
        labels = (label[0], label[1], label[2])
    elif (
        not isinstance(labels, tuple | list)
        or len(labels) != 3
        or not all(isinstance(x, str) for x in labels)
    ):
        raise InvalidTypeError(
            "The 'labels' parameter of plot_surface must be three str (x, y, z). "
            f"Got {labels!r} instead."
        )
    g1 = np.linspace(*fls.inputs[0].universe, n)
    g2 = np.linspace(*fls.inputs[1].universe, n)
    x1, x2 = np.meshgrid(g1, g2, indexing="ij")
    try:
        packed = fls.compiled()
    except ValueError:
        z = fls(x1, x2)
    else:
        z = evaluate_many(packed, np.column_stack([x1.ravel(), x2.ravel()])).reshape(x1.shape)
    if ax is None:
        ax = new_figure(SINGLE_COLUMN, 3.0).add_subplot(projection="3d")
    artist: Artist
    if ax.name == "3d":
        ax3d = cast(Any, ax)  # mpl_toolkits' Axes3D carries no type information
        artist = ax3d.plot_surface(x1, x2, z, cmap="viridis", lw=0, antialiased=False)
        ax3d.set_xlabel(labels[0], labelpad=-2)
        ax3d.set_ylabel(labels[1], labelpad=-2)
        ax3d.set_zlabel(labels[2], labelpad=-2)
        ax3d.tick_params(pad=-1)
        ax3d.set_box_aspect(None, zoom=0.9)  # room for the labels in a narrow figure
    else:
        artist = ax.contourf(x1, x2, z, levels=20, cmap="viridis")
        ax.figure.colorbar(artist, ax=ax, label=labels[2])
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
    return ax, artist
