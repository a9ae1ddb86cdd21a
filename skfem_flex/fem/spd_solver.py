"""One factorization of a sparse symmetric positive definite matrix (a clamped stiffness), and the lowest
modes of a pencil (K, M) on it.

A 3D mesh's stiffness fills in when it is factorized: SuperLU (scipy's ``splu``, always there) orders it for
a general matrix, and its time grows about as N^1.6 on a tetrahedral bar. Intel MKL's PARDISO (through the
optional package ``pypardiso``, ``pip install "skfem-flex[large]"``) orders it by nested dissection and
factorizes the symmetric matrix once (Cholesky-like), near linearly in N up to 10⁵ nodes (the table of
``examples/reduction_scaling.py`` in ``docs/spatial_solids.md``). :func:`spd_factor` takes PARDISO when it is
installed and the matrix is larger than :data:`PARDISO_ABOVE` rows, else SuperLU.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

__all__ = ["spd_factor", "lowest_modes", "PARDISO_ABOVE", "pardiso_available"]

#: rows above which :func:`spd_factor` takes PARDISO when it is installed (below, SuperLU is as fast)
PARDISO_ABOVE = 20_000


def pardiso_available():
    """Whether the optional package ``pypardiso`` (Intel MKL PARDISO) can be imported."""
    try:
        import pypardiso  # noqa: F401
    except ImportError:
        return False
    return True


class _Pardiso:
    """PARDISO's factorization of an SPD matrix (its upper triangle), kept for every later solve."""

    name = "PARDISO"

    def __init__(self, K):
        import pypardiso
        # real symmetric positive definite; pypardiso checks on every solve that the matrix is the one it
        # factorized: by a hash (size_limit_storage=0), not by a copy of the matrix
        self._solver = pypardiso.PyPardisoSolver(mtype=2, size_limit_storage=0)
        self._upper = sps.triu(K, format="csr")
        self._solver.factorize(self._upper)

    def solve(self, b):
        return self._solver.solve(self._upper, np.asarray(b, dtype=float))


class _SuperLU:
    name = "SuperLU"

    def __init__(self, K):
        self._lu = spla.splu(sps.csc_matrix(K))

    def solve(self, b):
        return self._lu.solve(np.asarray(b, dtype=float))


def spd_factor(K, method="auto"):
    """A factorization of the sparse SPD matrix K with ``solve(b)`` for a vector or a block of columns.

    Parameters
    ----------
    K : scipy.sparse matrix (n, n)
    method : {"auto", "superlu", "pardiso"}
        "auto": PARDISO when ``pypardiso`` is installed and n > :data:`PARDISO_ABOVE`, else SuperLU.

    Raises
    ------
    ValueError
        An unknown method, or "pardiso" without ``pypardiso``.
    """
    if method not in ("auto", "superlu", "pardiso"):
        raise ValueError(f"method must be 'auto', 'superlu' or 'pardiso', got {method!r}")
    if method == "pardiso" and not pardiso_available():
        raise ValueError("method='pardiso' needs the package pypardiso (pip install \"skfem-flex[large]\")")
    if method == "pardiso" or (method == "auto" and K.shape[0] > PARDISO_ABOVE and pardiso_available()):
        return _Pardiso(K)
    return _SuperLU(K)


def lowest_modes(K, M, n, factor=None):
    """The n lowest eigenpairs of K φ = λ M φ (M-normalized φ, λ ascending): ARPACK in shift-invert mode about
    zero on the factorization of K (:func:`spd_factor`, made here unless given), with a fixed start vector so
    that every run gives the same basis (ARPACK's default start is random, and a nearly repeated pair of modes
    would come out mixed differently each time)."""
    factor = spd_factor(K) if factor is None else factor
    lam, vec = spla.eigsh(K, k=int(n), M=M, sigma=0.0, which="LM", v0=np.ones(K.shape[0]),
                          OPinv=spla.LinearOperator(K.shape, matvec=factor.solve, dtype=float))
    order = np.argsort(lam)
    return lam[order], vec[:, order]
