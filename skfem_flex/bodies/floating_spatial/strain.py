r"""Strain energy of a spatial floating-frame beam: the linear 3D Timoshenko beam with a Green–Lagrange axis.

Torsion, bending in both planes and shear are the constant quadratic forms of
:class:`~skfem_flex.fem.spatial_beam.TimoshenkoBeam3D`. The axial strain is either linear, ε = u₃', or the
Green–Lagrange strain of the axis with both transverse deflections,

.. math::  ε = u_3' + \tfrac12 (u_1'^2 + u_2'^2 + u_3'^2),

whose energy ½∫EA ε² ds couples stretch to bending in both planes: a tension stiffens flapwise and
lead-lag bending alike (centrifugal stiffening). On the exact Gauss rule of the basis
(u' = A_k y at the points)

.. math::

    V = ½ y^T K_0 y + ½ \sum_q w_q EA\, ε_q^2,\qquad
    ∇V = K_0 y + B(y)^T (w EA ε),\qquad B(y) = A_3 + \sum_k \operatorname{diag}(u_k') A_k ,

K₀ the stiffness without its axial part. ε is quadratic in y, so ε(y₁) − ε(y₀) = B(y_m)(y₁ − y₀)
exactly and the discrete gradient "stress at the mean strain", B(y_m)ᵀ(w EA (ε₀ + ε₁)/2), is exact.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import asm

from ...fem import spatial_forms

__all__ = ["SpatialBeamStrain"]


class SpatialBeamStrain:
    """Strain energy V(y) of a :class:`~skfem_flex.fem.spatial_beam.TimoshenkoBeam3D` on its DOFs ``free``.

    Parameters
    ----------
    beam : TimoshenkoBeam3D
    free : ndarray of int
        The beam DOFs that are elastic coordinates (y = q_full[free]).
    strain : {"green-lagrange", "linear"}
    """

    def __init__(self, beam, free, strain):
        if strain not in ("green-lagrange", "linear"):
            raise ValueError(f"strain must be 'green-lagrange' or 'linear', got {strain!r}")
        self.nonlinear = strain == "green-lagrange"
        sec = beam.section
        K = beam.stiffness()
        if self.nonlinear:
            K = K - asm(spatial_forms.axial, beam.basis, EA=sec.EA)
        self.K = K.tocsr()[free][:, free].toarray()
        fb = beam.field_basis
        field_dofs = np.array(beam.basis.split_indices())
        nel, nqp = fb.dx.shape
        rows = (np.arange(nel)[:, None] * nqp + np.arange(nqp)[None, :])        # (nel, nqp)
        position = np.full(beam.n_dofs, -1)
        position[free] = np.arange(free.size)
        self.A = []
        for k in range(3):
            r, c, v = [], [], []
            for a in range(fb.element_dofs.shape[0]):
                col = position[field_dofs[k][fb.element_dofs[a]]]                 # (nel,)
                keep = col >= 0
                r.append(rows[keep].ravel())
                c.append(np.repeat(col[keep], nqp))
                v.append(fb.basis[a][0].grad[0][keep].ravel())
            # dense: this body is for beams of tens of elements, where numpy on dense arrays beats sparse overhead
            self.A.append(sps.csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                                         shape=(nel * nqp, free.size)).toarray())
        self.w = sec.EA * fb.dx.ravel()

    def projected(self, basis):
        """The same energy on reduced coordinates η, y = Φ η: ΦᵀKΦ and the rows A_kΦ (a new object)."""
        out = object.__new__(SpatialBeamStrain)
        out.nonlinear, out.w = self.nonlinear, self.w
        out.K = basis.T @ self.K @ basis
        out.A = [A @ basis for A in self.A]
        return out

    def compiled_strain(self):
        """The compiled core's form of this energy, keyword arguments of :func:`.kernel.kernel_data`: K or,
        with the Green–Lagrange axis, K₀, A (3, n_points, n) and w."""
        if not self.nonlinear:
            return {"K": self.K}
        return {"K": self.K, "A": np.stack(self.A), "w": self.w}

    def strains(self, y):
        """(u' (3, n_points), ε (n_points,)) at the Gauss points."""
        up = np.stack([A @ y for A in self.A])
        eps = up[2] + 0.5 * (up * up).sum(axis=0) if self.nonlinear else up[2]
        return up, eps

    def _B(self, up):
        return self.A[2] + sum(up[k][:, None] * self.A[k] for k in range(3))

    def _curvature(self, t):
        """Σ_k A_kᵀ diag(t) A_k: the second derivative of Σ t_q ε_q."""
        return sum(A.T @ (t[:, None] * A) for A in self.A)

    def energy(self, y):
        """V(y), J."""
        lin = 0.5 * float(y @ (self.K @ y))
        if not self.nonlinear:
            return lin
        _, eps = self.strains(y)
        return lin + 0.5 * float(self.w @ (eps * eps))

    def gradient(self, y):
        """∇V(y)."""
        g = self.K @ y
        if self.nonlinear:
            up, eps = self.strains(y)
            g = g + self._B(up).T @ (self.w * eps)
        return g

    def hessian(self, y):
        """∇²V(y) (dense)."""
        if not self.nonlinear:
            return self.K.copy()
        up, eps = self.strains(y)
        B = self._B(up)
        return self.K + B.T @ (self.w[:, None] * B) + self._curvature(self.w * eps)

    def discrete_gradient(self, y0, y1):
        """(g, ∂g/∂y1) with g · (y1 − y0) = V(y1) − V(y0) exactly (module docstring)."""
        ym = 0.5 * (y0 + y1)
        g = self.K @ ym
        jac = 0.5 * self.K
        if not self.nonlinear:
            return g, jac.copy()
        up0, e0 = self.strains(y0)
        up1, e1 = self.strains(y1)
        Bm = self._B(0.5 * (up0 + up1))
        t = self.w * 0.5 * (e0 + e1)
        g = g + Bm.T @ t
        jac = jac + 0.5 * Bm.T @ (self.w[:, None] * self._B(up1)) + 0.5 * self._curvature(t)
        return g, jac
