r"""Inertia integrals of a :class:`~skfem_flex.bodies.FloatingBeam`, assembled once by scikit-fem.

The floating-frame mass matrix M(q) is fixed by a handful of invariants (table in ``ffr.py``);
for a beam with axial/transverse shape functions S = [N_u; N_w] and section rotation N_φ they are

m = ∫ρA, S_0 = (∫ρA x, 0), I_0 = ∫ρA x² + J_r with J_r = ∫ρI, S̄ = ∫ρA S, c = ∫ρA Sᵀx_0,
k_0n = ∫ρA SᵀE x_0 + ∫ρI N_φ, M_A = ∫ρA SᵀS, H = ∫ρA SᵀE S, M_ff = M_A + ∫ρI N_φᵀN_φ,

all on the elastic coordinates q_f a reference condition leaves (``floating_reference.py``).
The matrices come from two forms of ``forms.py`` and :data:`skew_inertia`; the vectors from one
linear form, :data:`axis_moments`, with different coefficients; the scalars from the beam's
quadrature arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import BilinearForm, LinearForm, asm

from ...fem.forms import rotary_mass, translational_mass
from .reference import restrict

__all__ = ["BeamInertia", "beam_inertia", "skew_inertia", "axis_moments"]


# ---------------------------------------------------------------- scikit-fem forms (assembled once)
@BilinearForm
def skew_inertia(u, w, th, du, dw, dth, prm):
    """ρA (δu, δw)·E(u, w) = ρA (δw u − δu w): the skew coupling H = ∫ρA SᵀE S (parameter ``rhoA``)."""
    return prm.rhoA * (dw * u - du * w)


@LinearForm
def axis_moments(du, dw, dth, prm):
    """∫ (a_u δu + a_w δw + a_θ δθ) with a_k = α_k + β_k x (parameters ``au, bu, aw, bw, at``).

    Gives ∫ρA N (β = 0), ∫ρA x N (α = 0) and ∫ρI N_φ."""
    x = prm.x[0]
    return (prm.au + prm.bu * x) * du + (prm.aw + prm.bw * x) * dw + prm.at * dth


@dataclass(frozen=True, eq=False)
class BeamInertia:
    """The inertia invariants of a beam on its elastic coordinates (module docstring), the arguments
    of :meth:`FloatingFrame.set_invariants <skfem_flex.bodies.ffr.FloatingFrame.set_invariants>`.

    Attributes
    ----------
    mass : float
        m, kg.
    S0 : ndarray (2,)
        First moment of the undeformed beam about the frame origin, kg m.
    I0 : float
        Polar moment ∫ρA x² + ∫ρI about the frame origin, kg m².
    Sbar : ndarray (2, n_elastic)
        S̄, kg (S is dimensionless: u and w per unit nodal u and w).
    c, k0n : ndarray (n_elastic,)
        Centrifugal load per unit ω² and rotation–elastic coupling, kg m.
    MA, H, Mff : ndarray or csr_matrix (n_elastic, n_elastic)
        Translational elastic mass, skew coupling and elastic mass (kg on u, w; ρI terms kg m² on φ);
        CSR for sparse bodies.
    """

    mass: float
    S0: np.ndarray
    I0: float
    Sbar: np.ndarray
    c: np.ndarray
    k0n: np.ndarray
    MA: object
    H: object
    Mff: object


def beam_inertia(beam, free, sparse):
    """Assemble the :class:`BeamInertia` of ``beam`` on the beam DOFs ``free``.

    Parameters
    ----------
    beam : TimoshenkoBeam
    free : ndarray of int
        Beam DOFs of q_f (``ElasticCoordinates.free_dofs``).
    sparse : bool
        Keep M_A, H, M_ff as CSR (else dense arrays).

    Raises
    ------
    ValueError
        If mass or inertia overflow double precision (a beam far from SI sizes).
    """
    sec = beam.section
    b = beam.basis
    MA = restrict(asm(translational_mass, b, rhoA=sec.rhoA), free)
    MI = restrict(asm(rotary_mass, b, rhoI=sec.rhoI), free)
    H = restrict(asm(skew_inertia, b, rhoA=sec.rhoA), free)
    zero = dict(au=0.0, bu=0.0, aw=0.0, bw=0.0, at=0.0)
    lin = lambda **kw: asm(axis_moments, b, **{**zero, **kw})[free]   # noqa: E731
    Nu, Nw = lin(au=sec.rhoA), lin(aw=sec.rhoA)
    k0 = lin(bw=sec.rhoA)                             # ∫ρA Sᵀ E x0 = ∫ρA x N_w
    nphi = lin(at=sec.rhoI)                           # ∫ρI N_φ
    qd = beam.quadrature
    I00 = float(np.sum(sec.rhoA * qd.x ** 2 * qd.dx))
    Jr = float(np.sum(sec.rhoI * qd.dx))
    dense = (lambda m: m) if sparse else (lambda m: m.toarray())   # noqa: E731
    mass, s0x, c = float(np.sum(sec.rhoA * qd.dx)), float(np.sum(sec.rhoA * qd.x * qd.dx)), lin(bu=sec.rhoA)
    if not all(np.isfinite([mass, s0x, I00 + Jr])) or not np.all(np.isfinite(c)):
        raise ValueError(f"the beam's mass and inertia overflow double precision (length {beam.length:g} m, "
                         f"rhoA = {sec.rhoA:g} kg/m, rhoI = {sec.rhoI:g} kg m): give SI values of a physical size")
    return BeamInertia(mass=mass, S0=np.array([s0x, 0.0]), I0=I00 + Jr, Sbar=np.vstack([Nu, Nw]), c=c,
                       k0n=k0 + nphi, MA=dense(MA), H=dense(H), Mff=dense((MA + MI).tocsr()))
