"""The bordered band solve of the compiled core's Newton matrices (``band_kernels.bordered_band_solve`` and
``bordered_band_solve_csr``, which the solver kernels of ``skfem_flex/compiled/solvers.py`` call) and the
plans that ``skfem_flex/compiled/pack.py`` fixes per scene.

1. Random bordered-band matrices (frame-like dense rows and columns, multipliers with a zero
   diagonal, at the start and at the end; nonsymmetric; interiors that need row interchanges) are
   solved as ``np.linalg.solve`` solves them, and :func:`dense_bordered_plan` finds their border.
2. The Newton matrix of the flexible pendulum (16 elements, 53 × 53) as the energy-momentum step writes
   it (``Stepper.evaluate``): its border is the beam's three frame coordinates and the pin's two
   multipliers, the packed scene's plan is that plan and its pattern holds every entry written.
3. The solve reports failure (``ok`` False, no silent NaN) for a singular interior block, an entry
   the plan did not know about and a non-finite matrix; the plan declines full and tiny matrices.
   The written-out dense LU of small systems (``solvers.small_lu_solve``) is LAPACK's solve and reports
   a zero or non-finite pivot.
4. The border rule is the sparse solver's (the sparse plan covers every far entry and solves as
   SuperLU does; the same border for the same threshold).
5. The plan of a mechanism's Newton matrix puts every multiplier (no diagonal) in the border, and
   its band solve succeeds (the slider-crank: 8 multipliers).
6. The CSR form (the matrix held as the values of its pattern) gives the dense form's solution from the
   same elimination, takes the plan of a sparse pattern, and reports failure for an entry outside the
   planned band or a non-finite entry.
7. A reordered plan (reverse Cuthill–McKee, multipliers in the band) for a chain's Newton matrix, whose
   natural order has no band with a small border, solves the matrix the step wrote into its CSR storage.
"""
import numpy as np
import pytest
import scipy.sparse as sps
import scipy.sparse.linalg as spla

import skfem_flex as sf
from skfem_flex.compiled import solvers
from skfem_flex.compiled.storage import CSR, DENSE
from skfem_flex.numerics import band_kernels, band_plans
from skfem_flex.numerics import linear_solver as ls
from skfem_flex.schemes import EnergyMomentum
from skfem_flex.schemes.stepper import Stepper

from helpers import bordered_matrix, dense


def random_bordered(n_interior, lo, up, n_frame, n_mult, frame_first, seed, pivoting=True):
    """(mat, pattern, border) of a nonsymmetric band with dense frame rows/columns and multipliers.

    The frame coordinates are dense rows and columns; the multipliers have a zero diagonal and
    couple to a frame coordinate and to interior coordinates far apart. With ``pivoting`` every
    third interior diagonal entry is zero (kept in the pattern) or tiny, so the band LU must
    interchange rows.
    """
    rng = np.random.default_rng(seed)
    n = n_interior + n_frame + n_mult
    if frame_first:            # frame at the start, multipliers at the end (the Newton matrices' layout)
        frame, mult = np.arange(n_frame), np.arange(n - n_mult, n)
    else:                      # multipliers first, frame at the end
        mult, frame = np.arange(n_mult), np.arange(n - n_frame, n)
    border = np.sort(np.concatenate([frame, mult]))
    interior = np.setdiff1d(np.arange(n), border)
    a = np.zeros((n, n))
    pattern = np.zeros((n, n), dtype=bool)
    for r in range(n_interior):
        for c in range(max(0, r - lo), min(n_interior, r + up + 1)):
            a[interior[r], interior[c]] = rng.normal()
            pattern[interior[r], interior[c]] = True
        a[interior[r], interior[r]] += (lo + up + 1) * np.sign(rng.normal())
    for r in range(1, n_interior - 1, 3):
        if pivoting:           # [[0, β], [β, d]] on the diagonal: regular, but no pivot in place
            i, j = interior[r], interior[r + 1]
            a[i, i] = 0.0 if r % 2 else 1e-6 * rng.normal()
            a[j, i] = 2.0 * (lo + up + 1) * np.sign(rng.normal())
            a[i, j] = 2.0 * (lo + up + 1) * np.sign(rng.normal())
    for f in frame:
        a[f, :] = rng.normal(size=n)
        a[:, f] = rng.normal(size=n)
        a[f, f] += 10.0 * n
        pattern[f, :] = pattern[:, f] = True
    for i, mu in enumerate(mult):
        cols = [frame[i % n_frame], interior[(3 * i + 1) % n_interior], interior[-1 - 2 * i]]
        a[mu, :] = a[:, mu] = 0.0
        a[mu, cols] = rng.normal(size=3) + 1.0
        a[cols, mu] = rng.normal(size=3) - 1.0
        pattern[mu, :] = pattern[:, mu] = False
        pattern[mu, cols] = pattern[cols, mu] = True
    assert np.all(pattern | (a == 0.0))
    return a, pattern, border


