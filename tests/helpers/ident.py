"""What the identification tests share: the eq. 14 oracle, data, accumulator setups, files.

The oracle is eq. 14 written again in NumPy, independently of the compiled code:
each kernel's profile, the per-sample bandwidths ``h_i = bandwidth i**-decay``, the
product kernel over the dimensions and, for the fully recursive estimate, the
Devroye–Wagner weights ``h_i**-d``.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import lfilter

from flexarm.ident import KERNELS
from flexarm.ident.regression.accumulators import Smoothing

__all__ = [
    "PROFILES",
    "ar1",
    "arx_free_run",
    "column_files",
    "eq14",
    "fed",
    "files_fixture",
    "multisine",
    "regression_data",
    "same_state",
    "samples_fixture",
    "saturation_samples",
    "scaled",
    "silverman",
    "smoothing",
    "sums14",
    "sweep",
]

#: The one-dimensional kernel profiles, written out again here.
PROFILES = {
    "gaussian": lambda u: np.exp(-(u**2) / 2),
    "epanechnikov": lambda u: np.where(np.abs(u) <= 1, 0.75 * (1 - u**2), 0.0),
    "uniform": lambda u: np.where(np.abs(u) <= 1, 0.5, 0.0),
    "triangular": lambda u: np.where(np.abs(u) <= 1, 1 - np.abs(u), 0.0),
}


def sums14(q, X, y, bandwidth, decay, kernel, recursive=False):
    """``N(q)``, ``D(q)`` of eq. 14 (or the Devroye–Wagner weights) by NumPy, any ``d``."""
    q = np.asarray(q, float).reshape(len(q), -1)
    X = np.asarray(X, float).reshape(len(X), -1)
    i = np.arange(1, len(X) + 1, dtype=float)
    h = np.broadcast_to(np.asarray(bandwidth, float), (X.shape[1],))[None, :] * (
        i[:, None] ** -decay
    )
    K = np.prod(PROFILES[kernel]((q[:, None, :] - X[None, :, :]) / h[None, :, :]), axis=2)
    if recursive:
        K = K / np.prod(h, axis=1)[None, :]
    return K @ y, K.sum(axis=1)


def eq14(q, X, y, bandwidth, decay, kernel, recursive=False):
    """Eq. 14 (or the Devroye–Wagner estimate) at the rows of ``q``; NaN where no weight."""
    num, den = sums14(q, X, y, bandwidth, decay, kernel, recursive=recursive)
    out = np.full(num.shape, np.nan)
    out[den > 0] = num[den > 0] / den[den > 0]
    return out


def regression_data(n, d=1, seed=0):
    """``X`` uniform on the unit cube (shape ``(n,)`` for ``d = 1``, else ``(n, d)``) and
    ``y = sin(2 pi X_1) + X_d**2 + 0.1 noise``."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 1, (n, d)) if d > 1 else rng.uniform(0, 1, n)
    Xm = X.reshape(n, -1)
    y = np.sin(2 * np.pi * Xm[:, 0]) + Xm[:, -1] ** 2 + 0.1 * rng.standard_normal(n)
    return X, y


def smoothing(kernel="epanechnikov", bw=(0.3,), decay=0.2, grid=None, **kw):
    """A :class:`Smoothing` for an accumulator (a callable ``kernel`` gets code -1)."""
    return Smoothing(
        owner="test",
        kernel=kernel,
        code=KERNELS.index(kernel) if isinstance(kernel, str) else -1,
        bandwidth=np.asarray(bw, dtype=np.float64),
        decay=decay,
        recursive=kw.pop("recursive", False),
        grid=None if grid is None else np.asarray(grid, dtype=np.float64).reshape(len(grid), -1),
        **kw,
    )


def fed(acc, X, y, cuts=()):
    """``acc`` after the samples in chunks split at ``cuts`` (empty chunks left out)."""
    for a, b in itertools.pairwise([0, *cuts, len(y)]):
        if b > a:
            acc.add_chunk(np.ascontiguousarray(X[a:b]), y[a:b])
    return acc


def same_state(a, b):
    """Two accumulators' states are equal, array for array, bit for bit."""
    sa, sb = a.state(), b.state()
    assert sa.keys() == sb.keys()
    for k in sa:
        np.testing.assert_array_equal(sa[k], sb[k], err_msg=k)


