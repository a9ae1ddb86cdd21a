"""Small matrix helpers of the analysis layer, for dense arrays and scipy sparse matrices alike."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

__all__ = ["EPS", "TINY", "inf_norm", "as_dense", "submatrix", "abs_entries"]

#: machine epsilon of float64
EPS = np.finfo(float).eps
#: a positive floor that keeps divisions finite
TINY = 1e-300


def inf_norm(x):
    """max |x| over all entries (0 for an empty x)."""
    return float(np.abs(x).max()) if np.size(x) else 0.0


def as_dense(a):
    """``a`` as a dense float array."""
    return a.toarray() if sps.issparse(a) else np.asarray(a, dtype=float)


def submatrix(a, rows, cols):
    """The block of ``a`` in ``rows`` and ``cols`` (a CSR matrix for sparse ``a``)."""
    if sps.issparse(a):
        return a.tocsr()[rows][:, cols]
    return np.asarray(a)[np.ix_(rows, cols)]


def abs_entries(a):
    """|a| entry by entry (sparse stays sparse)."""
    return abs(a) if sps.issparse(a) else np.abs(a)
