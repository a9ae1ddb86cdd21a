"""The static-pivot sparse LU (``skfem_flex/numerics/sparse_lu.py``) and the loop's solver kernel that uses it
(``solvers.static_lu_solver``, chosen by ``Stepper.plan_sparse_lu``).

1. On random saddle-point matrices (multipliers with a zero diagonal block, nonsymmetric), stored dense or as
   the values of their pattern, the plan's structure holds every entry of the pattern, and the
   refactorization with the pivots chosen on one matrix solves other matrices of the same pattern as
   ``np.linalg.solve`` does.
2. A pivot that vanishes in a later matrix, or an update outside the planned structure, is reported
   (False), not a silent NaN.
3. In the loop: the spatial slider–crank (a closed loop, where the band plan needs every multiplier in its
   border) takes the static LU, and its run is the band solver's run; with the LU's pivots spoiled every
   solve falls back to the band solver (the run unchanged) and the LU is given up after
   ``STATIC_LU_FAILURES`` failures. A pendulum, where the band is faster, keeps the band.
"""
import numpy as np
import pytest
import scipy.sparse as sps

import skfem_flex as sf
from skfem_flex.compiled import solvers
from skfem_flex.numerics import sparse_lu
from skfem_flex.schemes import EnergyMomentum
from skfem_flex.schemes.base import State
from skfem_flex.schemes import stepper as stepper_module
from skfem_flex.schemes.stepper import STATIC_LU, Stepper


def saddle_point(n, m, density, seed):
    """(pattern (CSR bool), a function values(rng) → a dense matrix on that pattern): K (n × n, nonsymmetric,
    diagonally weighted) bordered by G (m × n) and Gᵀ, a zero m × m block."""
    rng = np.random.default_rng(seed)
    k = (rng.random((n, n)) < density) | np.eye(n, dtype=bool)
    g = rng.random((m, n)) < 2.5 / n
    for i in range(m):                     # every multiplier constrains at least two coordinates
        g[i, rng.choice(n, 2, replace=False)] = True
    pat = np.zeros((n + m, n + m), dtype=bool)
    pat[:n, :n], pat[n:, :n], pat[:n, n:] = k, g, g.T

    def values(r):
        a = np.where(pat, r.standard_normal(pat.shape), 0.0)
        a[np.arange(n), np.arange(n)] += 10.0 * np.sign(a[np.arange(n), np.arange(n)] + 1e-3)
        return a
    return sps.csr_matrix(pat), values