def rel_error(x, ref):
    return np.abs(x - ref).max() / np.abs(ref).max()


CASES = [  # (interior size, lo, up, frame coordinates, multipliers, frame first)
    (12, 2, 3, 3, 2, True),
    (40, 4, 4, 3, 2, True),
    (40, 3, 5, 3, 2, False),
    (100, 5, 2, 3, 4, True),
    (150, 4, 4, 6, 3, False),
]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("pivoting", [True, False])
def test_random_bordered_band_matches_dense_solve(case, pivoting):
    ni, lo, up, n_frame, n_mult, frame_first = case
    for seed in range(3):
        a, pattern, border = random_bordered(ni, lo, up, n_frame, n_mult, frame_first, seed, pivoting)
        plan = band_plans.dense_bordered_plan(pattern)
        assert plan is not None
        interior, plan_border, plan_lo, plan_up = plan
        np.testing.assert_array_equal(plan_border, border)
        np.testing.assert_array_equal(interior, np.setdiff1d(np.arange(a.shape[0]), border))
        assert (plan_lo, plan_up) == (lo, up)
        assert interior.dtype == np.int64 and plan_border.dtype == np.int64
        rhs = np.random.default_rng(100 + seed).normal(size=a.shape[0])
        before = a.copy()
        x, ok = band_kernels.bordered_band_solve(a, rhs, *plan)
        assert ok
        np.testing.assert_array_equal(a, before)                 # mat is only read
        ref = np.linalg.solve(a, rhs)
        assert rel_error(x, ref) <= 1e-12          # cond(a) ≤ 1e7 here, cond(A_II) ≈ 4


def test_interior_without_pivoting_would_fail():
    """The random interiors really need row interchanges: an exactly zero diagonal entry in the band."""
    a, pattern, border = random_bordered(40, 4, 4, 3, 2, True, seed=0, pivoting=True)
    interior = np.setdiff1d(np.arange(a.shape[0]), border)
    assert np.any(np.diagonal(a)[interior] == 0.0)
    x, ok = band_kernels.bordered_band_solve(a, np.ones(a.shape[0]), *band_plans.dense_bordered_plan(pattern))
    assert ok and np.allclose(a @ x, 1.0, rtol=0, atol=1e-12)


def test_border_columns_zero_on_the_interior_are_skipped():
    """A border coordinate whose column vanishes on the interior, before others that do not."""
    a, pattern, border = random_bordered(30, 3, 3, 3, 2, False, seed=4)   # multipliers 0, 1 first
    a[np.ix_(np.setdiff1d(np.arange(a.shape[0]), border), [0, 1])] = 0.0
    a[[0, 1], -1] = [1.0, -2.0]             # still regular: multipliers constrain frame coordinates only
    a[-1, [0, 1]] = [0.5, 0.7]
    a[[0, 1], -2] = [0.3, 1.1]
    a[-2, [0, 1]] = [-0.4, 0.2]
    plan = (np.setdiff1d(np.arange(a.shape[0]), border), border, 3, 3)
    rhs = np.linspace(-1.0, 2.0, a.shape[0])
    x, ok = band_kernels.bordered_band_solve(a, rhs, *plan)
    assert ok
    assert rel_error(x, np.linalg.solve(a, rhs)) <= 1e-12


