r"""Green–Lagrange strain of a linear displacement field, and its quartic energy on a reduced basis.

A :class:`GreenLagrange` describes the nonlinear (St. Venant–Kirchhoff) part of a body's strain
energy at quadrature points: with g = G d the displacement gradients at a point (n_g numbers,
linear in the nodal vector d), the strain components (n_s of them) are

.. math::

    E_a = \ell_a \cdot g + \tfrac12\, g^T Q_a\, g,

and the energy is ½ Σ_q w_q E_qᵀ C E_q. Plane stress: g = (u_x,X, u_x,Y, u_y,X, u_y,Y),
E = (E_XX, E_YY, 2E_XY); the floating-frame beam: g = (u', w'), E = u' + ½(u'² + w'²).

On a reduced basis d = Φ η the strain is E = L η + ½ N(η, η) with L_q (n_s, n_m) and
N_q (n_s, n_m, n_m), so the energy is a quartic polynomial (:class:`QuarticEnergy`)

.. math::

    V(η) = ½ ηᵀ K η + ½ K^{(3)}_{ijk} η_i η_j η_k + ⅛ K^{(4)}_{ijkl} η_i η_j η_k η_l,

K^{(3)}_{ijk} = Σ_q w L_iᵀ C N_jk,  K^{(4)}_{ijkl} = Σ_q w N_ijᵀ C N_kl, computed once
(K is the body's whole linear stiffness ΦᵀKΦ, which already holds the linear part of the strain).
The discrete gradient is the "stress at the mean strain" (E is quadratic in η, so
E(η₁) − E(η₀) = dE(η_m)·Δη exactly), written with the tensors; docs/flexible_bodies.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GreenLagrange", "QuarticEnergy", "QUARTIC_LIMIT"]

#: reduced bodies with more elastic coordinates than this get no Green–Lagrange tensors (m⁴ entries)
QUARTIC_LIMIT = 60


@dataclass
class GreenLagrange:
    """The nonlinear strain of a body at its quadrature points.

    Attributes
    ----------
    gradients : list of scipy.sparse matrices (n_q, n_dofs)
        G_k: the k-th displacement gradient component at every quadrature point.
    linear : ndarray (n_s, n_g)
        ℓ_a, the linear part of each strain component.
    quadratic : ndarray (n_s, n_g, n_g)
        Q_a (symmetric), the quadratic part: E_a = ℓ_a·g + ½ gᵀ Q_a g.
    material : ndarray (n_s, n_s)
        C, the elasticity matrix (Pa, or N for a beam's EA).
    weights : ndarray (n_q,)
        Quadrature weights times thickness (m³), or dx (m) for a beam.
    """

    gradients: list
    linear: np.ndarray
    quadratic: np.ndarray
    material: np.ndarray
    weights: np.ndarray

    def _grad(self, d):
        """g at every point, (n_q, n_g), of one or several (n_dofs, k) vectors → (n_q, n_g[, k])."""
        return np.stack([G @ d for G in self.gradients], axis=1)

    def second_derivative(self, a, b):
        """∂²f/∂d² [a, b] at d = 0: the quadratic internal force of the fields a and b (N).

        f(d) = ∂/∂d ½ Σ w Eᵀ C E; at d = 0 its second derivative in the directions a, b, tested
        with v, is Σ w [L(v)ᵀ C N(a, b) + N(v, a)ᵀ C L(b) + N(v, b)ᵀ C L(a)]. Used for the
        static modal derivatives of :func:`~skfem_flex.bodies.modal.reduction.modal_derivatives`.
        """
        ga, gb = self._grad(a), self._grad(b)
        la, lb = ga @ self.linear.T, gb @ self.linear.T                 # (n_q, n_s)
        nab = np.einsum("qg,agh,qh->qa", ga, self.quadratic, gb)
        C = self.material
        h = (nab @ C) @ self.linear                                      # ℓᵀ C N(a, b)
        h += np.einsum("agh,qh,qa->qg", self.quadratic, ga, lb @ C)
        h += np.einsum("agh,qh,qa->qg", self.quadratic, gb, la @ C)
        h *= self.weights[:, None]
        return sum(G.T @ h[:, k] for k, G in enumerate(self.gradients))

    def reduced(self, Phi, K):
        """The :class:`QuarticEnergy` of this strain on the basis Φ (n_dofs, n_m), with linear stiffness K."""
        gm = self._grad(np.asarray(Phi))                                 # (n_q, n_g, n_m)
        L = np.einsum("ag,qgi->qai", self.linear, gm)
        N = np.einsum("agh,qgi,qhj->qaij", self.quadratic, gm, gm)
        nq, ns, nm = L.shape
        CN = np.einsum("ab,qbjk->qajk", self.material, N) * self.weights[:, None, None, None]
        K3 = np.einsum("qai,qajk->ijk", L, CN)
        K4 = (N.reshape(nq * ns, nm * nm).T @ CN.reshape(nq * ns, nm * nm)).reshape(nm, nm, nm, nm)
        return QuarticEnergy(np.asarray(K, dtype=float), K3, 0.5 * (K4 + K4.transpose(2, 3, 0, 1)))


@dataclass
class QuarticEnergy:
    """V(η) = ½ ηᵀKη + ½ K3_ijk η_iη_jη_k + ⅛ K4_ijkl η_iη_jη_kη_l (J), K3 and K4 None: linear.

    K3 is symmetric in (j, k); K4 in (i, j), in (k, l) and under (ij) ↔ (kl).
    """

    K: np.ndarray
    K3: np.ndarray = None
    K4: np.ndarray = None

    def __post_init__(self):
        if self.K3 is not None:
            m = self.K.shape[0]
            K3, K4 = self.K3, self.K4
            # the contractions of the discrete gradient as matrix products (BLAS), arranged once
            self._K3_m_jk = K3.reshape(m, m * m)
            self._K3_j_mk = np.ascontiguousarray(K3.transpose(1, 0, 2)).reshape(m, m * m)
            self._K3_mn_k = K3.reshape(m * m, m)
            self._K3_sym_mn_k = np.ascontiguousarray(K3.transpose(1, 0, 2) + K3.transpose(1, 2, 0)).reshape(m * m, m)
            self._K4_mk_jl = K4.reshape(m * m, m * m)
            self._K4_mn_kl = np.ascontiguousarray(K4.transpose(0, 2, 1, 3)).reshape(m * m, m * m)

    @property
    def linear(self):
        return self.K3 is None

    def energy(self, eta):
        v = 0.5 * float(eta @ (self.K @ eta))
        if not self.linear:
            v += 0.5 * float(np.einsum("ijk,i,j,k", self.K3, eta, eta, eta))
            v += 0.125 * float(np.einsum("ijkl,i,j,k,l", self.K4, eta, eta, eta, eta))
        return v

    def gradient(self, eta):
        """∂V/∂η = Kη + ½ K3_mjk η_jη_k + K3_jmk η_jη_k + ½ K4_mjkl η_jη_kη_l."""
        g = self.K @ eta
        if not self.linear:
            g = g + 0.5 * np.einsum("mjk,j,k->m", self.K3, eta, eta) + np.einsum("jmk,j,k->m", self.K3, eta, eta)
            g += 0.5 * np.einsum("mjkl,j,k,l->m", self.K4, eta, eta, eta)
        return g

    def hessian(self, eta):
        """∂²V/∂η² = K + (K3_mnk + K3_nmk + K3_kmn) η_k + ½ K4_mnkl η_kη_l + K4_mknl η_kη_l."""
        h = np.array(self.K, dtype=float)
        if not self.linear:
            K3 = self.K3
            h += np.einsum("mnk,k->mn", K3 + K3.transpose(1, 0, 2) + K3.transpose(1, 2, 0), eta)
            h += 0.5 * np.einsum("mnkl,k,l->mn", self.K4, eta, eta) + np.einsum("mknl,k,l->mn", self.K4, eta, eta)
        return h

    def discrete_gradient(self, eta0, eta1):
        """(g, ∂g/∂η1) with g·(η1 − η0) = V(η1) − V(η0) exactly (stress at the mean strain).

        With η̄ = (η0 + η1)/2 and P = (η0η0ᵀ + η1η1ᵀ)/2::

            g_m = K η̄ + ½ K3_mjk P_jk + K3_jmk η̄_j η̄_k + ½ K4_mkjl η̄_k P_jl
        """
        em = 0.5 * (eta0 + eta1)
        g = self.K @ em
        dg = 0.5 * np.array(self.K, dtype=float)
        if self.linear:
            return g, dg
        m = em.size
        P = (0.5 * (np.outer(eta0, eta0) + np.outer(eta1, eta1))).ravel()
        A = (self._K4_mk_jl @ P).reshape(m, m)                              # A_mk = K4_mkjl P_jl
        g = g + 0.5 * (self._K3_m_jk @ P) + self._K3_j_mk @ np.outer(em, em).ravel() + 0.5 * (A @ em)
        dg += 0.5 * (self._K3_mn_k @ eta1).reshape(m, m) + 0.5 * (self._K3_sym_mn_k @ em).reshape(m, m)
        dg += 0.25 * A + 0.5 * (self._K4_mn_kl @ np.outer(em, eta1).ravel()).reshape(m, m)
        return g, dg
