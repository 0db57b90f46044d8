"""Linear binning of kernel sums: the optional approximate grid mode (``binned=r``).

Scheme
------
Grid mode keeps, at each grid point ``x``, the sums
``N(x) = sum_i s_i Y_i K((x - X_i)/h_i)`` and ``D(x) = sum_i s_i K((x - X_i)/h_i)``
(``s_i = 1`` for eq. 14, ``h_i**-1`` for the recursive estimate). With
``binned = r`` (``d = 1``) they are approximated as follows.

1. **Blocks of nearly equal bandwidth.** Samples are taken in consecutive
   blocks of indices ``[a, b)`` chosen so that ``h_a / h_{b-1} <= 1 + rho``
   with ``rho = r**2`` (``b = floor(a q) + 1``, ``q = (1 + rho)**(1/decay)``;
   one block when ``decay = 0``). A block is smoothed with one bandwidth, the
   geometric mean ``h_B`` of its first and last ``h_i``, so that
   ``h_i / h_B`` lies in ``[(1+rho)**-1/2, (1+rho)**1/2]``.
2. **Linear binning.** Each block has its own equispaced bins, width
   ``delta_B = r h_B``, covering the grid widened by ``c h_B + delta_B`` on
   both sides (``c = 1`` for compact kernels, ``c = 9`` for the Gaussian).
   A sample between bin centres ``g_j`` and ``g_{j+1}`` adds ``s_i (1-t)``
   and ``s_i t`` (times ``Y_i`` for ``N``) to them, ``t = (X_i - g_j)/delta_B``.
   Samples outside the bins are dropped.
3. **Evaluation.** When the block is complete, each grid point ``x`` adds
   ``K((x - g_j)/h_B)`` times the two sums of every bin with
   ``|x - g_j| <= c h_B``. The ``u_j`` of consecutive bins are equispaced, so
   the Gaussian needs two ``exp`` per 64 bins (a product recurrence), not one
   per bin.

A block whose bins would outnumber its samples (the first, short blocks) is
added sample by sample with its exact ``h_i``, as in plain grid mode (the
Gaussian cut at ``|u| <= c``).

Error bound
-----------
For one sample and one grid point, with ``u_i = (x - X_i)/h_i``, the binned
weight differs from ``K(u_i)`` by at most

``E = M1 (sqrt(1 + rho) - 1) + I(r) + tau``

* **bandwidth** (step 1): ``|K(u) - K(a u)| <= M1 |a - 1| / min(1, a)`` with
  ``M1 = sup |v K'(v)|`` (mean value theorem; ``K`` absolutely continuous):
  ``2/e`` (Gaussian), ``3/2`` (Epanechnikov), ``1`` (triangular);
* **interpolation** (step 2): linear interpolation of ``X -> K((x - X)/h_B)``
  over a bin errs by at most ``delta**2/8 sup|f''|`` plus ``J delta/4`` for a
  kink where ``f'`` jumps by ``J``. In units of ``h_B``:
  ``I(r) = r**2/8`` (Gaussian, ``sup|K''| = 1``), ``3 r**2/16 + 3 r/8``
  (Epanechnikov, ``K'' = -3/2``, kinks ``J = 3/2`` at ``|u| = 1``),
  ``r/2`` (triangular, at most one kink per bin, ``J <= 2``);
* **truncation and recurrence** (Gaussian only): a dropped sample or bin lies
  beyond ``c h_B >= c h_i / sqrt(1 + rho)``, so its weight is below
  ``exp(-c**2 / (2 (1 + rho)))`` (``< 1e-14`` for ``c = 9``); the product
  recurrence adds a relative rounding error below ``1e-12``:
  ``tau = exp(-c**2 / (2 (1 + rho))) + 1e-12``.

The uniform kernel is discontinuous (a sample one bin from its edge can move
a whole weight), so it cannot be binned.

Only samples near ``x`` can err by more than ``tau``: a compact kernel's
exact and binned weights both vanish beyond ``|x - X_i| > (1 + r) h_B``, and
a Gaussian sample beyond ``c h_B + delta`` has binned weight 0 and exact weight
below ``tau``. Such a sample's bins lie within ``(c + 2 r) h_B`` of ``x``, so
with ``S_near(x)``, ``A_near(x)`` the binned ``s_i`` and ``s_i |Y_i|`` in
those bins (accumulated alongside the sums), and ``S``, ``A`` the totals
over all samples (exact blocks included: they only risk the Gaussian cut),

``|D_binned(x) - D(x)| <= E S_near(x) + tau S =: eD``,
``|N_binned(x) - N(x)| <= E A_near(x) + tau A =: eN``

(``tau = 0`` for compact kernels), and for the estimate ``m = N / D``
(``m_b - m = (dN - m dD) / D_b``, solved for ``|m_b - m|``)

``|m_binned(x) - m(x)| <= (eN + |m_binned(x)| eD) / (D_binned(x) - eD)``

wherever ``D_binned(x) > eD``. The tests check all three against exact grid
mode.

These bounds hold in exact arithmetic; the estimator's
``sum_error_bounds`` adds ``4 (2 n + J + 16) 2**-53`` times ``S`` (``A``) for
the rounding of the sums (``n`` samples; ``J`` bins in the open block; a
closed block never has more bins than samples, except the single block of
``decay = 0``, which is the open one).
"""

