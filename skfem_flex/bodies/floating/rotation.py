r"""Steady rotation of a :class:`~skfem_flex.bodies.FloatingBeam`: centrifugal equilibrium and rotating modes.

Beside the time loop: with the frame origin fixed and θ̇ = ω constant, the elastic equations of
motion (eq. 26) reduce to

    M_ff q̈_f + 2ω H q̇_f + ∇V(q_f) − ω² (c + M_A q_f) = 0,

whose static solution is the stretched state of a spinning beam (:func:`centrifugal_equilibrium`)
and whose linearisation about it gives the frequencies seen in the rotating frame
(:func:`rotating_modes`): the classic check of centrifugal stiffening (the Green–Lagrange strain
puts it in the tangent K_T; the linear strain misses it).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from ...errors import ConvergenceError
from ...numerics.newton import NewtonSettings, newton_solve
from ..base import to_dense

__all__ = ["centrifugal_equilibrium", "rotating_modes", "DENSE_MODES_LIMIT"]

_EPS = np.finfo(float).eps
_TINY = 1e-300
#: bodies with at most this many elastic coordinates get their rotating modes from a dense
#: eigensolve of the whole first-order system; larger ones from ARPACK in shift-invert mode about
#: zero, which finds the few lowest modes of a 2000-element beam in a fraction of a second (the
#: dense solve of its 12000 × 12000 first-order system would take many minutes)
DENSE_MODES_LIMIT = 150
#: the load stepping in ω² gives up when its step falls below this fraction of ω²
_MIN_LOAD_STEP = 1e-6


def _centrifugal_system(body, omega2, tol):
    """fun(x) -> (r, J, err) of the centrifugal balance at ω² = ``omega2`` for :func:`newton_solve`.

    r = ∇V(q_f) − ω² (c + M_A q_f), J = K_T(q_f) − ω² M_A, and the scaled error

        err = ‖r‖∞ / (tol · max(‖∇V‖∞, ‖ω²(c + M_A q_f)‖∞) + 16 ε ‖ |K_T| |q_f| ‖∞),

    the residual against the largest term of the balance it checks plus the round-off floor of the
    internal forces (differences of terms |K_T| |q_f| far larger than their sum). A fixed fraction
    of the centrifugal load alone is no size-independent test: the nodal loads shrink with the
    element length while the round-off of K q grows with the stiffness EA/h, so a tolerance that
    holds on 100 elements is below round-off on 101 or more.
    """
    MA, c = body.invariants.MA, body.invariants.c
    q = body.q0.copy()

    def fun(x):
        q[3:] = x
        grad = body.potential_gradient(q)[3:]
        hess = body.potential_hessian(q)[3:, 3:]
        load = omega2 * (c + MA @ x)
        r = grad - load
        jac = hess - omega2 * MA
        if sps.issparse(jac):
            jac = sps.csr_matrix(jac)
        floor = float(np.max(abs(hess) @ np.abs(x), initial=0.0))
        scale = max(float(np.max(np.abs(grad), initial=0.0)), float(np.max(np.abs(load), initial=0.0)))
        err = float(np.max(np.abs(r), initial=0.0)) / (tol * scale + 16 * _EPS * floor + _TINY)
        return r, jac, err

    return fun


def centrifugal_equilibrium(body, omega, tol=1e-12, max_iterations=50):
    r"""Static elastic state q_f of ``body`` turning at constant ω (rad/s) with R fixed.

    Solves the centrifugal balance (eq. 26 at rest in the turning frame)

    .. math::  ∇V(q_f) = ω² (c + M_A q_f)

    by the package's Newton core (:func:`~skfem_flex.numerics.newton.newton_solve`) with the
    tangent K_T(q_f) − ω² M_A, from q_f = 0. Converged when ‖r‖∞ ≤ ``tol`` times the largest
    term of the balance (N) plus the round-off floor of the internal forces, so the test means
    the same on 1 element and on 2000. If the direct solve fails, the load is stepped: the
    balance is solved at ω_s² = s ω² for s rising from 0 to 1, each solve starting from the last,
    the step halved on failure and grown on success (continuation in ω²).

    Parameters
    ----------
    body : FloatingBeam
    omega : float
        Spin rate ω, rad/s.
    tol : float
        Relative tolerance of the balance, in (0, 1).
    max_iterations : int
        Newton iterations per solve.

    Returns
    -------
    ndarray (n_elastic,)
        q_f, m (and rad for section rotations).

    Raises
    ------
    ValueError
        If ω is not finite, or the balance cannot be followed to ω (e.g. beyond a divergence
        speed of the linear strain); the message names the spin rate reached.
    """
    om = float(omega)
    if not np.isfinite(om):
        raise ValueError(f"omega must be finite, got {omega!r}")
    settings = NewtonSettings(rtol=float(tol), max_iterations=int(max_iterations))
    x = np.zeros(body.n_elastic)
    target = om * om

    def solve(s, start):
        return newton_solve(_centrifugal_system(body, s * target, settings.rtol), start, settings,
                            "centrifugal equilibrium", f"omega = {np.sqrt(s) * abs(om):.6g} rad/s")[0]

    try:
        return solve(1.0, x).copy()
    except ConvergenceError:
        pass
    s, ds, last = 0.0, 0.25, None
    while s < 1.0:
        s_try = min(1.0, s + ds)
        try:
            x_new = solve(s_try, x)
        except ConvergenceError as exc:
            last = exc
            ds *= 0.5
            if ds < _MIN_LOAD_STEP:
                raise ValueError(f"centrifugal equilibrium at omega = {om} did not converge: the load stepping in "
                                 f"omega^2 reached omega = {np.sqrt(s) * abs(om):.6g} rad/s and could go no "
                                 f"further (beyond a divergence speed?): {last}") from None
            continue
        s, x = s_try, x_new
        ds = min(2.0 * ds, 1.0)
    return x.copy()


def rotating_modes(body, omega, n_modes=3, bending_only=True):
    """Natural frequencies (rad/s) of ``body`` in the frame turning at constant ω, about the stretched state.

    Linearisation of the elastic equations (R fixed, θ̇ = ω)::

        M_ff δq̈ + 2ω H δq̇ + (K_T(q_f*) − ω² M_A) δq = 0

    with K_T the tangent stiffness at the centrifugal equilibrium q_f* (for the
    Green–Lagrange strain it holds the geometric stiffness N δw'² — the centrifugal
    stiffening), −ω² M_A the centrifugal softening (its transverse part is the "−1" of
    in-plane bending) and 2ωH the Coriolis (gyroscopic) coupling of axial and transverse
    motion. Solved as a first-order eigenproblem, dense up to :data:`DENSE_MODES_LIMIT` elastic
    coordinates, else by ARPACK in shift-invert mode about zero (the lowest modes only);
    frequencies are the positive imaginary parts. With ``bending_only`` modes whose kinetic
    energy is mostly axial are skipped.

    Returns
    -------
    omega_n : ndarray (n_modes,)
        Frequencies in rad/s, ascending.
    shapes : ndarray (n_elastic, n_modes)
        Real parts of the displacement eigenvectors (normalised to unit max).

    Raises
    ------
    ValueError
        If fewer than ``n_modes`` modes are found (or as :func:`centrifugal_equilibrium`).
    """
    om = float(omega)
    qf = centrifugal_equilibrium(body, om)
    q = body.q0.copy()
    q[3:] = qf
    K = body.potential_hessian(q)[3:, 3:] - om * om * body.invariants.MA
    nf = body.n_elastic
    lam = None
    if nf > DENSE_MODES_LIMIT:
        lam, vec = _lowest_modes_sparse(body, K, om, n_modes, bending_only)
    if lam is None:
        lam, vec = _modes_dense(body, to_dense(K), om)
        lam, vec = _bending(body, lam, vec, bending_only)
    if lam.size < n_modes:
        raise ValueError(f"only {lam.size} modes available, asked for {n_modes}")
    # turn each eigenvector so that its largest entry is real, then keep the real part
    shapes = np.real(vec[:, :n_modes] * np.exp(-1j * np.angle(vec[np.argmax(np.abs(vec[:, :n_modes]), axis=0),
                                                                    np.arange(n_modes)])))
    shapes /= np.abs(shapes).max(axis=0)
    return lam.imag[:n_modes].copy(), shapes


def _oscillating(lam, vec, nf):
    """The eigenpairs with positive frequency (Im s > 0), ascending, displacement part only."""
    finite = np.isfinite(lam)                   # ρI = 0 leaves infinite eigenvalues
    lam, vec = lam[finite], vec[:, finite]
    keep = lam.imag > 1e-9 * max(1.0, float(np.abs(lam).max(initial=0.0)))
    lam, vec = lam[keep], vec[:nf, keep]
    order = np.argsort(lam.imag)
    return lam[order], vec[:, order]


def _bending(body, lam, vec, bending_only):
    """Drop the modes whose displacement is mostly axial (with ``bending_only``)."""
    if not bending_only or lam.size == 0:
        return lam, vec
    d = np.zeros((body.beam.n_dofs, vec.shape[1]), dtype=complex)
    d[body.free_dofs] = vec
    ax = np.sum(np.abs(d[body.beam.node_dofs[:, 0]]) ** 2, axis=0)
    tr = np.sum(np.abs(d[body.beam.node_dofs[:, 1]]) ** 2, axis=0)
    sel = tr > ax
    return lam[sel], vec[:, sel]


def _modes_dense(body, K, om):
    """All eigenpairs of [[0, I], [−K, −G]] z = s [[I, 0], [0, M]] z (G = 2ωH), oscillating ones kept."""
    M = to_dense(body.invariants.Mff)
    G = 2.0 * om * to_dense(body.invariants.H)
    nf = body.n_elastic
    I = np.eye(nf)
    Z = np.zeros((nf, nf))
    a = np.block([[Z, I], [-K, -G]])
    bm = np.block([[I, Z], [Z, M]])
    lam, vec = sla.eig(a, bm)
    return _oscillating(lam, vec, nf)


def _lowest_modes_sparse(body, K, om, n_modes, bending_only):
    """The lowest oscillating eigenpairs by ARPACK in shift-invert mode about s = 0.

    Below every divergence speed K = K_T − ω² M_A is positive definite, and with z = (q̇, q) the
    equations take the form A z = s B z with A = [[−G, −K], [K, 0]] skew-symmetric (G = 2ωH is
    skew) and B = diag(M_ff, K) symmetric positive (semi)definite: in the B inner product the
    operator A⁻¹B is skew-adjoint, its eigenvalues 1/s lie on the imaginary axis and Arnoldi
    converges on the largest (the lowest frequencies) in a few dozen steps. A⁻¹ needs one
    factorisation of K: A w = b gives w_q̇ = K⁻¹ b_q and w_q = −K⁻¹(b_q̇ + G w_q̇).
    More eigenvalues are asked for until ``n_modes`` (bending) modes are among them. Returns
    (None, None) when K is not positive definite (beyond a divergence speed) or ARPACK fails,
    for the dense solve to take over.
    """
    nf = body.n_elastic
    K = sps.csc_matrix(K)
    M = sps.csr_matrix(body.invariants.Mff)
    G = sps.csr_matrix(2.0 * om * body.invariants.H)
    try:
        # no pivoting and one symmetric permutation: U's diagonal holds the pivots of a symmetric
        # LDLᵀ, whose signs are the signs of K's eigenvalues (Sylvester's law of inertia)
        lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:                        # a zero pivot: singular, or indefinite
        return None, None
    if not (np.array_equal(lu.perm_r, lu.perm_c) and np.all(lu.U.diagonal() > 0.0)):
        return None, None

    def inverse(b):
        w_v = lu.solve(np.ascontiguousarray(b[nf:]))
        w_q = -lu.solve(np.asarray(b[:nf] + G @ w_v))
        return np.concatenate([w_v, w_q])

    a = sps.bmat([[-G, -K], [K, None]], format="csr")
    b = sps.block_diag([M, K], format="csr")
    op_inv = spla.LinearOperator((2 * nf, 2 * nf), matvec=inverse, dtype=float)
    k = 2 * n_modes + 6
    while k < 2 * nf - 1:
        try:
            found, vec = spla.eigs(a, k=k, M=b, sigma=0.0, OPinv=op_inv, which="LM")
        except spla.ArpackError:
            return None, None
        lam, vec = _bending(body, *_oscillating(found, vec[nf:], nf), bending_only)
        # the modes found are the lowest ones only below the largest |s| found (the next one may
        # be the partner of that one, of equal |s|)
        if lam.size >= n_modes and np.abs(lam[n_modes - 1]) < np.abs(found).max() * (1 - 1e-9):
            return lam, vec
        k *= 2
    return None, None