@pytest.mark.parametrize("dense_storage", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_refactorization_solves_later_matrices(dense_storage, seed):
    pattern, values = saddle_point(40, 12, 0.08, seed)
    rng = np.random.default_rng(100 + seed)
    plan = sparse_lu.static_lu_plan(pattern, values(rng), dense_storage)
    assert plan is not None
    # every entry of the pattern has its place in L + U
    assert np.count_nonzero(plan.src >= 0) == pattern.nnz
    n = pattern.shape[0]
    lu, w, mark, z = np.zeros(plan.idx.size), np.zeros(n), np.full(n, -1, dtype=np.int64), np.zeros(n)
    for _ in range(4):                                 # other matrices of the pattern, the same plan
        a = values(rng)
        b = rng.standard_normal(n)
        vals = a.ravel() if dense_storage else sps.csr_matrix(a)[pattern.nonzero()].A1
        if not dense_storage:                          # the pattern's own order
            s = sps.csr_matrix(pattern, dtype=float)
            s.sort_indices()
            r, c = np.repeat(np.arange(n), np.diff(s.indptr)), s.indices
            vals = a[r, c]
        x = np.zeros(n)
        assert sparse_lu.static_lu_solve(vals, b, x, *plan, lu, w, mark, z)
        ref = np.linalg.solve(a, b)
        assert np.abs(x - ref).max() <= 1e-10 * np.abs(ref).max()


def test_vanishing_pivot_is_reported():
    """Pivots chosen where a₀₀ is large; a later matrix with a₀₀ = 0 (and nothing below it in column 0) has no
    such pivot: the solve says so."""
    a = np.array([[4.0, 1.0, 0.0], [0.0, 3.0, 1.0], [0.0, 1.0, 2.0]])
    pattern = sps.csr_matrix(a != 0.0)
    plan = sparse_lu.static_lu_plan(pattern, a, True)
    later = a.copy()
    later[0, 0] = 0.0
    n = 3
    x = np.zeros(n)
    work = (np.zeros(plan.idx.size), np.zeros(n), np.full(n, -1, dtype=np.int64), np.zeros(n))
    assert sparse_lu.static_lu_solve(a.ravel(), np.ones(n), x, *plan, *work)
    assert np.allclose(a @ x, 1.0)
    assert not sparse_lu.static_lu_solve(later.ravel(), np.ones(n), x, *plan, *work)


def test_update_outside_the_structure_is_reported():
    """A structure without a fill entry — the arrow matrix eliminated in its order, without the fill at (1, 2)
    and (2, 1) — is caught by the kernel, not written out of place; with the fill it solves."""
    a = np.array([[4.0, 1.0, 1.0], [1.0, 3.0, 0.0], [1.0, 0.0, 2.0]])
    ident = np.arange(3, dtype=np.int64)

    def plan(rows):
        ptr = np.concatenate([[0], np.cumsum([len(r) for r in rows])]).astype(np.int64)
        idx = np.concatenate(rows).astype(np.int64)
        diag = np.array([ptr[i] + rows[i].index(i) for i in range(3)], dtype=np.int64)
        src = np.where(a[np.repeat(ident, np.diff(ptr)), idx] != 0.0, 3 * np.repeat(ident, np.diff(ptr)) + idx, -1)
        return sparse_lu.StaticLUPlan(ident, ident, ptr, idx, diag, src.astype(np.int64))
    work = (np.zeros(9), np.zeros(3), np.full(3, -1, dtype=np.int64), np.zeros(3))
    x = np.zeros(3)
    assert not sparse_lu.static_lu_solve(a.ravel(), np.ones(3), x, *plan([[0, 1, 2], [0, 1], [0, 2]]), *work)
    assert sparse_lu.static_lu_solve(a.ravel(), np.ones(3), x, *plan([[0, 1, 2], [0, 1, 2], [0, 1, 2]]), *work)
    assert np.allclose(x, np.linalg.solve(a, np.ones(3)))


def test_plan_declines_large_and_singular():
    big = sps.identity(sparse_lu.MAX_UNKNOWNS + 1, format="csr")
    assert sparse_lu.static_lu_plan(big, big, False) is None
    pattern = sps.csr_matrix(np.ones((3, 3), dtype=bool))
    assert sparse_lu.static_lu_plan(pattern, np.zeros((3, 3)), True) is None


def _crank_steps(steps, spoil=False, gain=None, monkeypatch=None):
    """(stepper, states) of ``steps`` energy-momentum steps of the spatial slider–crank through the Stepper."""
    if gain is not None:
        monkeypatch.setattr(stepper_module, "STATIC_LU_GAIN", gain)
    scene = sf.scenes.spatial_slider_crank()
    st = Stepper(scene, EnergyMomentum())
    q, v = scene.initial_state()
    state = st.starting_state(State(0.0, q, v))
    st.load(state)
    st.plan_sparse_lu(0.0, 1e-3)
    if spoil and st.solver_name == STATIC_LU:
        prow = st._static_lu.array("prow")             # a wrong row order: every solution fails its check
        prow[[0, 1]] = prow[[1, 0]]
    out = []
    for _ in range(steps):
        state, _ = st.step(state, 1e-3)
        out.append(np.concatenate([state.q, state.v]))
    return st, np.array(out)


def test_closed_loop_takes_the_static_lu_and_runs_as_the_band(monkeypatch):
    st, lu_run = _crank_steps(20)
    assert st.solver_name == STATIC_LU
    band, band_run = _crank_steps(20, gain=0.0, monkeypatch=monkeypatch)
    assert band.solver_name == "bordered band"
    assert np.abs(lu_run - band_run).max() <= 1e-10 * np.abs(band_run).max()


def test_spoiled_pivots_fall_back_to_the_band(monkeypatch):
    st, spoiled = _crank_steps(20, spoil=True)
    assert st.solver_name == STATIC_LU
    assert st._static_lu.array("state")[1] == solvers.STATIC_LU_FAILURES    # tried, then given up
    _, band_run = _crank_steps(20, gain=0.0, monkeypatch=monkeypatch)
    assert np.abs(spoiled - band_run).max() <= 1e-10 * np.abs(band_run).max()


def test_simulate_reports_the_solver_and_a_band_scene_keeps_its_band():
    r = sf.simulate(sf.scenes.spatial_slider_crank(), t_end=0.01, dt=1e-3)
    assert r.run_path["solver"] == STATIC_LU
    E = r.total_energy - r.external_work
    assert np.abs(E - E[0]).max() <= 1e-10 * np.abs(r.total_energy).max()
    r = sf.simulate(sf.scenes.flexible_pendulum(), t_end=0.005, dt=1e-3)
    assert r.run_path["solver"] == "bordered band"
