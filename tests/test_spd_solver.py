"""One factorization of a clamped stiffness (skfem_flex/fem/spd_solver.py): SuperLU and, when the optional
pypardiso is installed, PARDISO solve the same systems, and the lowest modes are the dense eigensolver's."""
import numpy as np
import pytest
import scipy.linalg
import skfem

from skfem_flex.fem import spd_solver
from skfem_flex.fem.elasticity3d import ElasticSolid3D


def clamped_bar():
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 1.0, 9), np.linspace(0, 0.1, 3), np.linspace(0, 0.1, 3))
    solid = ElasticSolid3D(mesh.to_meshtet(), 2e11, 0.3, 7800.0, order=1)
    T, n = solid.tie(solid.nodes(lambda X: np.isclose(X[0], 0.0)), [])
    return (T.T @ solid.stiffness @ T).tocsr()[:n, :n], (T.T @ solid.mass @ T).tocsr()[:n, :n]


METHODS = ["superlu"] + (["pardiso"] if spd_solver.pardiso_available() else [])


@pytest.mark.parametrize("method", METHODS)
def test_factor_solves_vectors_and_blocks(method):
    K, _ = clamped_bar()
    f = spd_solver.spd_factor(K, method)
    rng = np.random.default_rng(0)
    B = rng.normal(size=(K.shape[0], 3))
    X = f.solve(B)
    assert np.abs(K @ X - B).max() <= 1e-9 * np.abs(B).max()
    assert np.allclose(f.solve(B[:, 1]), X[:, 1], rtol=0, atol=1e-12 * np.abs(X).max())


@pytest.mark.parametrize("method", METHODS)
def test_lowest_modes_are_the_dense_eigensolvers(method):
    K, M = clamped_bar()
    lam, vec = spd_solver.lowest_modes(K, M, 5, spd_solver.spd_factor(K, method))
    dense = scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=(0, 4))
    assert np.allclose(lam, dense, rtol=1e-9, atol=0)
    assert np.allclose(vec.T @ (M @ vec), np.eye(5), atol=1e-9)


def test_bad_method(monkeypatch):
    K, _ = clamped_bar()
    with pytest.raises(ValueError, match="method must be"):
        spd_solver.spd_factor(K, "cholesky")
    monkeypatch.setattr(spd_solver, "pardiso_available", lambda: False)
    with pytest.raises(ValueError, match="pypardiso"):
        spd_solver.spd_factor(K, "pardiso")
    assert spd_solver.spd_factor(K).name == "SuperLU"
