r"""Green–Lagrange strain energy of a reduced 3D solid, and the vectors its reduction basis needs for stiffening.

On reduced coordinates η (u = Φ η) the displacement gradient at a quadrature point is U = Σ_m η_m G_m
(G_m the gradient of mode m there), the Green–Lagrange strain E = ½(U + Uᵀ + UᵀU) and, St. Venant–Kirchhoff,
S = λ tr(E) I + 2μ E:

.. math::

    V = ½ \sum_q w_q\, E_q : S_q,\qquad
    \frac{∂V}{∂η_m} = \sum_q w_q\, (F S)_q : G_{m,q},\quad F = I + U,

    \frac{∂^2V}{∂η_m ∂η_n} = \sum_q w_q \big[dE_m : C : dE_n + S : G_m^T G_n\big],\quad dE_m = \operatorname{sym}(F^T G_m).

E is quadratic in η, so E(η₁) − E(η₀) = dE(η_m)·(η₁ − η₀) exactly and the discrete gradient "stress at the
mean strain", Σ w S̄ : dE(η_m) with S̄ = C : (E₀ + E₁)/2, is exact. Its quadratic part is the linear
stiffness ΦᵀKΦ (the same quadrature as scikit-fem's assembly).

Bending modes alone cannot stretch the body, so a basis for stiffening needs more vectors (assembled on the
full mesh by scikit-fem forms, :func:`stiffening_loads`): the **modal derivatives**, the static response to the
third derivative of V at rest, ∂³V[φ_i, φ_j, δ] = (C:Q_ij):ε(δ) + (C:ε_i):sym(G_jᵀ∇δ) + (C:ε_j):sym(G_iᵀ∇δ)
with Q_ij = sym(G_iᵀG_j); and the **centrifugal shapes**, the static response to the inertia load
ρ ω × (ω × X) of a unit spin about each frame axis.
"""
from __future__ import annotations

import numpy as np
from skfem import LinearForm, asm
from skfem.helpers import ddot, dot, mul, transpose

__all__ = ["SolidGreenLagrange", "stiffening_loads"]


def _sym(A):
    return 0.5 * (A + transpose(A))


def _stress(E, lam, mu):
    """C : E for a field of 3 × 3 tensors (first two axes)."""
    I = np.eye(3).reshape((3, 3) + (1,) * (E.ndim - 2))
    return lam * np.trace(E, axis1=0, axis2=1)[None, None] * I + 2.0 * mu * E


@LinearForm
def _third_derivative(v, w):
    Gi, Gj, Gv = w.phi_i.grad, w.phi_j.grad, v.grad
    ei, ej = _sym(Gi), _sym(Gj)
    Q = _sym(mul(transpose(Gi), Gj))
    return (ddot(_stress(Q, w.lam, w.mu), _sym(Gv)) + ddot(_stress(ei, w.lam, w.mu), _sym(mul(transpose(Gj), Gv)))
            + ddot(_stress(ej, w.lam, w.mu), _sym(mul(transpose(Gi), Gv))))


@LinearForm
def _spin_load(v, w):
    x = w.x - w.origin
    return w.rho * dot(np.cross(w.axis, np.cross(w.axis, x, axis=0), axis=0), v)


def stiffening_loads(solid, modes, origin, pairs=True, spins=True):
    """Load vectors on the full mesh (columns) whose static responses join a stiffening basis: ∂³V[φ_i, φ_j, ·]
    for every pair of the columns of ``modes`` (with ``pairs``) and the inertia loads of a unit spin about each
    frame axis through ``origin`` (with ``spins``), N."""
    from skfem.models.elasticity import lame_parameters
    lam, mu = lame_parameters(solid.E, solid.nu)
    b = solid.basis
    out = []
    if pairs:
        fields = [b.interpolate(modes[:, k]) for k in range(modes.shape[1])]
        for i in range(len(fields)):
            for j in range(i, len(fields)):
                out.append(asm(_third_derivative, b, phi_i=fields[i], phi_j=fields[j], lam=lam, mu=mu))
    if spins:
        for axis in np.eye(3):
            out.append(asm(_spin_load, b, rho=solid.rho, axis=axis.reshape(3, 1, 1),
                           origin=np.asarray(origin, dtype=float).reshape(3, 1, 1)))
    return np.column_stack(out) if out else np.zeros((b.N, 0))


