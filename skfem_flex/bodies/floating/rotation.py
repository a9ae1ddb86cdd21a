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

from ..base import to_dense

__all__ = ["centrifugal_equilibrium", "rotating_modes"]


def centrifugal_equilibrium(body, omega, tol=1e-12, max_iterations=50):
    """Static elastic state q_f of ``body`` turning at constant ω (rad/s) with R fixed.

    Solves ∇V(q_f) = ω² (c + M_A q_f) (centrifugal load, eq. 26) by Newton with the
    tangent K_T(q_f) − ω² M_A, from q_f = 0, to ``tol`` relative to the largest centrifugal load.

    Returns
    -------
    ndarray (n_elastic,)

    Raises
    ------
    ValueError
        If ω is not finite or Newton does not converge (e.g. beyond a divergence speed).
    """
    om = float(omega)
    if not np.isfinite(om):
        raise ValueError(f"omega must be finite, got {omega!r}")
    q = body.q0.copy()
    q[3:] = 0.0
    MA = body._MA
    for _ in range(max_iterations):
        r = body.potential_gradient(q)[3:] - om * om * (body._c + MA @ q[3:])
        K = body.potential_hessian(q)[3:, 3:] - om * om * MA
        scale = max(np.abs(om * om * body._c).max(), 1e-300)
        if np.abs(r).max() <= tol * scale:
            return q[3:].copy()
        dq = spla.spsolve(sps.csc_matrix(K), r) if sps.issparse(K) else np.linalg.solve(K, r)
        q[3:] -= dq
    raise ValueError(f"centrifugal equilibrium at omega = {om} did not converge")


def rotating_modes(body, omega, n_modes=3, bending_only=True):
    """Natural frequencies (rad/s) of ``body`` in the frame turning at constant ω, about the stretched state.

    Linearisation of the elastic equations (R fixed, θ̇ = ω)::

        M_ff δq̈ + 2ω H δq̇ + (K_T(q_f*) − ω² M_A) δq = 0

    with K_T the tangent stiffness at the centrifugal equilibrium q_f* (for the
    Green–Lagrange strain it holds the geometric stiffness N δw'² — the centrifugal
    stiffening), −ω² M_A the centrifugal softening (its transverse part is the "−1" of
    in-plane bending) and 2ωH the Coriolis (gyroscopic) coupling of axial and transverse
    motion. Solved as a dense first-order eigenproblem; frequencies are the positive imaginary
    parts. With ``bending_only`` modes whose kinetic energy is mostly axial are skipped.

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
    K = body.potential_hessian(q)[3:, 3:]
    K = (K.toarray() if sps.issparse(K) else K) - om * om * to_dense(body._MA)
    M = to_dense(body._Mff)
    G = 2.0 * om * to_dense(body._H)
    nf = body.n_elastic
    I = np.eye(nf)
    Z = np.zeros((nf, nf))
    a = np.block([[Z, I], [-K, -G]])
    bm = np.block([[I, Z], [Z, M]])
    lam, vec = sla.eig(a, bm)
    finite = np.isfinite(lam)                   # ρI = 0 leaves infinite eigenvalues
    lam, vec = lam[finite], vec[:, finite]
    keep = lam.imag > 1e-9 * max(1.0, np.abs(lam).max())
    lam, vec = lam[keep], vec[:nf, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    if bending_only:
        d = np.zeros((body.beam.n_dofs, vec.shape[1]), dtype=complex)
        d[body.free_dofs] = vec
        ax = np.sum(np.abs(d[body.beam.node_dofs[:, 0]]) ** 2, axis=0)
        tr = np.sum(np.abs(d[body.beam.node_dofs[:, 1]]) ** 2, axis=0)
        sel = tr > ax
        lam, vec = lam[sel], vec[:, sel]
    if lam.size < n_modes:
        raise ValueError(f"only {lam.size} modes available, asked for {n_modes}")
    # turn each eigenvector so that its largest entry is real, then keep the real part
    shapes = np.real(vec[:, :n_modes] * np.exp(-1j * np.angle(vec[np.argmax(np.abs(vec[:, :n_modes]), axis=0),
                                                                    np.arange(n_modes)])))
    shapes /= np.abs(shapes).max(axis=0)
    return lam.imag[:n_modes].copy(), shapes