def newton_evaluation(scene, h, dv=0.0, perturbations=0, seed=0):
    """The energy-momentum step of size h from the scene's initial state (velocities + ``dv``), evaluated by
    its compiled kernels (``Stepper.evaluate``) at the predictor Δq = h v0, μ = 0: (stepper, residual,
    Newton matrix (dense), where it is nonzero). The last is the union over that evaluation and
    ``perturbations`` more at random unknowns near it: an entry that happens to be zero at one state is kept."""
    scheme = EnergyMomentum()
    st = Stepper(scene, scheme)
    q0, v0 = scene.initial_state()
    v0 = v0 + dv
    st.load(scheme.make_state(0.0, q0, v0, acc=np.zeros(scene.n), lam=np.zeros(scene.n_constraints)))
    pk = st.packed
    x0 = np.concatenate([h * v0[pk.free], np.zeros(pk.m)])
    rng = np.random.default_rng(seed)
    nonzero = None
    for k in range(perturbations + 1):
        x = x0 if k == 0 else x0 + 1e-3 * rng.normal(size=x0.size)
        mat = dense(st.evaluate(0.0, h, x)[1])
        nonzero = mat != 0.0 if nonzero is None else nonzero | (mat != 0.0)
    res, mat, _ = st.evaluate(0.0, h, x0)
    return st, res, dense(mat), nonzero


@pytest.fixture(scope="module")
def pendulum_newton():
    """Newton matrix and residual of the energy-momentum step for the flexible pendulum, where they are
    nonzero over five evaluations, and the packed scene."""
    scene = sf.scenes.get("flexible_pendulum")(n_elements=16)
    st, res, mat, nonzero = newton_evaluation(scene, 1e-3, dv=0.01, perturbations=4)
    return scene, mat, res, nonzero, st.packed


