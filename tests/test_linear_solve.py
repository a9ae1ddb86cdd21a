"""The core's linear solver (``linear_solver.linear_solve``) on the shapes of Newton matrices it meets.

A scene with floating-frame bodies and joints gives a matrix that is banded but for a few
rows and columns (frame coordinates, Lagrange multipliers with a zero diagonal). It is solved
as a band with a dense border (Schur complement), which keeps memory and time linear in the
mesh; the reference is SciPy's general sparse LU.
"""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from skfem_flex.numerics import linear_solver

from helpers import bordered_matrix


@pytest.mark.parametrize("n", [200, 2000])
def test_bordered_band_matrix_matches_general_sparse_lu(n):
    a = bordered_matrix(n)
    b = np.random.default_rng(1).normal(size=a.shape[0])
    plan = linear_solver._bordered_band_plan(a.tocsr())
    assert plan is not None
    lo, up, interior, border = plan[:4]
    assert border.size <= 3 + 2 + 2 and lo + up <= 2 * 3 + 2    # frame, multipliers, their far coordinates
    x = linear_solver.linear_solve(a, b)
    ref = spla.spsolve(a.tocsc(), b)
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


def test_singular_interior_falls_back_to_general_lu():
    # two elastic coordinates with the same row and column inside the band (the interior block alone
    # is singular) that differ in their coupling to a frame coordinate: the whole matrix is regular
    a = bordered_matrix(60).tolil()
    k = 3 + 30
    for i in (k, k + 1):
        a[i, :] = 0.0
        a[:, i] = 0.0
    a[k, k] = a[k, k + 1] = a[k + 1, k] = a[k + 1, k + 1] = 1.0
    a[k, 0] = a[0, k] = 1.0
    a = a.tocsr()
    assert np.linalg.matrix_rank(a.toarray()) == a.shape[0]
    plan = linear_solver._bordered_band_plan(a)
    with pytest.raises(np.linalg.LinAlgError):          # the bordered solve alone cannot do it
        linear_solver._bordered_band_solve(a, np.ones(a.shape[0]), plan)
    b = np.arange(a.shape[0], dtype=float)
    np.testing.assert_allclose(linear_solver.linear_solve(a, b), spla.spsolve(a.tocsc(), b), rtol=1e-8, atol=1e-10)


def test_singular_matrix_raises():
    a = bordered_matrix(200).tolil()
    a[5, :] = 0.0
    with pytest.raises(np.linalg.LinAlgError):
        linear_solver.linear_solve(a.tocsc(), np.ones(a.shape[0]))
