r"""Strain energy of a :class:`~skfem_flex.bodies.FloatingBeam`: constant stiffness and the axial kernel.

V(q_f) = ½ q_fᵀ K q_f + ½ Σ_k EA dx_k ε_k² with K the bending (EI κ², κ = φ') and shear
(kGA γ², γ = w' − φ) stiffness of the linear beam, assembled once by scikit-fem. The axial
strain ε = u' + ½(u'² + w'²) (Green–Lagrange) is evaluated at the beam's quadrature points k by a
few matrix products on precomputed arrays (:class:`AxialQuadrature`), vectorised over elements:
nothing is assembled in the time loop. With ``strain="linear"`` the axial part ε = u' is in K
and the kernel is not used (the compiled kernel in ``floating_kernel.py`` does the same
arithmetic; these numpy functions are its reference).

With D = [D_u; D_w] mapping q_f to (u', w') at the points, the strain derivative is
dε = diag(1 + u') D_u + diag(w') D_w and d²ε = D_uᵀD_u + D_wᵀD_w (constant), so

    ∇V_ax = dεᵀ (EA dx ε),   ∇²V_ax = dεᵀ diag(EA dx) dε + Σ_k EA dx_k ε_k d²ε_k.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps
from skfem import asm

from ...fem.forms import bending, shear
from .reference import restrict

__all__ = ["AxialQuadrature", "axial_quadrature", "elastic_stiffness", "axial_derivatives", "axial_gradient",
           "axial_element_tangent", "section_strains", "element_strain_energy"]


def elastic_stiffness(beam, free, strain):
    """Constant stiffness K on q_f (CSR), N/m, N, N m per rad.

    ``strain="linear"``: the beam's whole stiffness (axial EA u'² included). ``"green-lagrange"``:
    bending and shear only; the axial part is the nonlinear kernel of this module.
    """
    sec = beam.section
    if strain == "linear":
        return restrict(beam.stiffness(), free)
    return restrict(asm(bending, beam.basis, EI=sec.EI) + asm(shear, beam.shear_basis, kGA=sec.kGA), free)


@dataclass(frozen=True, eq=False)
class AxialQuadrature:
    """The precomputed arrays of the axial kernel and of the output strains (built by :func:`axial_quadrature`).

    Attributes
    ----------
    eu, ew, eth : ndarray of int (n_el, n_l)
        Beam DOFs of u, w, φ of each element's local shape functions.
    dN : ndarray (n_l, n_el, n_qp)
        dN/dx at the axial quadrature points, 1/m (one point per element for P1 elements: u', w'
        are constant there, so one point is exact).
    dx : ndarray (n_el, n_qp)
        Quadrature weights, m.
    shear : quadrature arrays
        The beam's shear quadrature (``N``, ``dNdx``, ``dx``) for γ.
    D, DT : ndarray or csr_matrix (2 n_q, n_elastic), (n_elastic, 2 n_q)
        [D_u; D_w]: q_f -> (u', w') at the n_q = n_el n_qp points (module docstring), and its transpose.
    wq : ndarray (n_q,)
        EA dx per point, N m.
    dNt : ndarray (n_el, n_qp, n_l)
        ``dN`` reordered element-major for the element matrices.
    loc : ndarray of int (n_el, 2 n_l)
        Elastic index of each element's local (u, w) DOFs, −1 where the reference condition
        eliminated it.
    """

    eu: np.ndarray
    ew: np.ndarray
    eth: np.ndarray
    dN: np.ndarray
    dx: np.ndarray
    shear: object
    D: object
    DT: object
    wq: np.ndarray
    dNt: np.ndarray
    loc: np.ndarray

    @property
    def nq(self):
        """Number of axial quadrature points n_el n_qp."""
        return self.dx.size


def axial_quadrature(beam, free, sparse):
    """The :class:`AxialQuadrature` of ``beam`` on the beam DOFs ``free`` (D dense unless ``sparse``)."""
    nf = free.size
    red = -np.ones(beam.n_dofs, dtype=int)            # beam DOF -> elastic index, −1 = eliminated
    red[free] = np.arange(nf)
    qd = beam.quadrature
    ed = beam.element_dofs
    eu, ew, eth = ed[:, 0::3], ed[:, 1::3], ed[:, 2::3]
    dN, dx = qd.dNdx, qd.dx
    if np.allclose(qd.dNdx, qd.dNdx[:, :, :1]):     # P1: u', w' constant per element, one point is exact
        dN, dx = qd.dNdx[:, :, :1].copy(), qd.dx.sum(axis=1, keepdims=True)
    nel, nqp = dx.shape
    nq = nel * nqp
    blocks = []
    for e_dofs in (eu, ew):
        loc = red[e_dofs]                                            # (nel, nl)
        rows = np.broadcast_to((np.arange(nel)[:, None] * nqp + np.arange(nqp)[None, :])[:, :, None],
                               (nel, nqp, loc.shape[1]))
        cols = np.broadcast_to(loc[:, None, :], rows.shape)
        vals = dN.transpose(1, 2, 0)
        keep = cols >= 0
        blocks.append(sps.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(nq, nf)))
    D = sps.vstack(blocks).tocsr()
    D = D if sparse else D.toarray()
    DT = D.T.tocsr() if sparse else np.ascontiguousarray(D.T)
    return AxialQuadrature(eu=eu, ew=ew, eth=eth, dN=dN, dx=dx, shear=beam.shear_quadrature, D=D, DT=DT,
                           wq=(beam.section.EA * dx).ravel(),
                           dNt=np.ascontiguousarray(dN.transpose(1, 2, 0)),
                           loc=red[np.concatenate([eu, ew], axis=1)])


def axial_derivatives(ax, qf):
    """(u', w') at the axial quadrature points (flattened, length n_q) of the elastic vector ``qf``."""
    y = ax.D @ qf
    return y[:ax.nq], y[ax.nq:]


def axial_gradient(ax, up, wp, t):
    """dε(u', w')ᵀ t on q_f: the axial force vector of the point weights ``t`` (N, e.g. EA dx ε)."""
    return ax.DT @ np.concatenate([t * (1.0 + up), t * wp])


def axial_element_tangent(ax, w, a, b, weps):
    """Element matrices (n_el, 2 n_l, 2 n_l) on the local (u, w) DOFs of

    Σ_k w_k dε_k(a)ᵀ dε_k(b) + Σ_k weps_k d²ε_k

    for the strain states a = (u', w') and b at the points (``w``, ``weps`` per point, N m and N).
    The body scatters them into its elastic block (``floating_pattern.py``)."""
    nel, nqp = ax.dx.shape
    sh = (nel, nqp, 1)
    dn = ax.dNt                                                      # (nel, nqp, nl)
    de_a = np.concatenate([(1.0 + a[0]).reshape(sh) * dn, a[1].reshape(sh) * dn], axis=2)
    de_b = np.concatenate([(1.0 + b[0]).reshape(sh) * dn, b[1].reshape(sh) * dn], axis=2)
    out = np.matmul((de_a * w.reshape(sh)).transpose(0, 2, 1), de_b)
    blk = np.matmul((dn * weps.reshape(sh)).transpose(0, 2, 1), dn)
    nl = dn.shape[2]
    out[:, :nl, :nl] += blk
    out[:, nl:, nl:] += blk
    return out


def section_strains(ax, section, d, green):
    """Section strains and forces of the beam DOF vector ``d`` (u, w, φ per node), each (n_el, n_qp).

    Axial strain ε (Green–Lagrange if ``green``, else u') and force EA ε, N, on the axial rule;
    curvature κ, 1/m, and moment EI κ, N m, on the same rule; shear strain γ = w' − φ and force
    kGA γ, N, on the shear rule.
    """
    up = np.einsum("el,lek->ek", d[ax.eu], ax.dN)
    wp = np.einsum("el,lek->ek", d[ax.ew], ax.dN)
    eps = up + 0.5 * (up * up + wp * wp) if green else up
    kap = np.einsum("el,lek->ek", d[ax.eth], ax.dN)
    sq = ax.shear
    gam = (np.einsum("el,lek->ek", d[ax.ew], sq.dNdx) - np.einsum("el,lek->ek", d[ax.eth], sq.N))
    s = section
    return dict(axial_strain=eps, axial_force=s.EA * eps, curvature=kap, bending_moment=s.EI * kap,
                shear_strain=gam, shear_force=s.kGA * gam)


def element_strain_energy(ax, section, strains):
    """Strain energy of each element, J, from :func:`section_strains`."""
    s = section
    return (0.5 * np.sum((s.EA * strains["axial_strain"] ** 2 + s.EI * strains["curvature"] ** 2) * ax.dx, axis=1)
            + 0.5 * s.kGA * np.sum(strains["shear_strain"] ** 2 * ax.shear.dx, axis=1))
