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

With E = Lη + ½N(η, η) the energy is the quartic polynomial ½ηᵀKη + ½K3_ijk η_iη_jη_k + ⅛K4_ijkl η_iη_jη_kη_l
whose tensors are these sums over the quadrature points, taken once (:func:`quartic_tensors`); every
evaluation (the formulas above, written in the tensors: :class:`~skfem_flex.bodies.modal.stiffening.QuarticEnergy`,
the same as the planar reduced body's) then costs m⁴ operations and none over the mesh, and the compiled core
evaluates the same tensors (:mod:`.kernel`).

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

from ..modal.kernel import pack_quartic
from ..modal.stiffening import QuarticEnergy

__all__ = ["SolidGreenLagrange", "quartic_tensors", "stiffening_loads"]


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


def quartic_tensors(G, w, lam, mu, chunk=1024):
    r"""The Green–Lagrange energy on a reduced basis as a quartic polynomial of η (module docstring).

    With the strain E = Lη + ½N(η, η), L_m = sym(G_m), N_mn = sym(G_mᵀG_n) and A : C : B =
    λ tr A tr B + 2μ A : B at every quadrature point,

    .. math::

        K_{ij} = \sum_q w\, L_i : C : L_j,\quad K^{(3)}_{ijk} = \sum_q w\, L_i : C : N_{jk},\quad
        K^{(4)}_{ijkl} = \sum_q w\, N_{ij} : C : N_{kl},

    the same quadrature as the definition (a test holds them to it). The sums run over the quadrature
    points in chunks of ``chunk`` (about 30 × ``chunk`` × m(m+1)/2 numbers at a time) and over the pairs
    j ≤ k only (N is symmetric in them): about 7 Q m⁴/4 multiply–adds for Q points.

    Parameters
    ----------
    G : ndarray (Q, 3, 3, m)
        The displacement gradient of each basis vector at every quadrature point, G[q, i, j, m] = ∂Φ_im/∂X_j.
    w : ndarray (Q,)
        The quadrature weights, m³.
    lam, mu : float
        The Lamé parameters, Pa.
    chunk : int
        Quadrature points per block of the sums.

    Returns
    -------
    QuarticEnergy
        K (N/m), K3 (N/m²) and K4 (N/m³) on the basis's coordinates (per unit of η where Φ is not in m),
        K4 exactly symmetric in (i, j), in (k, l) and under (ij) ↔ (kl) as
        :class:`~skfem_flex.bodies.modal.stiffening.QuarticEnergy` requires.
    """
    Q, _, _, m = G.shape
    j, k = np.triu_indices(m)
    # a symmetric 3 × 3 tensor as 6 numbers whose dot product is the full contraction A : B
    rows, cols = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])
    scale = np.array([1.0, 1.0, 1.0, np.sqrt(2.0), np.sqrt(2.0), np.sqrt(2.0)])
    K = np.zeros((m, m))
    K3p = np.zeros((m, j.size))
    K4p = np.zeros((j.size, j.size))
    for start in range(0, Q, chunk):
        Gc = G[start:start + chunk]
        wc = w[start:start + chunk]
        L = 0.5 * (Gc + Gc.transpose(0, 2, 1, 3))                             # (n, 3, 3, m)
        T = np.einsum("qcaP,qcbP->qabP", Gc[..., j], Gc[..., k])               # G_jᵀG_k on the pairs
        N = 0.5 * (T + T.transpose(0, 2, 1, 3))
        del T
        L6 = L[:, rows, cols] * scale[:, None]                               # (n, 6, m)
        N6 = N[:, rows, cols] * scale[:, None]                               # (n, 6, n_pairs)
        trL = np.einsum("qaam->qm", L)
        trN = np.einsum("qaaP->qP", N)
        wL6 = (wc[:, None, None] * L6).reshape(-1, m)
        wtrL = wc[:, None] * trL
        K += lam * (wtrL.T @ trL) + 2.0 * mu * (wL6.T @ L6.reshape(-1, m))
        K3p += lam * (wtrL.T @ trN) + 2.0 * mu * (wL6.T @ N6.reshape(-1, j.size))
        wN6 = (wc[:, None, None] * N6).reshape(-1, j.size)
        K4p += lam * ((wc[:, None] * trN).T @ trN) + 2.0 * mu * (wN6.T @ N6.reshape(-1, j.size))
    K4p = 0.5 * (K4p + K4p.T)           # the two factors of its products differ: exact at round-off only
    K3 = np.empty((m, m, m))
    K3[:, j, k] = K3p
    K3[:, k, j] = K3p
    K4 = np.empty((m, m, m, m))
    for a in range(j.size):
        K4[j[a], k[a], j, k] = K4p[a]
        K4[j[a], k[a], k, j] = K4p[a]
        K4[k[a], j[a], j, k] = K4p[a]
        K4[k[a], j[a], k, j] = K4p[a]
    return QuarticEnergy(0.5 * (K + K.T), K3, K4)


class SolidGreenLagrange:
    """V(η) of a reduced solid (module docstring): energy, gradient, Hessian and the exact discrete gradient.

    The energy is the quartic polynomial of :func:`quartic_tensors`, summed over the mesh's quadrature points
    once, here: every evaluation then costs m⁴ operations and none over the mesh, and the mode gradients at the
    quadrature points (Q × 9 × m numbers) are not kept.

    Parameters
    ----------
    solid : ElasticSolid3D
    basis : ndarray (n_dofs, m)
        Φ, u = Φ η.
    """

    nonlinear = True

    def __init__(self, solid, basis):
        from skfem.models.elasticity import lame_parameters
        lam, mu = lame_parameters(solid.E, solid.nu)
        m = basis.shape[1]
        grads = np.stack([solid.basis.interpolate(basis[:, k]).grad for k in range(m)], axis=-1)
        G = np.ascontiguousarray(grads.transpose(2, 3, 0, 1, 4).reshape(-1, 3, 3, m))   # (Q, 3, 3, m)
        #: the energy as a :class:`~skfem_flex.bodies.modal.stiffening.QuarticEnergy` (K, K3, K4)
        self.polynomial = quartic_tensors(G, solid.basis.dx.ravel(), lam, mu)
        self._packed = None

    @property
    def K(self):
        """The quadratic part, ΦᵀKΦ on the same quadrature (N/m)."""
        return self.polynomial.K

    def energy(self, y):
        return self.polynomial.energy(y)

    def gradient(self, y):
        return self.polynomial.gradient(y)

    def hessian(self, y):
        return self.polynomial.hessian(y)

    def discrete_gradient(self, y0, y1):
        """(g, ∂g/∂y1): the stress at the mean strain times the mid-point dE, exact (module docstring)."""
        return self.polynomial.discrete_gradient(y0, y1)

    def compiled_strain(self):
        """The compiled core's form of this energy (:func:`.kernel.kernel_data`): the quadratic part K and the
        cubic and quartic tensors, folded by their symmetries once
        (:func:`~skfem_flex.bodies.modal.kernel.pack_quartic`)."""
        if self._packed is None:
            self._packed = pack_quartic(self.polynomial.K3, self.polynomial.K4)
        return {"K": self.polynomial.K, "quartic": self._packed}
