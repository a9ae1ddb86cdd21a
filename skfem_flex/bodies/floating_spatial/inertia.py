r"""Inertia shape integrals of a spatial floating-frame beam, assembled once by scikit-fem.

The beam lies along the frame's third axis: a point of the axis at arc length s sits at
X₀(s) = (0, 0, s) in the frame and moves to ρ(s) = X₀ + S(s) y, S the shape functions of the
elastic displacements (u₁, u₂, u₃) on the elastic coordinates y. Its section turns by θ(s) = N_θ(s) y
(small), so the section's directors are e_k + θ × e_k = e_k + Θ_k y with Θ_k = −[e_k]_× N_θ. With the
frame's directors D = [d₁ d₂ d₃] the kinetic energy (``kinetics.py``) needs only

.. math::

    m = ∫ρA,\quad S_0 = ∫ρA X_0,\quad \bar S_k = ∫ρA S_k,\quad
    I_0 = ∫ρA X_0X_0^T + ∫\operatorname{diag}(E),

    P_{ik} = ∫ρA X_{0i} S_k + ∫E_{ii} (Θ_i)_k,\qquad
    N_{ik} = ∫ρA S_i^T S_k + \sum_j ∫E_{jj} (Θ_j)_i^T (Θ_j)_k,

where S_k is row k of S, (Θ_j)_i row i of Θ_j, and E = diag(ρI₂, ρI₁, 0) the section's Euler tensor per
length (a thin section has no extent along the axis). All six fields share one scalar basis, so every
integral is a slice of three scalar arrays: ∫N_a N_b ds, ∫N_a ds and ∫s N_a ds.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import BilinearForm, LinearForm, asm

__all__ = ["SpatialFrameInertia", "spatial_frame_inertia", "projected_inertia", "LEVI_CIVITA"]

#: ε_ijk
LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    LEVI_CIVITA[_i, _j, _k], LEVI_CIVITA[_i, _k, _j] = 1.0, -1.0


@BilinearForm
def _scalar_mass(u, v, w):
    return u * v


@LinearForm
def _scalar_moment(v, w):
    """∫ (α + β s) N_a (parameters ``alpha``, ``beta``)."""
    return (w.alpha + w.beta * w.x[0]) * v


@dataclass(frozen=True, eq=False)
class SpatialFrameInertia:
    """The inertia invariants of a spatial floating-frame beam on its elastic coordinates y (module docstring).

    Attributes
    ----------
    mass : float
        m, kg.
    S0 : ndarray (3,)
        First moment of the undeformed axis about the frame origin, kg m.
    Sbar : ndarray (3, n_elastic)
        S̄_k, kg.
    I0 : ndarray (3, 3)
        Second moments of the undeformed beam (axis and sections), kg m².
    P : ndarray (3, 3, n_elastic)
        P_ik, kg m.
    N : ndarray (3, 3, n_elastic, n_elastic)
        N_ik, kg (N_ki = N_ikᵀ); Σ_k N_kk is the beam's consistent mass on y.
    """

    mass: float
    S0: np.ndarray
    Sbar: np.ndarray
    I0: np.ndarray
    P: np.ndarray
    N: np.ndarray


def spatial_frame_inertia(beam, free):
    """The :class:`SpatialFrameInertia` of a :class:`~skfem_flex.fem.spatial_beam.TimoshenkoBeam3D` on its DOFs
    ``free`` (the elastic coordinates a reference condition leaves)."""
    sec = beam.section
    fb = beam.field_basis
    field_dofs = np.array(beam.basis.split_indices())          # (6, n_scalar): vector DOF of each scalar DOF
    Ms = asm(_scalar_mass, fb).toarray()
    m1 = asm(_scalar_moment, fb, alpha=1.0, beta=0.0)
    ms = asm(_scalar_moment, fb, alpha=0.0, beta=1.0)
    n = beam.n_dofs
    length = beam.length
    s_lo, s_hi = float(beam.x_nodes[0]), float(beam.x_nodes[-1])
    E = np.array([sec.rhoI2, sec.rhoI1, 0.0])                   # the section's Euler tensor per length

    Sbar = np.zeros((3, n))
    P = np.zeros((3, 3, n))
    N = np.zeros((3, 3, n, n))
    u, th = field_dofs[:3], field_dofs[3:]
    for k in range(3):
        Sbar[k, u[k]] = sec.rhoA * m1
        P[2, k, u[k]] += sec.rhoA * ms
        for i in range(3):
            N[i, k][np.ix_(u[i], u[k])] += sec.rhoA * Ms
    eps = LEVI_CIVITA
    for i in range(3):
        for j in range(3):
            for ell in range(3):
                # (Θ_i)_j = −Σ_l ε_{j i l} N_θl: the rotation θ moves director e_i by θ × e_i
                if eps[j, i, ell] != 0.0 and E[i] != 0.0:
                    P[i, j, th[ell]] -= E[i] * eps[j, i, ell] * m1
                for m in range(3):
                    c = sum(E[k] * eps[i, k, ell] * eps[j, k, m] for k in range(3))
                    if c != 0.0:
                        N[i, j][np.ix_(th[ell], th[m])] += c * Ms
    I0 = np.diag(E * length)
    I0[2, 2] += sec.rhoA * (s_hi ** 3 - s_lo ** 3) / 3.0
    S0 = np.array([0.0, 0.0, sec.rhoA * 0.5 * (s_hi ** 2 - s_lo ** 2)])
    return SpatialFrameInertia(mass=sec.rhoA * length, S0=S0, Sbar=np.ascontiguousarray(Sbar[:, free]), I0=I0,
                               P=np.ascontiguousarray(P[:, :, free]),
                               N=np.ascontiguousarray(N[:, :, free][:, :, :, free]))


def projected_inertia(inv, basis):
    """The invariants on reduced coordinates η, y = Φ η: S̄Φ, PΦ and ΦᵀN_ikΦ (m, S₀ and I₀ stay)."""
    Phi = np.asarray(basis, dtype=float)
    return SpatialFrameInertia(mass=inv.mass, S0=inv.S0, Sbar=inv.Sbar @ Phi, I0=inv.I0, P=inv.P @ Phi,
                               N=np.einsum("am,ikab,bn->ikmn", Phi, inv.N, Phi))
