"""Canonical correlation between generated and time-aligned natural motion.

The first canonical pair maximises the correlation between projections ``a^T x_t`` (generated
pose vectors) and ``b^T y_t`` (natural ones). With covariances ``Cxx``, ``Cyy``, ``Cxy``:

    K = Cxx^{-1/2} Cxy Cyy^{-1/2},   K = U S V^T,   a = Cxx^{-1/2} u_1,  b = Cyy^{-1/2} v_1

and the in-sample first canonical correlation is ``S[0]``. Dimensions that are constant on the
fitting data (std <= 1e-8, as the GENEA script drops) are left out, and the inverse square
roots use only eigenvalues above ``1e-10 x`` the largest (a pseudo-inverse, because pose
dimensions of rigidly linked joints are often collinear).

**Scoring.** :func:`cca_score` is the Pearson correlation of the two projections on *other*
data. The GENEA scripts (``cca.py``/``calc_cca.py``, sklearn ``CCA(n_components=1)``) call
``fit`` on the very frames they score, so their value is the in-sample first canonical
correlation — optimistic, and close to 1 for any model with enough dimensions. evalsuite's
default convention cross-fits (fit on one half of the sequences, score on the other, and the
reverse; the mean of both); the reference conventions use :func:`canonical_correlation`
in-sample. sklearn's NIPALS iteration converges to the same first pair; scikit-learn is not
needed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError
from evalsuite.metrics._validate import samples_array

__all__ = ["CCAModel", "cca_fit", "cca_score", "canonical_correlation", "cca_fit_moments",
           "cca_score_moments"]

_CONSTANT_STD = 1e-8
_EIG_FLOOR = 1e-10


@dataclass
class CCAModel:
    """First canonical pair: weights on the kept dimensions and the means they are applied to."""

    keep_x: np.ndarray
    keep_y: np.ndarray
    a: np.ndarray
    b: np.ndarray
    mean_x: np.ndarray
    mean_y: np.ndarray
    correlation: float  # in-sample first canonical correlation


def _inv_sqrt(c: np.ndarray) -> np.ndarray:
    c = (c + c.T) / 2
    w, v = np.linalg.eigh(c)
    ok = w > _EIG_FLOOR * max(w.max(), 0.0) if w.size else w > 0
    if not ok.any():
        raise InputError("the motion has no variance to correlate (static pose?)", field="cca")
    v = v[:, ok]
    return np.asarray((v / np.sqrt(w[ok])) @ v.T)


def cca_fit_moments(n: float, mean: np.ndarray, scatter: np.ndarray, dx: int) -> CCAModel:
    """Fit the first canonical pair from moments of stacked samples ``z = [x; y]`` (``dx`` dims of x)."""
    if n < 3:
        raise InputError(f"CCA needs at least 3 frames, got {n}", field="cca")
    cov = scatter / (n - 1)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    keep = std > _CONSTANT_STD
    keep_x = np.flatnonzero(keep[:dx])
    keep_y = np.flatnonzero(keep[dx:])
    if keep_x.size == 0 or keep_y.size == 0:
        raise InputError("CCA is undefined: one of the motions has no varying dimension (static pose?)",
                         field="cca")
    ix, iy = keep_x, dx + keep_y
    cxx, cyy, cxy = cov[np.ix_(ix, ix)], cov[np.ix_(iy, iy)], cov[np.ix_(ix, iy)]
    wx, wy = _inv_sqrt(cxx), _inv_sqrt(cyy)
    u, s, vt = np.linalg.svd(wx @ cxy @ wy)
    return CCAModel(keep_x, keep_y, wx @ u[:, 0], wy @ vt[0], mean[ix], mean[iy], float(min(s[0], 1.0)))


def cca_score_moments(model: CCAModel, n: float, mean: np.ndarray, scatter: np.ndarray, dx: int) -> float:
    """Correlation of the model's projections on data given by moments of ``z = [x; y]``."""
    ix, iy = model.keep_x, dx + model.keep_y
    c = scatter
    sxy = model.a @ c[np.ix_(ix, iy)] @ model.b
    sxx = model.a @ c[np.ix_(ix, ix)] @ model.a
    syy = model.b @ c[np.ix_(iy, iy)] @ model.b
    if sxx <= 0 or syy <= 0:
        return float("nan")
    return float(sxy / np.sqrt(sxx * syy))


def _stacked(x: npt.ArrayLike, y: npt.ArrayLike) -> tuple[float, np.ndarray, np.ndarray, int]:
    x = samples_array(x, "x", min_rows=3)
    y = samples_array(y, "y", min_rows=3)
    if len(x) != len(y):
        raise InputError(f"x has {len(x)} frames but y {len(y)}; CCA needs time-aligned frames", field="cca")
    z = np.hstack([x, y])
    mean = z.mean(axis=0)
    c = z - mean
    return len(z), mean, c.T @ c, x.shape[1]


def cca_fit(x: npt.ArrayLike, y: npt.ArrayLike) -> CCAModel:
    """Fit the first canonical pair on time-aligned frames ``x (N, Dx)``, ``y (N, Dy)``."""
    n, mean, scatter, dx = _stacked(x, y)
    return cca_fit_moments(n, mean, scatter, dx)


def cca_score(model: CCAModel, x: npt.ArrayLike, y: npt.ArrayLike) -> float:
    """Pearson correlation of ``a^T x`` and ``b^T y`` on (held-out) time-aligned frames."""
    n, mean, scatter, dx = _stacked(x, y)
    if dx != model.mean_x.size and dx <= model.keep_x.max(initial=0):
        raise InputError("x has fewer dimensions than the fitted model", field="cca")
    return cca_score_moments(model, n, mean, scatter, dx)


def canonical_correlation(x: npt.ArrayLike, y: npt.ArrayLike) -> float:
    """In-sample first canonical correlation (what the GENEA scripts report)."""
    return cca_fit(x, y).correlation
