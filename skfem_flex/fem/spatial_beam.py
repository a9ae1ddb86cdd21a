r"""Linear spatial Timoshenko beam on a scikit-fem line mesh.

:class:`TimoshenkoBeam3D` turns a :class:`skfem.MeshLine` over the arc length s of a straight beam and a
:class:`~skfem_flex.fem.spatial_section.SpatialSection` into scikit-fem bases, the constant stiffness and
consistent mass matrices (the forms of :mod:`skfem_flex.fem.spatial_forms`), load vectors, static
solutions and natural modes. The six fields u₁, u₂, u₃, θ₁, θ₂, θ₃ are in the section's axes (d₁, d₂ the
principal axes, d₃ the beam axis); the basis is built on the arc length, never on points in space (the
affine line mapping of scikit-fem degenerates for a line embedded in 3D).
"""
from __future__ import annotations

import numpy as np
from skfem import Basis, ElementLineP1, ElementLineP2, asm

from . import spatial_forms as forms
from .beam import LinearBeamAnalyses, check_mesh, gauss_line
from .spatial_section import SpatialSection
from ..numerics.resources import BYTES_PER_ELEMENT, check_fits

__all__ = ["TimoshenkoBeam3D", "FIELDS_3D"]

#: the fields of a node, in order
FIELDS_3D = ("u1", "u2", "u3", "theta1", "theta2", "theta3")


class TimoshenkoBeam3D(LinearBeamAnalyses):
    """Linear spatial Timoshenko beam: bases, K, M, loads, statics, modes (module docstring).

    Parameters
    ----------
    mesh : skfem.MeshLine
        The arc length s (m) of a straight beam: one chain of elements.
    section : SpatialSection
    order : {1, 2}
        P1 or P2 for all six fields.

    Attributes
    ----------
    n_dofs : int
        Six per node.
    x_nodes : ndarray
        Node coordinates s (m), ascending (P2 midpoints included).
    node_dofs : ndarray (n_nodes, 6)
        The DOFs (u₁, u₂, u₃, θ₁, θ₂, θ₃) of those nodes.

    Examples
    --------
    >>> import numpy as np, skfem
    >>> sec = SpatialSection(EA=1e7, GA1=4e6, GA2=4e6, GJ=8e5, EI1=8e5, EI2=8e5, rhoA=1.0, rhoI1=0.1, rhoI2=0.1)
    >>> beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0, 2, 9)), sec)
    >>> q = beam.solve_static(beam.point_load(2.0, force=(0.0, 0.0, 1.0)), fixed=beam.dofs_at(0.0))
    >>> round(q[beam.dofs_at(2.0)[2]] * 1e7, 6)     # F L / EA
    2.0
    """

    def __init__(self, mesh, section, order=1):
        check_mesh(mesh)
        if not isinstance(section, SpatialSection):
            raise ValueError(f"section must be a skfem_flex SpatialSection, got {section!r}")
        if isinstance(order, bool) or order not in (1, 2):
            raise ValueError(f"order must be 1 or 2, got {order!r}")
        n_el = mesh.t.shape[1]
        check_fits(2 * BYTES_PER_ELEMENT * order * n_el, f"a spatial beam of {n_el} elements (order {order})")
        self.mesh, self.section, self.order = mesh, section, int(order)
        scalar = ElementLineP1() if order == 1 else ElementLineP2()
        element = scalar * scalar * scalar * scalar * scalar * scalar
        self.basis = Basis(mesh, element, quadrature=gauss_line(order + 1))
        self.shear_basis = Basis(mesh, element, quadrature=gauss_line(order))
        self.field_basis = Basis(mesh, scalar, quadrature=gauss_line(order + 1))
        field_dofs = np.array(self.basis.split_indices())               # (6, n_nodes)
        self.n_dofs = self.basis.N
        x = self.field_basis.doflocs[0]
        by_x = np.argsort(x, kind="stable")
        self.x_nodes = x[by_x]
        self.node_dofs = np.ascontiguousarray(field_dofs[:, by_x].T)
        self.length = float(self.x_nodes[-1] - self.x_nodes[0])
        self._stiffness = self._mass = None

    def stiffness(self):
        """K of the axial, torsion, bending and (reduced-rule) shear forms, assembled once (csr)."""
        if self._stiffness is None:
            s = self.section
            self._stiffness = (asm(forms.axial, self.basis, EA=s.EA) + asm(forms.torsion, self.basis, GJ=s.GJ)
                               + asm(forms.bending, self.basis, EI1=s.EI1, EI2=s.EI2)
                               + asm(forms.shear, self.shear_basis, GA1=s.GA1, GA2=s.GA2)).tocsr()
        return self._stiffness

    def mass(self):
        """The consistent mass, assembled once (csr; kg, kg m²)."""
        if self._mass is None:
            s = self.section
            self._mass = asm(forms.mass, self.basis, rhoA=s.rhoA, rhoI1=s.rhoI1, rhoI2=s.rhoI2).tocsr()
        return self._mass

    def point_load(self, x, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)):
        """The load vector of a force (N) and a moment (N m), in the section's axes, at the node at x (m)."""
        f = np.asarray(force, dtype=float).ravel()
        m = np.asarray(moment, dtype=float).ravel()
        if f.shape != (3,) or m.shape != (3,) or not (np.all(np.isfinite(f)) and np.all(np.isfinite(m))):
            raise ValueError(f"force and moment must be finite 3-vectors, got {force!r} and {moment!r}")
        out = np.zeros(self.n_dofs)
        out[self.dofs_at(x)] = np.concatenate([f, m])
        return out

    def distributed_load(self, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)):
        """The load vector of a uniform force (N/m) and moment (N m/m) per length, in the section's axes."""
        f = np.asarray(force, dtype=float).ravel()
        m = np.asarray(moment, dtype=float).ravel()
        if f.shape != (3,) or m.shape != (3,) or not (np.all(np.isfinite(f)) and np.all(np.isfinite(m))):
            raise ValueError(f"force and moment must be finite 3-vectors, got {force!r} and {moment!r}")
        return asm(forms.distributed_load, self.basis, f1=f[0], f2=f[1], f3=f[2], m1=m[0], m2=m[1], m3=m[2])