from __future__ import annotations

import math

import numba as nb

from ..._types import F64
from ..options import BINNABLE
from .kernels import kernel_profile

__all__ = [
    "BINNABLE",
    "GAUSS_RADIUS",
    "bin_samples",
    "block_end",
    "far_error",
    "flush_bins",
    "interpolation_error",
    "per_weight_error",
    "radius",
]


#: Truncation radius of the Gaussian in binned mode, in units of ``h_B``.
GAUSS_RADIUS = 9.0
_NO_END = 2**62  # block end when decay = 0 (one block)
_RUN = 64  # Gaussian recurrence restarted every _RUN bins
_ROUNDING = 1e-12  # bound on the recurrence's relative rounding error (2.4e-13 for _RUN = 64)

# sup |v K'(v)|: the bandwidth term
_M1 = {"gaussian": 2.0 / math.e, "epanechnikov": 1.5, "triangular": 1.0}


def interpolation_error(kernel: str, r: float) -> float:
    """Bound on the linear-interpolation error of ``K`` over one bin of width ``r`` (units of h)."""
    if kernel == "gaussian":
        return r * r / 8.0
    if kernel == "epanechnikov":
        return 3.0 * r * r / 16.0 + 3.0 * r / 8.0
    return r / 2.0  # triangular


def radius(kernel: str) -> float:
    """Window half-width ``c`` in units of ``h_B``."""
    return GAUSS_RADIUS if kernel == "gaussian" else 1.0


def far_error(kernel: str, r: float) -> float:
    """``tau``: the bound on the error of a weight far from ``x`` (0 for compact kernels)."""
    if kernel != "gaussian":
        return 0.0
    return math.exp(-(GAUSS_RADIUS**2) / (2.0 * (1.0 + r * r))) + _ROUNDING


def per_weight_error(kernel: str, r: float, decay: float) -> float:
    """The bound ``E`` on the error of one binned weight (see the module docstring).

    Parameters
    ----------
    kernel : str
        One of :data:`BINNABLE`.
    r : float
        Relative bin width ``delta / h`` (dimensionless).
    decay : float
        Bandwidth decay; ``0`` means one block and no bandwidth term.

    Returns
    -------
    float
        ``E`` (dimensionless; a weight is at most 1).

    Examples
    --------
    >>> round(per_weight_error("gaussian", 0.1, 0.0), 6)
    0.00125
    """
    rho = r * r
    bandwidth_term = _M1[kernel] * (math.sqrt(1.0 + rho) - 1.0) if decay > 0.0 else 0.0
    return bandwidth_term + interpolation_error(kernel, r) + far_error(kernel, r)


def block_end(start: int, r: float, decay: float) -> int:
    """One past the last index of the block starting at 1-based index ``start``.

    ``h_start / h_{end-1} = ((end-1)/start)**decay <= 1 + r**2``.
    """
    if decay <= 0.0:
        return _NO_END
    q = (1.0 + r * r) ** (1.0 / decay)
    top = math.floor(start * q)
    return int(min(max(top, start) + 1, _NO_END))