class SolidGreenLagrange:
    """V(η) of a reduced solid (module docstring): energy, gradient, Hessian and the exact discrete gradient.

    Parameters
    ----------
    solid : ElasticSolid3D
    basis : ndarray (n_dofs, m)
        Φ, u = Φ η.
    """

    nonlinear = True

    def __init__(self, solid, basis):
        from skfem.models.elasticity import lame_parameters
        self.lam, self.mu = lame_parameters(solid.E, solid.nu)
        b = solid.basis
        grads = np.stack([b.interpolate(basis[:, k]).grad for k in range(basis.shape[1])], axis=-1)
        m = basis.shape[1]
        self.G = np.ascontiguousarray(grads.transpose(2, 3, 0, 1, 4).reshape(-1, 3, 3, m))   # (Q, 3, 3, m)
        self.w = b.dx.ravel()

    def _strain(self, y):
        U = np.einsum("qijm,m->qij", self.G, y)
        return U, 0.5 * (U + U.transpose(0, 2, 1) + U.transpose(0, 2, 1) @ U)

    def _stress(self, E):
        return self.lam * np.trace(E, axis1=1, axis2=2)[:, None, None] * np.eye(3) + 2.0 * self.mu * E

    def _dE(self, U):
        """dE_m = sym(Fᵀ G_m), (Q, 3, 3, m)."""
        FtG = np.einsum("qki,qkjm->qijm", np.eye(3) + U, self.G)
        return 0.5 * (FtG + FtG.transpose(0, 2, 1, 3))

    def _curvature(self, S):
        """Σ_q w S : G_mᵀ G_n (the second derivative of E contracted with S)."""
        SG = np.einsum("qij,qkjn->qkin", S * self.w[:, None, None], self.G)
        return np.einsum("qkim,qkin->mn", self.G, SG)

    def _material(self, dEa, dEb, weights):
        CdE = (self.lam * np.einsum("qiim->qm", dEb)[:, None, None, :] * np.eye(3)[None, :, :, None]
               + 2.0 * self.mu * dEb)
        return np.einsum("q,qijm,qijn->mn", weights, dEa, CdE)

    def energy(self, y):
        _, E = self._strain(y)
        return 0.5 * float(np.einsum("q,qij,qij->", self.w, E, self._stress(E)))

    def gradient(self, y):
        U, E = self._strain(y)
        P = (np.eye(3) + U) @ self._stress(E)
        return np.einsum("q,qij,qijm->m", self.w, P, self.G)

    def hessian(self, y):
        U, E = self._strain(y)
        dE = self._dE(U)
        return self._material(dE, dE, self.w) + self._curvature(self._stress(E))

    def compiled_strain(self):
        """None: the compiled core has no form of the solid's Green–Lagrange energy (it runs in Python)."""
        return None

    def discrete_gradient(self, y0, y1):
        """(g, ∂g/∂y1): the stress at the mean strain times the mid-point dE, exact (module docstring)."""
        _, E0 = self._strain(y0)
        U1, E1 = self._strain(y1)
        Um, _ = self._strain(0.5 * (y0 + y1))
        S = self._stress(0.5 * (E0 + E1))
        dEm = self._dE(Um)
        g = np.einsum("q,qij,qijm->m", self.w, S, dEm)
        jac = 0.5 * self._material(dEm, self._dE(U1), self.w) + 0.5 * self._curvature(S)
        return g, jac
