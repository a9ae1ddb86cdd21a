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
import scipy.sparse.linalg as spla

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
        if dense_storage:
            vals = a.ravel()
        else:                                          # the values in the pattern's own order
            s = sps.csr_matrix(pattern, dtype=float)
            s.sort_indices()
            vals = a[np.repeat(np.arange(n), np.diff(s.indptr)), s.indices]
        x = np.zeros(n)
        assert sparse_lu.static_lu_solve(vals, b, x, *plan, lu, w, mark, z)
        ref = np.linalg.solve(a, b)
        assert np.abs(x - ref).max() <= 1e-10 * np.abs(ref).max()


def test_pivots_are_superlus(monkeypatch):
    """On the sample itself the refactorization meets SuperLU's factors: its pivots u_ii are SuperLU's, in the
    same order (the row and column permutations read the right way round), and they are the pivots of B =
    P A Q eliminated in order."""
    monkeypatch.setattr(sparse_lu, "ORDERINGS", ("COLAMD",))
    pattern, values = saddle_point(30, 8, 0.1, 7)
    a = values(np.random.default_rng(3))
    plan = sparse_lu.static_lu_plan(pattern, a, True)
    n = a.shape[0]
    lu = np.zeros(plan.idx.size)
    assert sparse_lu.static_lu_solve(a.ravel(), np.ones(n), np.zeros(n), *plan, lu, np.zeros(n),
                                     np.full(n, -1, dtype=np.int64), np.zeros(n))
    ref = spla.splu(sps.csc_matrix(a + sps.csr_matrix(pattern, dtype=float) * (1e-30 * np.abs(a).max())),
                    permc_spec="COLAMD", diag_pivot_thresh=1.0)
    np.testing.assert_allclose(lu[plan.diag], ref.U.diagonal(), rtol=1e-10)
    b = a[plan.prow][:, plan.qcol]
    u = b.copy()
    for k in range(n):
        u[k + 1:, k:] -= np.outer(u[k + 1:, k] / u[k, k], u[k, k:])
    np.testing.assert_allclose(lu[plan.diag], np.diag(u), rtol=1e-10)


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


def _steps(make, dt, steps, spoil=False, gain=None, monkeypatch=None):
    """(stepper, states) of ``steps`` energy-momentum steps of the scene ``make()`` through the Stepper;
    ``gain``: STATIC_LU_GAIN for the plan (0: never the static LU, 1e9: always); ``spoil``: swap two of the
    plan's rows, so that every solution fails its check."""
    if gain is not None:
        monkeypatch.setattr(stepper_module, "STATIC_LU_GAIN", gain)
    scene = make()
    st = Stepper(scene, EnergyMomentum())
    q, v = scene.initial_state()
    state = st.starting_state(State(0.0, q, v))
    st.load(state)
    st.plan_sparse_lu(0.0, dt)
    if spoil and st.solver_name == STATIC_LU:
        prow = st.static_lu.array("prow")
        prow[[0, 1]] = prow[[1, 0]]
    out = []
    for _ in range(steps):
        state, _ = st.step(state, dt)
        out.append(np.concatenate([state.q, state.v]))
    return st, np.array(out)


def test_closed_loop_takes_the_static_lu_and_runs_as_the_band(monkeypatch):
    st, lu_run = _steps(sf.scenes.spatial_slider_crank, 1e-3, 20)
    assert st.solver_name == STATIC_LU
    assert st.static_lu.array("state")[1] == 0               # every solve by the LU itself
    band, band_run = _steps(sf.scenes.spatial_slider_crank, 1e-3, 20, gain=0.0, monkeypatch=monkeypatch)
    assert band.solver_name == "bordered band"
    assert np.abs(lu_run - band_run).max() <= 1e-10 * np.abs(band_run).max()


@pytest.mark.parametrize("n_bodies, fallback", [(2, "dense"), (3, "dense"), (7, "bordered band (CSR)"),
                                                (20, "bordered band (CSR)")])
def test_spoiled_pivots_fall_back_to_the_scenes_solver(monkeypatch, n_bodies, fallback):
    """Each kind of fallback (dense LU; the band on CSR storage; the crank below: the band on dense storage):
    with the LU forced and its pivots spoiled, every solve fails its check and is solved by the scene's own
    solver, the run unchanged, and the LU is given up after STATIC_LU_FAILURES failures."""
    def make():
        return sf.scenes.rigid_chain(n_bodies)
    own, own_run = _steps(make, 1e-3, 12, gain=0.0, monkeypatch=monkeypatch)
    assert own.solver_name == fallback
    forced, forced_run = _steps(make, 1e-3, 12, gain=1e9, monkeypatch=monkeypatch)
    assert forced.solver_name == STATIC_LU and forced.static_lu.array("state")[1] == 0
    assert np.abs(forced_run - own_run).max() <= 1e-10 * np.abs(own_run).max()
    spoiled, spoiled_run = _steps(make, 1e-3, 12, spoil=True, gain=1e9, monkeypatch=monkeypatch)
    assert spoiled.static_lu.array("state")[1] == solvers.STATIC_LU_FAILURES
    assert np.abs(spoiled_run - own_run).max() <= 1e-10 * np.abs(own_run).max()


def test_spoiled_pivots_fall_back_to_the_band(monkeypatch):
    st, spoiled = _steps(sf.scenes.spatial_slider_crank, 1e-3, 20, spoil=True)
    assert st.solver_name == STATIC_LU
    assert st.static_lu.array("state")[1] == solvers.STATIC_LU_FAILURES    # tried, then given up
    _, band_run = _steps(sf.scenes.spatial_slider_crank, 1e-3, 20, gain=0.0, monkeypatch=monkeypatch)
    assert np.abs(spoiled - band_run).max() <= 1e-10 * np.abs(band_run).max()


def test_simulate_reports_the_solver_and_a_band_scene_keeps_its_band():
    r = sf.simulate(sf.scenes.spatial_slider_crank(), t_end=0.01, dt=1e-3)
    assert r.run_path["solver"] == STATIC_LU
    E = r.total_energy - r.external_work
    assert np.abs(E - E[0]).max() <= 1e-10 * np.abs(r.total_energy).max()
    r = sf.simulate(sf.scenes.flexible_pendulum(), t_end=0.005, dt=1e-3)
    assert r.run_path["solver"] == "bordered band"