@nb.njit(cache=True)
def bin_samples(
    x: F64,
    y: F64,
    start: int,
    bw: float,
    decay: float,
    recursive: bool,
    origin: float,
    delta: float,
    cw: F64,
    sw: F64,
    aw: F64,
    sums: F64,
) -> None:  # pragma: no cover - compiled
    """Linear binning of samples ``start+1, start+2, ...`` into ``cw`` (``s_i``),
    ``sw`` (``s_i Y_i``) and ``aw`` (``s_i |Y_i|``).

    ``sums[0] += s_i`` and ``sums[1] += s_i |Y_i|`` for every sample, binned or
    dropped (the bound's ``S`` and ``A``).
    """
    last = cw.shape[0] - 1
    for k in range(x.shape[0]):
        s = 1.0
        if recursive:
            s = 1.0 / (bw * float(start + k + 1) ** (-decay))
        yk = y[k]
        sums[0] += s
        sums[1] += s * abs(yk)
        t = (x[k] - origin) / delta
        if not (t >= 0.0 and t <= last):
            continue
        j = int(t)
        if j >= last:
            j = last - 1
        f = t - j
        a = s * (1.0 - f)
        b = s * f
        cw[j] += a
        cw[j + 1] += b
        sw[j] += a * yk
        sw[j + 1] += b * yk
        aw[j] += a * abs(yk)
        aw[j + 1] += b * abs(yk)


@nb.njit(cache=True)
def flush_bins(
    code: int,
    gs: F64,
    origin: float,
    delta: float,
    hb: float,
    c: float,
    cw: F64,
    sw: F64,
    aw: F64,
    num: F64,
    den: F64,
    near: F64,
) -> None:  # pragma: no cover - compiled
    """Add ``sum_j K((x - g_j)/h_B) [sw_j, cw_j]`` over ``|x - g_j| <= c h_B`` at each grid ``x``.

    ``g_j = origin + j delta``. Along the bins ``u_j = u_0 - j r`` is
    equispaced (``r = delta / h_B``), so the Gaussian is evaluated by the
    recurrence ``w_{j+1} = w_j p_j``, ``p_{j+1} = p_j exp(-r**2)`` (two ``exp``
    per run), restarted every ``_RUN`` bins: each weight then carries a
    relative rounding error below ``_ROUNDING`` (``(RUN**2/2 + 2 RUN) 2**-53``).

    ``near[0, k]`` and ``near[1, k]`` receive the plain sums of ``cw`` and
    ``aw`` over the bins with ``|x - g_j| <= (c + 2 r) h_B``: every sample whose
    binned weight at ``x`` may err by more than ``tau`` lies in them.
    """
    last = cw.shape[0] - 1
    r = delta / hb
    q = math.exp(-r * r)
    for k in range(gs.shape[0]):
        x = gs[k]
        nlo = max(0, math.ceil((x - (c + 2.0 * r) * hb - origin) / delta))
        nhi = min(last, math.floor((x + (c + 2.0 * r) * hb - origin) / delta))
        ns = 0.0
        na = 0.0
        for j in range(nlo, nhi + 1):
            ns += cw[j]
            na += aw[j]
        near[0, k] += ns
        near[1, k] += na
        jlo = max(0, math.ceil((x - c * hb - origin) / delta))
        jhi = min(last, math.floor((x + c * hb - origin) / delta))
        if jhi < jlo:
            continue
        sn = 0.0
        sd = 0.0
        if code == 0:
            j = jlo
            while j <= jhi:
                u = (x - (origin + j * delta)) / hb
                w = math.exp(-0.5 * u * u)
                p = math.exp(u * r - 0.5 * r * r)
                stop = min(jhi, j + _RUN - 1)
                while True:
                    sn += w * sw[j]
                    sd += w * cw[j]
                    if j == stop:
                        break
                    w *= p
                    p *= q
                    j += 1
                j += 1
        else:
            for j in range(jlo, jhi + 1):
                w = kernel_profile(code, (x - (origin + j * delta)) / hb)
                sn += w * sw[j]
                sd += w * cw[j]
        num[k] += sn
        den[k] += sd
