r"""scikit-fem forms of the linear spatial Timoshenko beam.

The beam carries six fields on a line mesh over its arc length s, all in the section's axes (d₁, d₂ the
principal axes, d₃ the beam axis): the displacements u₁, u₂, u₃ and the small rotations θ₁, θ₂, θ₃ about
d₁, d₂, d₃, discretised with the composite element ``ElementLineP1() * 6`` (or P2). scikit-fem hands every
bilinear form the trial fields, then the test fields, then its parameter object::

    def form(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm)

The strains are the linearization of the geometrically exact beam's (docs/spatial_beams.md) about the
straight reference:

.. math::

    Γ_1 = u_1' − θ_2, \quad Γ_2 = u_2' + θ_1, \quad Γ_3 = u_3', \qquad K_i = θ_i',

and the energies

.. math::

    V = ½ \int kGA₁ Γ₁² + kGA₂ Γ₂² + EA Γ₃² + EI₁ θ₁'² + EI₂ θ₂'² + GJ θ₃'² \, ds,

    T = ½ \int ρA (\dot u₁² + \dot u₂² + \dot u₃²) + ρI₁ \dot θ₁² + ρI₂ \dot θ₂² + (ρI₁ + ρI₂) \dot θ₃² \, ds,

so each bilinear form below is the second variation of one term. Assemble ``shear`` on the reduced rule
(one Gauss point per P1 element, two per P2 element) against shear locking.
"""
from __future__ import annotations

from skfem import BilinearForm, LinearForm

__all__ = ["axial", "torsion", "bending", "shear", "mass", "distributed_load", "centrifugal_tension",
           "centrifugal_softening", "coriolis"]


@BilinearForm
def axial(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """EA u₃' δu₃' (parameter ``EA``, N)."""
    return prm.EA * u3.grad[0] * v3.grad[0]


@BilinearForm
def torsion(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """GJ θ₃' δθ₃' (parameter ``GJ``, N m²)."""
    return prm.GJ * t3.grad[0] * s3.grad[0]


@BilinearForm
def bending(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """EI₁ θ₁' δθ₁' + EI₂ θ₂' δθ₂' (parameters ``EI1``, ``EI2``, N m²)."""
    return prm.EI1 * t1.grad[0] * s1.grad[0] + prm.EI2 * t2.grad[0] * s2.grad[0]


@BilinearForm
def shear(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """kGA₁ (u₁' − θ₂)(δu₁' − δθ₂) + kGA₂ (u₂' + θ₁)(δu₂' + δθ₁) (parameters ``GA1``, ``GA2``, N)."""
    return (prm.GA1 * (u1.grad[0] - t2) * (v1.grad[0] - s2)
            + prm.GA2 * (u2.grad[0] + t1) * (v2.grad[0] + s1))


@BilinearForm
def mass(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """ρA u·δu + ρI₁ θ₁ δθ₁ + ρI₂ θ₂ δθ₂ + (ρI₁ + ρI₂) θ₃ δθ₃ (parameters ``rhoA`` kg/m, ``rhoI1``,
    ``rhoI2`` kg m)."""
    return (prm.rhoA * (u1 * v1 + u2 * v2 + u3 * v3) + prm.rhoI1 * t1 * s1 + prm.rhoI2 * t2 * s2
            + (prm.rhoI1 + prm.rhoI2) * t3 * s3)


@LinearForm
def distributed_load(v1, v2, v3, s1, s2, s3, prm):
    """f·δu + m·δθ per length (parameters ``f1, f2, f3`` N/m and ``m1, m2, m3`` N m/m)."""
    return (prm.f1 * v1 + prm.f2 * v2 + prm.f3 * v3 + prm.m1 * s1 + prm.m2 * s2 + prm.m3 * s3)


@BilinearForm
def centrifugal_tension(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """N(s) (u₁' δu₁' + u₂' δu₂'): the geometric stiffness of the centrifugal tension of a beam spinning at Ω
    about an axis through the hub (radius ``r``) normal to it, N(s) = ρA Ω² (r (L − s) + (L² − s²)/2)
    (parameters ``rhoA``, ``Omega`` rad/s, ``r``, ``L`` m; s = ``prm.x[0]``)."""
    s = prm.x[0]
    N = prm.rhoA * prm.Omega ** 2 * (prm.r * (prm.L - s) + 0.5 * (prm.L ** 2 - s ** 2))
    return N * (u1.grad[0] * v1.grad[0] + u2.grad[0] * v2.grad[0])


@BilinearForm
def centrifugal_softening(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """ρA (u₂ δu₂ + u₃ δu₃): times Ω², the centrifugal force of displacements in the plane of rotation (normal
    to the spin axis d₁) (parameter ``rhoA``)."""
    return prm.rhoA * (u2 * v2 + u3 * v3)


@BilinearForm
def coriolis(u1, u2, u3, t1, t2, t3, v1, v2, v3, s1, s2, s3, prm):
    """ρA (u₂ δu₃ − u₃ δu₂): times 2Ω and applied to the velocities, the Coriolis force 2ρA Ω d₁ × u̇ of a
    spin about d₁ (parameter ``rhoA``)."""
    return prm.rhoA * (u2 * v3 - u3 * v2)