def silverman(x, n=None, factor=1.0, decay=0.2):
    """Silverman (1986, eq. 3.31) per column, anchored at the last of ``n`` samples:
    ``h_1 = factor 0.9 min(sd, IQR/1.34) n**(decay - 1/(d+4))``."""
    x = np.asarray(x, float).reshape(len(x), -1)
    n = len(x) if n is None else n
    d = x.shape[1]
    out = []
    for j in range(d):
        col = x[:, j]
        iqr = np.subtract(*np.percentile(col, [75, 25]))
        s = min(col.std(ddof=1), iqr / 1.34)
        out.append(factor * 0.9 * s * n ** (decay - 1 / (d + 4)))
    return np.array(out)


def saturation_samples(n=400, seed=7):
    """``x`` uniform on [-1, 1] and ``y = clip(1.5 x, -0.75, 0.75) + 0.05 noise``."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1, 1, n)
    y = np.clip(1.5 * x, -0.75, 0.75) + 0.05 * rng.standard_normal(n)
    return x, y


def column_files(directory: Path, x, y):
    """The samples as data files: ``csv`` (``time,u,w``), ``txt`` (two columns, a comment
    line), ``npz`` (arrays ``u``, ``w``) and ``table`` (one array, columns t, u, w)."""
    t = np.arange(len(x))
    csv = directory / "d.csv"
    lines = ["time,u,w"] + [
        f"{a},{b!r},{c!r}" for a, b, c in zip(t, x.tolist(), y.tolist(), strict=True)
    ]
    csv.write_text("\n".join(lines) + "\n")
    txt = directory / "d.txt"
    txt.write_text(
        "# a comment line\n"
        + "\n".join(f"{b!r}  {c!r}" for b, c in zip(x.tolist(), y.tolist(), strict=True))
    )
    npz = directory / "d.npz"
    np.savez(npz, u=x, w=y)
    table = directory / "t.npz"
    np.savez(table, np.column_stack([t, x, y]))
    return {"csv": csv, "txt": txt, "npz": npz, "table": table}


@pytest.fixture(name="samples", scope="module")
def samples_fixture():
    """The fixture ``samples``: :func:`saturation_samples` (400 of them)."""
    return saturation_samples()


@pytest.fixture(name="files")
def files_fixture(tmp_path, samples):
    """The fixture ``files``: the ``samples`` as data files (:func:`column_files`)."""
    return column_files(tmp_path, *samples)


# ------------------------------------------------------------ inputs of the Hammerstein tests


def scaled(x):
    """``x`` mapped so that its 1 % and 99 % quantiles sit at -2 and 2."""
    lo, hi = np.quantile(x, [0.01, 0.99])
    return (x - 0.5 * (lo + hi)) * 4.0 / (hi - lo)


def sweep(n, rng):
    """Linear chirp from 0.001 to 0.4 cycles/sample over the record (random start phase)."""
    k = np.arange(n)
    phase = 2 * np.pi * (0.001 * k + 0.5 * (0.4 - 0.001) * k**2 / n)
    return scaled(np.sin(phase + rng.uniform(0, 2 * np.pi)))


def multisine(n, rng):
    """Random-phase multisine: every harmonic of 1/n up to 0.4 cycles/sample, unit amplitude."""
    spectrum = np.zeros(n // 2 + 1, complex)
    k = np.arange(1, int(0.4 * n))
    spectrum[k] = np.exp(1j * rng.uniform(0, 2 * np.pi, k.shape[0]))
    return scaled(np.fft.irfft(spectrum, n))


def ar1(n, rng):
    """AR(1) noise, coefficient 0.9 (500 samples of transient dropped)."""
    e = rng.standard_normal(n + 500)
    return scaled(lfilter([1.0], [1.0, -0.9], e)[500:])


def arx_free_run(u_fit, y_fit, order, u):
    """Least-squares ARX(order, order) of ``(u_fit, y_fit)`` about their means, written out
    with NumPy (``y_n = sum a_i y_{n-i} + sum_{j=0}^{order} b_j u_{n-j}``), and its free run
    from rest on ``u``."""
    uc, yc = u_fit - u_fit.mean(), y_fit - y_fit.mean()
    rows = [
        np.r_[yc[t - order : t][::-1], uc[t - order : t + 1][::-1]] for t in range(order, len(yc))
    ]
    coef = np.linalg.lstsq(np.array(rows), yc[order:], rcond=None)[0]
    a, b = coef[:order], coef[order:]
    return lfilter(b, np.r_[1.0, -a], u - u_fit.mean()) + y_fit.mean()
