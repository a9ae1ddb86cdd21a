r"""The strains of the spatial director beam on its strain points, their energy and its discrete gradient.

Every node a of a :class:`~skfem_flex.bodies.exact.spatial_body.SpatialExactBeam` carries the position
φ_a of the beam axis and three directors d_{1a}, d_{2a}, d_{3a} (the section's principal axes and its
normal), twelve coordinates in all; the scene holds each triad orthonormal with six quadratic
equations. Along an element all four vectors are interpolated with the same scikit-fem shape functions
N_a(s) of the reference arc length s (P1 or P2, ' = d/ds). The strains of the section, after
Antman and Simo, in the directors' own axes,

.. math::

    Γ_i = d_i · φ' − Γ^0_i \quad (i = 1, 2, 3), \qquad
    K_1 = ½ (d_3 · d_2' − d_2 · d_3') − K^0_1, \quad
    K_2 = ½ (d_1 · d_3' − d_3 · d_1') − K^0_2, \quad
    K_3 = ½ (d_2 · d_1' − d_1 · d_2') − K^0_3,

are sampled on the reduced Gauss rule (one point per P1 element, two per P2 element), which keeps
slender beams free of shear locking. Γ₁, Γ₂ are the shears, Γ₃ the stretch, K₁, K₂ the bending
curvatures about d₁, d₂ and K₃ the twist; the reference values Γ⁰, K⁰ are the same expressions in the
reference configuration, so an initially curved and twisted beam is stress-free there. Every strain is
a dot product of interpolated vectors: invariant under any rigid motion (objective), and, because the
interpolated directors are never rotated but simply added, independent of the path the nodes took
(Betsch & Steinmann 2002). The strain energy is ½ ∫ eᵀ C e ds with C = diag(kGA₁, kGA₂, EA, EI₁, EI₂,
GJ) (:class:`~skfem_flex.fem.spatial_section.SpatialSection`).

Each strain of an element is a quadratic form e_k = ½ q_eᵀ H_k q_e − e⁰_k of the element's
coordinates q_e with a constant, symmetric H_k. Hence its mid-point gradient is exact,
e(q₁) − e(q₀) = H_k q_m · (q₁ − q₀) with q_m = (q₀ + q₁)/2, and with the section forces taken at the
mean strain, C (e₀ + e₁)/2,

.. math::

    \bar ∇V = \sum_p w_p \, (H q_m)^T C \, \frac{e(q_0) + e(q_1)}{2}

satisfies \bar ∇V · (q₁ − q₀) = V(q₁) − V(q₀) exactly (Gonzalez 1996). It is a sum of gradients of
rotation-invariant functions at one configuration, so it exerts no net force or moment: the
energy–momentum step conserves energy and both momenta of a free beam to the Newton tolerance.

References
----------
P. Betsch, P. Steinmann, "Frame-indifferent beam finite elements based upon the geometrically exact beam
theory", IJNME 54 (2002) 1775–1788.
O. Gonzalez, "Time integration and discrete Hamiltonian systems", J. Nonlinear Sci. 6 (1996) 449–467.
J. C. Simo, N. Tarnow, M. Doblaré, "Non-linear dynamics of three-dimensional rods: exact energy and
momentum conserving algorithms", IJNME 38 (1995) 1431–1473.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import Basis, ElementLineP1, ElementLineP2

from ...fem.beam import ElementQuadrature, gauss_line

__all__ = ["DirectorStrainPoints", "STRAIN_NAMES", "NODE_SIZE"]

#: the six strains of a section, in the order of :attr:`SpatialSection.stiffness`
STRAIN_NAMES = ("Gamma1", "Gamma2", "Gamma3", "K1", "K2", "K3")
#: coordinates per node: φ, d₁, d₂, d₃
NODE_SIZE = 12

# the vectors of a node, by their place in its twelve coordinates
_PHI, _D1, _D2, _D3 = 0, 1, 2, 3
# each strain as a sum of c · (X interpolated with N or N') · (Y interpolated with N or N'):
# (coefficient, vector X, derivative of X?, vector Y, derivative of Y?)
_TERMS = (
    ((1.0, _D1, False, _PHI, True),),
    ((1.0, _D2, False, _PHI, True),),
    ((1.0, _D3, False, _PHI, True),),
    ((0.5, _D3, False, _D2, True), (-0.5, _D2, False, _D3, True)),
    ((0.5, _D1, False, _D3, True), (-0.5, _D3, False, _D1, True)),
    ((0.5, _D2, False, _D1, True), (-0.5, _D1, False, _D2, True)),
)


class DirectorStrainPoints:
    """The strain points of a spatial director beam and the strain energy on them (module docstring).

    Parameters
    ----------
    mesh : skfem.MeshLine
        The beam's mesh over the reference arc length s, m.
    order : {1, 2}
        P1 or P2 interpolation.
    node_of_dof : ndarray (n_nodes,)
        The beam's node (ascending s) of every scalar scikit-fem DOF.
    stiffness : sequence of 6 floats
        (kGA₁, kGA₂, EA, EI₁, EI₂, GJ).
    q_reference : ndarray (12 n_nodes,)
        The stress-free reference configuration.
    dense : bool
        Whether matrices are handed out dense (else CSR).

    Attributes
    ----------
    ed : ndarray (n_elements, 12 k)
        The coordinates of every element, node after node (φ, d₁, d₂, d₃).
    H : ndarray (n_elements, n_points, 6, 12 k, 12 k)
        The constant second derivatives of the strains.
    W : ndarray (n_elements, n_points)
        Quadrature weights, m.
    s_points : ndarray (n_elements, n_points)
        Reference arc length of the strain points, m.
    """

    def __init__(self, mesh, order, node_of_dof, stiffness, q_reference, dense):
        scalar = ElementLineP1() if order == 1 else ElementLineP2()
        basis = Basis(mesh, scalar, quadrature=gauss_line(order))
        quad = ElementQuadrature.from_basis(basis)
        N = np.transpose(quad.N, (1, 2, 0))                 # (n_el, n_p, k)
        dN = np.transpose(quad.dNdx, (1, 2, 0))
        self.W = np.asarray(quad.dx)
        self.s_points = np.asarray(quad.x)
        nodes = np.asarray(node_of_dof)[np.asarray(basis.element_dofs).T]      # (n_el, k)
        self.n_elements, k = nodes.shape
        self.ed = (NODE_SIZE * nodes[:, :, None] + np.arange(NODE_SIZE)).reshape(self.n_elements, -1)
        self.C = np.asarray(stiffness, dtype=float)
        self.n_dofs = NODE_SIZE * int(np.max(node_of_dof) + 1)
        self.dense = bool(dense)

        # H[e, p, strain, (a, vector, component), (b, vector, component)]
        nl = NODE_SIZE * k
        H = np.zeros((self.n_elements, N.shape[1], 6, k, 4, k, 4))
        for j, terms in enumerate(_TERMS):
            for coef, x, dx, y, dy in terms:
                cx, cy = (dN if dx else N), (dN if dy else N)
                H[:, :, j, :, x, :, y] += coef * np.einsum("epa,epb->epab", cx, cy)
        H = H + np.transpose(H, (0, 1, 2, 5, 6, 3, 4))      # ½ qᵀ H q = the bilinear form
        self.H = np.einsum("epjaxby,cd->epjaxcbyd", H, np.eye(3)).reshape(self.n_elements, N.shape[1], 6, nl, nl)
        self.H = np.ascontiguousarray(self.H)
        self.e_reference = np.zeros((self.n_elements, N.shape[1], 6))
        self.e_reference = self.strains(q_reference)

        rows = np.broadcast_to(self.ed[:, :, None], (self.n_elements, nl, nl)).ravel()
        cols = np.broadcast_to(self.ed[:, None, :], (self.n_elements, nl, nl)).ravel()
        self._rows, self._cols = rows, cols

    # ---------------------------------------------------------------- strains
    def _local(self, q):
        q = np.asarray(q, dtype=float)
        if q.shape != (self.n_dofs,):
            raise ValueError(f"coordinates of shape {q.shape}, expected ({self.n_dofs},)")
        return q[self.ed]

    def strains(self, q):
        """The strains e = (Γ₁, Γ₂, Γ₃, K₁, K₂, K₃) at every strain point, (n_elements, n_points, 6)."""
        qe = self._local(q)
        return 0.5 * np.einsum("epjab,ea,eb->epj", self.H, qe, qe) - self.e_reference

    def _strain_gradients(self, qe):
        """∂e/∂q_e = H q_e, (n_elements, n_points, 6, 12 k)."""
        return np.einsum("epjab,eb->epja", self.H, qe)

    def section_forces(self, q):
        """C e: the shear forces and the normal force (N) and the bending and twisting moments (N m) in
        the directors' axes at every strain point, (n_elements, n_points, 6)."""
        return self.strains(q) * self.C

    # ----------------------------------------------------------------- energy
    def energy(self, q):
        """V = ½ Σ_p w_p eᵀ C e, J."""
        e = self.strains(q)
        return 0.5 * float(np.einsum("ep,epj->", self.W, e * e * self.C))

    def _assemble_vector(self, fe):
        return np.bincount(self.ed.ravel(), weights=fe.ravel(), minlength=self.n_dofs)

    def _assemble_matrix(self, ke):
        m = sps.csr_matrix((ke.ravel(), (self._rows, self._cols)), shape=(self.n_dofs, self.n_dofs))
        return m.toarray() if self.dense else m

    def gradient(self, q):
        """∇V = Σ_p w_p (H q)ᵀ C e."""
        qe = self._local(q)
        s = (0.5 * np.einsum("epjab,ea,eb->epj", self.H, qe, qe) - self.e_reference) * self.C
        return self._assemble_vector(np.einsum("ep,epj,epja->ea", self.W, s, self._strain_gradients(qe)))

    def hessian(self, q):
        """∇²V = Σ_p w_p ((H q)ᵀ C (H q) + Σ_j (C e)_j H_j)."""
        qe = self._local(q)
        g = self._strain_gradients(qe)
        s = (0.5 * np.einsum("epja,ea->epj", g, qe) - self.e_reference) * self.C
        ke = (np.einsum("ep,epja,epj,epjb->eab", self.W, g, np.broadcast_to(self.C, s.shape), g)
              + np.einsum("ep,epj,epjab->eab", self.W, s, self.H))
        return self._assemble_matrix(ke)

    def discrete_gradient(self, q0, q1):
        """(\\bar∇V, ∂\\bar∇V/∂q₁): the exact, rotation-equivariant discrete gradient of the module
        docstring and its derivative with respect to the step's end."""
        qe0, qe1 = self._local(q0), self._local(q1)
        qm = 0.5 * (qe0 + qe1)
        gm = self._strain_gradients(qm)
        g1 = self._strain_gradients(qe1)
        e0 = 0.5 * np.einsum("epja,ea->epj", self._strain_gradients(qe0), qe0) - self.e_reference
        e1 = 0.5 * np.einsum("epja,ea->epj", g1, qe1) - self.e_reference
        s = 0.5 * (e0 + e1) * self.C
        fe = np.einsum("ep,epj,epja->ea", self.W, s, gm)
        ke = 0.5 * (np.einsum("ep,epja,epj,epjb->eab", self.W, gm, np.broadcast_to(self.C, s.shape), g1)
                    + np.einsum("ep,epj,epjab->eab", self.W, s, self.H))
        return self._assemble_vector(fe), self._assemble_matrix(ke)
