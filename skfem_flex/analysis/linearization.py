r"""The linearized equations of a scene about a state, reduced to independent coordinates.

:func:`linearize` gives M, C and K (with the geometric, centrifugal and λ·Φ_qq terms) about any
state, reduced by the sparse null-space basis of Φ_q (:func:`null_space_basis`) into a
:class:`LinearSystem`, dense up to :data:`~skfem_flex.scene.DENSE_LIMIT` independent coordinates
(dense LAPACK eigensolvers in :mod:`skfem_flex.analysis.modal`), sparse above (ARPACK).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from ..scene import DENSE_LIMIT, add_matrices
from ..scene_initial import RedundantConstraintsError
from .balance import force_balance
from .matrix_tools import as_dense, inf_norm, submatrix
from .start import consistent_start

__all__ = ["null_space_basis", "LinearSystem", "linearize"]


def null_space_basis(jacobian, rtol=1e-10):
    r"""A sparse basis N of the null space of a constraint Jacobian: Φ_q N = 0.

    The coordinates are split into m dependent ones (a well-conditioned m × m block Φ_D of
    Φ_q, chosen by a pivoted QR factorization of the columns that constraints touch) and
    n − m independent ones, and

    .. math::  N = P \begin{bmatrix} −Φ_D^{-1} Φ_I \\ I \end{bmatrix},

    so independent coordinates that no constraint touches keep unit columns and N has
    about as many entries as Φ_q plus n − m: it stays sparse for large meshes.

    Parameters
    ----------
    jacobian : matrix (m, n)
        Φ_q (dense or sparse), restricted to the unknown coordinates.
    rtol : float
        A pivot of the QR factorization below ``rtol`` times the largest counts as zero.

    Returns
    -------
    scipy.sparse.csr_matrix (n, n − m)

    Raises
    ------
    RedundantConstraintsError
        When Φ_q does not have full row rank.
    """
    m, n = jacobian.shape
    if m == 0:
        return sps.identity(n, format="csr")
    a = sps.csc_matrix(jacobian)
    a.eliminate_zeros()
    touched = np.flatnonzero(np.diff(a.indptr))
    sub = a[:, touched].toarray()
    norms = np.linalg.norm(sub, axis=1)
    if np.any(norms == 0.0):
        raise RedundantConstraintsError(f"a constraint equation has a zero Jacobian row (rows "
                                        f"{np.flatnonzero(norms == 0.0).tolist()})")
    _, r, piv = sla.qr(sub / norms[:, None], mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > rtol * diag[0])) if diag.size else 0
    if rank < m:
        raise RedundantConstraintsError(f"redundant constraints: the constraint Jacobian has rank {rank} for {m} "
                                        f"equations", rank=rank, n_equations=m)
    dep = np.sort(touched[piv[:m]])
    ind = np.setdiff1d(np.arange(n), dep)
    ind_touched = np.intersect1d(ind, touched)
    lu = spla.splu(sps.csc_matrix(a[:, dep]))
    x = -lu.solve(a[:, ind_touched].toarray()) if ind_touched.size else np.zeros((m, 0))
    col_of = np.full(n, -1)
    col_of[ind] = np.arange(ind.size)
    rows = [ind, np.repeat(dep, ind_touched.size)]
    cols = [col_of[ind], np.tile(col_of[ind_touched], m)]
    vals = [np.ones(ind.size), x.ravel()]
    basis = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n, n - m))
    basis.eliminate_zeros()
    return basis


@dataclass
class LinearSystem:
    r"""The linearized equations M z̈ + C ż + K z = 0 in independent coordinates z.

    Perturbations of the unknown coordinates are δq_free = N z; prescribed coordinates do
    not vary. Matrices are dense for small systems and sparse otherwise.

    Attributes
    ----------
    mass, damping, stiffness : matrix (n_z, n_z)
        Nᵀ M N, Nᵀ C N (gyroscopic and damping parts together; ``None`` when zero) and
        Nᵀ (K + ∂(Φ_qᵀλ)/∂q) N.
    basis : scipy.sparse matrix (n, n_z)
        Maps z to all coordinates (rows of prescribed coordinates are zero).
    t : float
    q, v, lam, acc : ndarray
        The reference state.
    """

    mass: object
    damping: object
    stiffness: object
    basis: object
    t: float
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    acc: np.ndarray

    @property
    def n(self):
        """Number of independent coordinates."""
        return self.basis.shape[1]

    @property
    def gyroscopic(self):
        """Skew part of the velocity matrix, (C − Cᵀ)/2 (None without velocity terms)."""
        if self.damping is None:
            return None
        return 0.5 * (self.damping - self.damping.T)


def _reduce(mat, basis, dense):
    out = basis.T @ (sps.csr_matrix(mat) if sps.issparse(mat) else mat) @ basis
    if dense:
        return as_dense(out)
    return sps.csr_matrix(out)


def linearize(scene, q, v, t=0.0, lam=None, acc=None):
    r"""Linearize the equations of motion of a scene about the state (q, v, t).

    .. math::

        M δq̈ + C δq̇ + (K + ∂(Φ_qᵀλ)/∂q) δq = 0, \qquad Φ_q δq = 0,

    M = M(q), C = −∂(Q_v + Q)/∂v, K = ∂(M a)/∂q − ∂Q_v/∂q + ∇²V − ∂Q/∂q (see
    :func:`~skfem_flex.analysis.balance.force_balance`): the tangent stiffness with the geometric terms of the current
    stresses, the centrifugal terms of the motion, and the constraint curvature λ·Φ_qq.
    The constraints are removed by δq_free = N z with N = :func:`null_space_basis` of
    Φ_q at q: exact for equilibria and for steady motions whose constraints do not involve
    the moving coordinates; about a general moving state it is the linearization with the
    constraint directions frozen at q.

    Parameters
    ----------
    scene : Scene
    q, v : array_like (n,)
        Reference state.
    t : float
        Time, s.
    lam : array_like, optional
        Multipliers of the state; default: those of the consistent accelerations
        (as a time integration would start from (q, v)).
    acc : array_like, optional
        Accelerations of the state (default: consistent with (q, v) and λ as above).

    Returns
    -------
    LinearSystem
    """
    q = np.asarray(q, dtype=float).ravel()
    v = np.asarray(v, dtype=float).ravel()
    for label, x in (("q", q), ("v", v)):
        if x.size != scene.n or not np.all(np.isfinite(x)):
            raise ValueError(f"{label} must be a finite vector of {scene.n} coordinates")
    t = float(t)
    if lam is None or acc is None:
        acc_start, lam_start, _ = consistent_start(scene, t, q, v)
        lam = lam_start if lam is None else lam
        acc = acc_start if acc is None else acc
    lam = np.asarray(lam, dtype=float).ravel()
    acc = np.asarray(acc, dtype=float).ravel()
    if lam.size != scene.n_constraints:
        raise ValueError(f"lam must have {scene.n_constraints} entries, got {lam.size}")
    free = scene.free_index
    _, stiff, damp, _, _ = force_balance(scene, q, v, acc, t)
    m = scene.n_constraints
    if m:
        stiff = add_matrices(stiff, scene.constraint_hessian_product(q, lam, t))
        cqf = submatrix(scene.constraint_jacobian(q, t), np.arange(m), free)
    else:
        cqf = np.zeros((0, free.size))
    basis_free = null_space_basis(cqf)
    rows = sps.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(scene.n, free.size))
    basis = (rows @ basis_free).tocsr()
    dense = basis.shape[1] <= DENSE_LIMIT
    mass = _reduce(submatrix(scene.mass_matrix(q), free, free), basis_free, dense)
    stiffness = _reduce(submatrix(stiff, free, free), basis_free, dense)
    damping = None
    if damp is not None:
        damping = _reduce(submatrix(damp, free, free), basis_free, dense)
        if inf_norm(as_dense(damping) if dense else damping.data) == 0.0:
            damping = None
    return LinearSystem(mass, damping, stiffness, basis, t, q.copy(), v.copy(), lam.copy(), acc.copy())