def test_flexible_pendulum_newton_matrix(pendulum_newton):
    scene, mat, res, nonzero, packed = pendulum_newton
    n = mat.shape[0]
    assert n == 53 and scene.n_constraints == 2
    plan = band_plans.dense_bordered_plan(nonzero)
    assert plan is not None
    interior, border, lo, up = plan
    # the beam's frame coordinates (R_x, R_y, θ: couple to every elastic coordinate) and the pin's
    # two multipliers (zero diagonal); the elastic coordinates form a band of three per node
    np.testing.assert_array_equal(border, [0, 1, 2, n - 2, n - 1])
    assert (lo, up) == (4, 4)
    # the sparse solver's threshold gives the same border at this size
    np.testing.assert_array_equal(band_plans.dense_bordered_plan(nonzero, far=band_plans.MAX_BANDWIDTH // 2)[1], border)
    # the packed scene's pattern holds every entry the step wrote, and its plan (fixed before any
    # evaluation, from that pattern) is this plan: dense storage, the bordered band solver
    pattern = packed.pattern.toarray().astype(bool)
    assert pattern.shape == (n, n) and not (nonzero & ~pattern).any()
    assert packed.storage == DENSE and packed.solver == "bordered band"
    for x, y in zip(packed.plan, plan):
        np.testing.assert_array_equal(x, y)
    x, ok = band_kernels.bordered_band_solve(mat, res, *plan)
    assert ok
    ref = np.linalg.solve(mat, res)
    assert rel_error(x, ref) <= 1e-12


def test_singular_interior_block_reports_failure():
    # two interior coordinates with the same row and column inside the band (A_II singular) that
    # differ in their coupling to a frame coordinate: the whole matrix is regular
    a, pattern, border = random_bordered(40, 3, 3, 3, 2, True, seed=1, pivoting=False)
    interior = np.setdiff1d(np.arange(a.shape[0]), border)
    i, j = interior[20], interior[21]
    for c in (i, j):
        a[c, interior] = 0.0
        a[interior, c] = 0.0
    a[i, i] = a[i, j] = a[j, i] = a[j, j] = 1.0
    a[i, 0] = a[0, i] = 1.0
    a[j, 0] = a[0, j] = 0.0
    assert np.linalg.matrix_rank(a) == a.shape[0]
    plan = band_plans.dense_bordered_plan(pattern)
    x, ok = band_kernels.bordered_band_solve(a, np.ones(a.shape[0]), *plan)
    assert not ok
    assert np.all(np.isfinite(np.linalg.solve(a, np.ones(a.shape[0]))))     # the caller's fallback


def test_entry_outside_the_planned_band_reports_failure():
    """A pattern from too few evaluations: the check with the dense matrix catches the missed entry."""
    a, pattern, border = random_bordered(40, 3, 3, 3, 2, True, seed=2, pivoting=False)
    plan = band_plans.dense_bordered_plan(pattern)
    rhs = np.ones(a.shape[0])
    assert band_kernels.bordered_band_solve(a, rhs, *plan)[1]
    interior = plan[0]
    a[interior[5], interior[30]] = 1.0
    x, ok = band_kernels.bordered_band_solve(a, rhs, *plan)
    assert not ok


@pytest.mark.parametrize("where", ["interior", "border", "outside"])
def test_non_finite_matrix_reports_failure(where):
    a, pattern, border = random_bordered(40, 3, 3, 3, 2, True, seed=3, pivoting=False)
    plan = band_plans.dense_bordered_plan(pattern)
    interior = plan[0]
    i, j = {"interior": (interior[4], interior[5]), "border": (border[0], interior[7]),
            "outside": (interior[2], interior[35])}[where]
    a[i, j] = np.nan
    x, ok = band_kernels.bordered_band_solve(a, np.ones(a.shape[0]), *plan)
    assert not ok


def test_plan_does_not_fit_raises():
    a, pattern, border = random_bordered(20, 2, 2, 3, 2, True, seed=0)
    interior, border, lo, up = band_plans.dense_bordered_plan(pattern)
    with pytest.raises(ValueError):
        band_kernels.bordered_band_solve(a[:-1, :-1].copy(), np.ones(a.shape[0] - 1), interior, border, lo, up)
    with pytest.raises(ValueError):
        band_kernels.bordered_band_solve(a, np.ones(a.shape[0]), interior + a.shape[0], border, lo, up)


def test_plan_declines_dense_tiny_and_wide():
    rng = np.random.default_rng(0)
    assert band_plans.dense_bordered_plan(np.ones((60, 60), dtype=bool)) is None              # full
    a, pattern, _ = random_bordered(6, 1, 1, 3, 2, True, seed=0)
    assert pattern.shape[0] < band_plans.MIN_DENSE_BORDERED and band_plans.dense_bordered_plan(pattern) is None
    sparse = rng.random((60, 60)) < 0.2                                                # no band structure
    np.fill_diagonal(sparse, True)
    assert band_plans.dense_bordered_plan(sparse) is None
    with pytest.raises(ValueError):
        band_plans.dense_bordered_plan(np.ones((3, 4), dtype=bool))


def _csr_examples():
    yield bordered_matrix(200).tocsr()
    yield bordered_matrix(1000, n_frame=6, n_mult=4, half_band=5, seed=3).tocsr()
    rng = np.random.default_rng(7)
    yield sps.random(300, 300, density=0.02, random_state=rng, format="csr") + sps.identity(300, format="csr")
    yield sps.diags([np.ones(99), np.ones(100), np.ones(99)], [-1, 0, 1], format="csr")
    many = sps.lil_matrix(bordered_matrix(400).tocsr())
    for i in range(0, 400, 2):                                    # more far coordinates than MAX_BORDER
        many[i, (i + 200) % 400] = 1.0
    yield many.tocsr()


def test_sparse_bordered_band_plan_covers_far_entries_and_solves():
    """The sparse plan's border holds the coordinates without a diagonal entry and a row or column of
    every entry farther than MAX_BANDWIDTH/2 from the diagonal, its interior is a band within
    MAX_BANDWIDTH, and the solve through it is SuperLU's (scipy.sparse.linalg.spsolve)."""
    planned = 0
    for a in _csr_examples():
        plan = ls._bordered_band_plan(a)
        n = a.shape[0]
        rows, cols = np.repeat(np.arange(n), np.diff(a.indptr)), a.indices
        far = np.abs(rows - cols) > band_plans.MAX_BANDWIDTH // 2
        if plan is None:
            continue
        planned += 1
        lo, up, interior, bidx = plan[:4]
        border = np.zeros(n, dtype=bool)
        border[bidx] = True
        assert np.all(border[rows[far]] | border[cols[far]])
        assert np.all(border[a.diagonal() == 0.0])
        np.testing.assert_array_equal(interior, np.flatnonzero(~border))
        pos = np.full(n, -1)
        pos[interior] = np.arange(interior.size)
        inner = ~border[rows] & ~border[cols]
        off = pos[cols[inner]] - pos[rows[inner]]
        assert -lo <= off.min() and off.max() <= up and lo + up <= band_plans.MAX_BANDWIDTH
        b = np.linspace(-1.0, 1.0, n)
        assert rel_error(ls._bordered_band_solve(a, b, plan), spla.spsolve(a.tocsc(), b)) <= 1e-10
    assert planned >= 2


def test_dense_plan_with_the_sparse_threshold_has_the_sparse_border():
    a = bordered_matrix(200).tocsr()
    sparse_plan = ls._bordered_band_plan(a)
    dense_plan = band_plans.dense_bordered_plan(a.toarray() != 0.0, far=band_plans.MAX_BANDWIDTH // 2,
                                                max_border=band_plans.MAX_BORDER)
    np.testing.assert_array_equal(dense_plan[1], sparse_plan[3])
    np.testing.assert_array_equal(dense_plan[0], sparse_plan[2])
    assert dense_plan[2:] == sparse_plan[:2]


def test_mechanism_plan_puts_every_multiplier_in_the_border():
    """The Newton pattern has no diagonal on the multipliers' rows: all eight of the slider-crank's are
    border coordinates of the packed scene's plan, and the bordered band solve of the Newton matrix the
    step writes succeeds (with a multiplier in the interior the band LU met zero pivots, failed its check
    and the dense solve ran after it)."""
    scene = sf.scenes.get("slider_crank")()
    st, res, mat, _ = newton_evaluation(scene, 1e-4)
    nf, m = scene.free_index.size, scene.n_constraints
    assert st.packed.solver == "bordered band"
    interior, border, lo, up = st.packed.plan
    assert m == 8 and set(range(nf, nf + m)) <= set(border.tolist()) and interior.size > 0
    x, ok = band_kernels.bordered_band_solve(mat, res, interior, border, lo, up)
    assert ok and rel_error(x, np.linalg.solve(mat, res)) <= 1e-12


def csr_of(a, pattern):
    """(vals, ptr, idx) of ``a`` stored on ``pattern`` (entries of a outside it dropped), with the extra last
    value of the compiled step's storage."""
    p = sps.csr_matrix(pattern.astype(np.int8))
    p.sort_indices()
    rows = np.repeat(np.arange(a.shape[0]), np.diff(p.indptr))
    vals = np.concatenate([a[rows, p.indices], [0.0]])
    return vals, p.indptr.astype(np.int64), p.indices.astype(np.int64)


@pytest.mark.parametrize("case", CASES)
def test_csr_form_matches_the_dense_form(case):
    ni, lo, up, n_frame, n_mult, frame_first = case
    for seed in range(2):
        a, pattern, border = random_bordered(ni, lo, up, n_frame, n_mult, frame_first, seed, pivoting=True)
        plan = band_plans.dense_bordered_plan(pattern)
        sparse_plan = band_plans.dense_bordered_plan(sps.csr_matrix(pattern))
        for x, y in zip(plan, sparse_plan):
            np.testing.assert_array_equal(x, y)
        rhs = np.random.default_rng(7 + seed).normal(size=a.shape[0])
        x_dense, ok_dense = band_kernels.bordered_band_solve(a, rhs, *plan)
        x, ok = band_kernels.bordered_band_solve_csr(*csr_of(a, pattern), rhs, *plan)
        assert ok and ok_dense
        np.testing.assert_array_equal(x, x_dense)             # the same elimination, the same rounding
        assert rel_error(x, np.linalg.solve(a, rhs)) <= 1e-12


def test_csr_form_reports_an_entry_outside_the_band_and_non_finite_values():
    a, pattern, border = random_bordered(40, 3, 3, 3, 2, True, seed=2, pivoting=False)
    plan = band_plans.dense_bordered_plan(pattern)
    interior = plan[0]
    rhs = np.ones(a.shape[0])
    pattern[interior[5], interior[30]] = True                 # stored, but outside the planned band
    a[interior[5], interior[30]] = 0.0
    assert band_kernels.bordered_band_solve_csr(*csr_of(a, pattern), rhs, *plan)[1]
    a[interior[5], interior[30]] = 1.0
    assert not band_kernels.bordered_band_solve_csr(*csr_of(a, pattern), rhs, *plan)[1]
    a[interior[5], interior[30]] = 0.0
    a[border[0], interior[7]] = np.nan
    assert not band_kernels.bordered_band_solve_csr(*csr_of(a, pattern), rhs, *plan)[1]
    vals, ptr, idx = csr_of(a, pattern)
    with pytest.raises(ValueError):
        band_kernels.bordered_band_solve_csr(vals, ptr[:-1], idx, rhs, *plan)
    bad = idx.copy()
    bad[3] = a.shape[0]
    with pytest.raises(ValueError):
        band_kernels.bordered_band_solve_csr(vals, ptr, bad, rhs, *plan)


def test_reordered_plan_of_a_chain():
    """A chain of 70 bars: the natural plan would put all 140 multipliers in its border, more than MAX_BORDER;
    the reordered plan is a band without border (the multipliers inside it, pivoted past by the band LU).
    The packed scene stores the Newton matrix as the values of its pattern (CSR) with that plan, and the
    solve of the matrix the step wrote is the dense solve's, from dense and from that CSR storage.

    The scene's pattern couples every coordinate a joint touches (the six of its two bars): its band is
    lo + up = 16 wide; the entries the step writes (the joints' Hessians on the angles only) give a band of
    at most 12, the half-width the chain's structure allows."""
    from test_compiled_scene import rigid_chain
    scene = rigid_chain(70)
    st, res, mat, nonzero = newton_evaluation(scene, 1e-3, dv=0.3, perturbations=2)
    packed = st.packed
    pattern = packed.pattern
    assert not (nonzero & ~pattern.toarray().astype(bool)).any()
    assert band_plans.dense_bordered_plan(pattern, max_border=band_plans.MAX_BORDER) is None
    plan = band_plans.reordered_band_plan(pattern)
    interior, border, lo, up = plan
    assert border.size == 0 and lo + up <= 16
    np.testing.assert_array_equal(np.sort(interior), np.arange(pattern.shape[0]))
    assert packed.storage == CSR and packed.solver == "bordered band (CSR)"
    for x, y in zip(packed.plan, plan):
        np.testing.assert_array_equal(x, y)
    tight = band_plans.reordered_band_plan(sps.csr_matrix(nonzero))
    assert tight[1].size == 0 and tight[2] + tight[3] <= 12
    ref = np.linalg.solve(mat, res)
    x, ok = band_kernels.bordered_band_solve(mat, res, *plan)
    assert ok and rel_error(x, ref) <= 1e-10
    # the values the step wrote into its CSR storage (the pattern's entries, in its order)
    vals = np.concatenate([st.ws.mat[:pattern.nnz], [0.0]])
    ptr, idx = pattern.indptr.astype(np.int64), pattern.indices.astype(np.int64)
    x, ok = band_kernels.bordered_band_solve_csr(vals, ptr, idx, res, *plan)
    assert ok and rel_error(x, ref) <= 1e-10
    x, ok = band_kernels.bordered_band_solve_csr(*csr_of(mat, pattern.toarray()), res, *plan)
    assert ok and rel_error(x, ref) <= 1e-10
    with pytest.raises(ValueError):
        band_plans.reordered_band_plan(np.ones((3, 4), dtype=bool))
    assert band_plans.reordered_band_plan(pattern, max_border=-1) is None


def well_conditioned_permuted(n, seed):
    """A random n × n matrix with a dominant diagonal, its rows permuted (cyclically: no diagonal entry of the
    result is its column's largest, so partial pivoting must interchange rows), and a right-hand side."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n)) + 2.0 * n * np.eye(n)
    return np.roll(a, 1, axis=0), rng.normal(size=n)


@pytest.mark.parametrize("n", [1, 2, 7, solvers.SMALL_DENSE])
def test_small_dense_lu_is_the_dense_solve(n):
    """The written-out LU of the dense solver kernel (systems up to SMALL_DENSE unknowns) solves as
    np.linalg.solve does, with row interchanges where the diagonal is not the pivot."""
    for seed in range(3):
        a, b = well_conditioned_permuted(n, seed)
        ref = np.linalg.solve(a, b)
        x = np.zeros(n)
        assert solvers.small_lu_solve(a.copy(), b.copy(), x)
        assert rel_error(x, ref) <= 1e-13
        y = b.copy()                                  # in place: x may be b
        assert solvers.small_lu_solve(a.copy(), y, y)
        np.testing.assert_array_equal(y, x)


@pytest.mark.parametrize("bad", ["equal rows", "zero column", "nan", "inf rhs"])
def test_small_dense_lu_reports_failure(bad):
    """A singular matrix (two equal rows, a zero column), a NaN entry or an infinite right-hand side: the
    written-out LU returns False (the loop then reports a singular Newton matrix), never a silent NaN."""
    a, b = well_conditioned_permuted(8, 1)
    if bad == "equal rows":
        a[5] = a[2]
    elif bad == "zero column":
        a[:, 3] = 0.0
    elif bad == "nan":
        a[4, 6] = np.nan
    else:
        b[2] = np.inf
    assert not solvers.small_lu_solve(a.copy(), b.copy(), np.zeros(8))
