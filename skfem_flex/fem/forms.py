r"""scikit-fem forms of the linear planar Timoshenko beam.

The beam carries three fields on a line mesh: axial displacement u, transverse
deflection w and cross-section rotation θ, discretised with a composite
element ``ElementLineP1() * 3`` (or P2). scikit-fem hands every form the
composite expanded, trial fields first, then test fields, then its parameter
object::

    def form(u, w, th, du, dw, dth, prm)   # bilinear
    def form(du, dw, dth, prm)             # linear

The parameter object (scikit-fem calls it ``w``) is named ``prm`` here
because ``w`` is the deflection and ``p`` the transverse load. Section values
arrive as keyword arguments of ``asm``::

    asm(axial, basis, EA=section.EA)

a scalar, or an array of shape (n_elements, n_quadrature_points) for values
that vary along the beam. ``prm.x[0]`` holds the global coordinates of the
quadrature points in m.

The energies are those of eq. (40) of Liu & Yun (Timoshenko beam, shear
strain γ = w' − θ):

.. math::

    V = \tfrac12 \int_0^l EA\,u'^2 + EI\,θ'^2 + kGA\,(w' − θ)^2 \,dx,
    \qquad
    T = \tfrac12 \int_0^l ρA\,(\dot u^2 + \dot w^2) + ρI\,\dot θ^2 \,dx,

so each bilinear form is the second variation of one term. Note that the
axial stiffness is EA ∫ u' δu' dx, as in eq. (42) of the paper; eq. (41)
carries a stray factor 1/2 on that term which would halve the axial
stiffness and is not used.
"""
from __future__ import annotations

import numpy as np
from skfem import BilinearForm, LinearForm

__all__ = [
    "axial",
    "bending",
    "shear",
    "translational_mass",
    "rotary_mass",
    "axial_load",
    "transverse_load",
]


@BilinearForm
def axial(u, w, th, du, dw, dth, prm):
    """Axial stiffness EA u' δu' (parameter ``EA`` in N); eq. (42), not (41)."""
    return prm.EA * u.grad[0] * du.grad[0]


@BilinearForm
def bending(u, w, th, du, dw, dth, prm):
    """Bending stiffness EI θ' δθ' (parameter ``EI`` in N·m²)."""
    return prm.EI * th.grad[0] * dth.grad[0]


@BilinearForm
def shear(u, w, th, du, dw, dth, prm):
    """Shear stiffness kGA (w' − θ)(δw' − δθ) (parameter ``kGA`` in N).

    Assemble it on a reduced rule (one Gauss point per P1 element, two per P2
    element) to avoid shear locking of slender beams.
    """
    return prm.kGA * (w.grad[0] - th) * (dw.grad[0] - dth)


@BilinearForm
def translational_mass(u, w, th, du, dw, dth, prm):
    """Consistent translational mass ρA (u δu + w δw) (parameter ``rhoA`` in kg/m)."""
    return prm.rhoA * (u * du + w * dw)


@BilinearForm
def rotary_mass(u, w, th, du, dw, dth, prm):
    """Consistent rotary mass ρI θ δθ (parameter ``rhoI`` in kg·m)."""
    return prm.rhoI * th * dth


def _load_at(load, x, name):
    """Distributed load at the quadrature points: a constant or ``load(x)``."""
    value = load(x) if callable(load) else load
    value = np.broadcast_to(np.asarray(value, dtype=float), x.shape)
    if not np.all(np.isfinite(value)):
        raise ValueError(f"distributed load {name} must be finite, got {value!r}")
    return value


def axial_load(f):
    """Linear form of a distributed axial load, ∫ f δu dx (first term of eq. 43).

    Parameters
    ----------
    f : float or callable
        Axial force per unit length in N/m, a constant or a function of the
        coordinate x (m) that accepts and returns arrays.

    Returns
    -------
    skfem.LinearForm
    """

    @LinearForm
    def distributed_axial_load(du, dw, dth, prm):
        return _load_at(f, prm.x[0], "f") * du

    return distributed_axial_load


def transverse_load(p):
    """Linear form of a distributed transverse load, ∫ p δw dx (third term of eq. 43).

    Parameters
    ----------
    p : float or callable
        Transverse force per unit length in N/m, a constant or a function of
        the coordinate x (m) that accepts and returns arrays.

    Returns
    -------
    skfem.LinearForm
    """

    @LinearForm
    def distributed_transverse_load(du, dw, dth, prm):
        return _load_at(p, prm.x[0], "p") * dw

    return distributed_transverse_load
