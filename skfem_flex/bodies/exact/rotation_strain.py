r"""The strains of the spatial beam with rotation-interpolated two-node elements, their energy and its discrete
gradient, on the beam's scikit-fem P1 mesh.

Each element's curvature is the rotation vector ψ of the relative rotation R_aᵀ R_b of its nodal triads,
divided by the element length, and its shear and stretch are Δφ/h seen from the triad half-way between
(:mod:`.rotation_kernel`, which holds the formulas and is the one implementation: this class packs the
element data once and calls it). Unlike the linear interpolation of the directors
(:mod:`.director_strain`), which turns a constant curvature κ into sin(κh)/h, this interpolation represents
any constant curvature and twist exactly; it is objective and path-independent, since every strain is a
function of products of the element's vectors.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import Basis, ElementLineP1

from . import rotation_kernel as kernel
from .director_strain import NODE_SIZE
from .strain import ElementInversionError

__all__ = ["RotationStrainPoints"]


class RotationStrainPoints:
    """The elements of a rotation-interpolated spatial beam and the strain energy on them (module docstring).

    Parameters
    ----------
    mesh : skfem.MeshLine
        The beam's P1 mesh over the reference arc length s, m.
    node_of_dof : ndarray (n_nodes,)
        The beam's node (ascending s) of every scikit-fem DOF.
    stiffness : sequence of 6 floats
        (kGA₁, kGA₂, EA, EI₁, EI₂, GJ).
    q_reference : ndarray (12 n_nodes,)
        The stress-free reference configuration.
    dense : bool
        Whether matrices are handed out dense (else CSR).
    name : str
        The beam's name, for errors.

    Raises
    ------
    ValueError
        When the reference placement itself turns an element by half a turn or more.
    ElementInversionError
        From every method, at a state where an element has turned half a turn or more between its nodes
        (its rotation vector is not defined; a Newton iterate that went there, or too coarse a mesh).

    Attributes
    ----------
    ed : ndarray (n_elements, 24)
        The coordinates of every element, node after node (φ, d₁, d₂, d₃).
    W : ndarray (n_elements, 1)
        The weight of each element's one strain point: its length, m.
    s_points : ndarray (n_elements, 1)
        Reference arc length of the strain points (the elements' middles), m.
    e_reference : ndarray (n_elements, 1, 6)
        The strains of the reference configuration.
    data : RotationKernelData
        The packed arrays of :mod:`.rotation_kernel`.
    """

    def __init__(self, mesh, node_of_dof, stiffness, q_reference, dense, name="spatial_beam"):
        self.name = str(name)
        basis = Basis(mesh, ElementLineP1())
        nodes = np.asarray(node_of_dof)[np.asarray(basis.element_dofs).T]          # (n_el, 2)
        nodes = np.sort(nodes, axis=1)                                              # a before b along s
        self.n_elements = nodes.shape[0]
        self.ed = (NODE_SIZE * nodes[:, :, None] + np.arange(NODE_SIZE)).reshape(self.n_elements, -1)
        s = np.asarray(mesh.p[0], dtype=float)[np.asarray(mesh.t)]                   # (2, n_el)
        h = np.abs(s[1] - s[0])
        self.W = h[:, None]
        self.s_points = (0.5 * (s[0] + s[1]))[:, None]
        self.C = np.asarray(stiffness, dtype=float)
        self.n_dofs = NODE_SIZE * int(np.max(node_of_dof) + 1)
        self.dense = bool(dense)
        self.data = kernel.pack(self.ed, h, self.C, np.asarray(q_reference, dtype=float), self.n_dofs)
        self.e_reference = self.data.e_ref.reshape(self.n_elements, 1, 6)
        bad = np.flatnonzero(~np.all(np.isfinite(self.data.e_ref.reshape(self.n_elements, 6)), axis=1))
        if bad.size:
            raise ValueError(f"{self.name}: the reference placement turns element {int(bad[0])} by half a turn or "
                             f"more between its nodes (s = {s[0, bad[0]]:g} to {s[1, bad[0]]:g} m): refine the mesh")

    def _checked(self, q):
        q = np.ascontiguousarray(q, dtype=float)
        if q.shape != (self.n_dofs,):
            raise ValueError(f"coordinates of shape {q.shape}, expected ({self.n_dofs},)")
        return q

    def _turned(self, *states):
        for q in states:
            k = int(kernel.first_turned(self.data, q))
            if k >= 0:
                return ElementInversionError(
                    f"{self.name}: element {k} has turned half a turn or more between its nodes (or its "
                    f"coordinates are not finite); its rotation vector is not defined there: refine the mesh "
                    f"or take smaller steps")
        return ElementInversionError(f"{self.name}: an element has turned half a turn or more within a step")

    def strains(self, q):
        """The strains e = (Γ₁, Γ₂, Γ₃, K₁, K₂, K₃) − e⁰ of every element, (n_elements, 1, 6)."""
        q = self._checked(q)
        e = kernel.element_strains(self.data, q)
        if not np.all(np.isfinite(e)):
            raise self._turned(q)
        return e[:, None, :]

    def section_forces(self, q):
        """C e: the shear forces and the normal force (N) and the bending and twisting moments (N m) in
        the axes of each element's middle section, (n_elements, 1, 6)."""
        return self.strains(q) * self.C

    def energy(self, q):
        """V = ½ Σ_e h_e eᵀ C e, J."""
        q = self._checked(q)
        v = float(kernel.potential_energy(self.data, q))
        if not np.isfinite(v):
            raise self._turned(q)
        return v

    def _matrix(self, data):
        d = self.data
        m = sps.csr_matrix((data, d.pat_idx, d.pat_ptr), shape=(self.n_dofs, self.n_dofs))
        return m.toarray() if self.dense else m

    def _terms(self, q0, q1):
        q0, q1 = self._checked(q0), self._checked(q1)
        ok, g, data, _ = kernel.discrete_gradient_terms(self.data, q0, q1, False)
        if not ok:
            raise self._turned(q0, q1, 0.5 * (q0 + q1))
        return g, data

    def gradient(self, q):
        """∇V(q)."""
        return self._terms(q, q)[0]

    def hessian(self, q):
        """∇²V(q) (twice the kernel's tangent at q₀ = q₁)."""
        return self._matrix(2.0 * self._terms(q, q)[1])

    def discrete_gradient(self, q0, q1):
        """(\\bar∇V, ∂\\bar∇V/∂q₁): the exact, rotation-equivariant discrete gradient of
        :mod:`.rotation_kernel` and its derivative with respect to the step's end."""
        g, data = self._terms(q0, q1)
        return g, self._matrix(data)
