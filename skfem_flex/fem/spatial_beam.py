r"""Linear spatial Timoshenko beam on a scikit-fem line mesh.

:class:`TimoshenkoBeam3D` turns a :class:`skfem.MeshLine` over the arc length s of a straight beam and a
:class:`~skfem_flex.fem.spatial_section.SpatialSection` into scikit-fem bases, the constant stiffness and
consistent mass matrices (the forms of :mod:`skfem_flex.fem.spatial_forms`), load vectors, static
solutions and natural modes. The six fields u₁, u₂, u₃, θ₁, θ₂, θ₃ are in the section's axes (d₁, d₂ the
principal axes, d₃ the beam axis); the basis is built on the arc length, never on points in space (the
affine line mapping of scikit-fem degenerates for a line embedded in 3D).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from skfem import Basis, ElementLineP1, ElementLineP2, asm

from . import spatial_forms as forms
from .beam import LinearBeamAnalyses, check_mesh, gauss_line
from .spatial_section import SpatialSection
from ..numerics.resources import BYTES_PER_ELEMENT, check_fits

__all__ = ["TimoshenkoBeam3D", "FIELDS_3D", "RotatingModes", "repeated_pairs"]

#: the fields of a node, in order
FIELDS_3D = ("u1", "u2", "u3", "theta1", "theta2", "theta3")


def repeated_pairs(lam):
    """The k whose eigenvalues lam[k], lam[k + 1] are one repeated value (within 1e-6 of each other, as a
    state-space eigensolver leaves a repeated frequency)."""
    return [k for k in range(len(lam) - 1) if abs(lam[k + 1] - lam[k]) <= 1e-6 * max(abs(lam[k]), 1e-300)]


@dataclass(frozen=True)
class RotatingModes:
    """Modes of a beam about steady rotation (:meth:`TimoshenkoBeam3D.rotating_modes`).

    Attributes
    ----------
    omega : ndarray
        Natural angular frequencies in the rotating frame, rad/s, ascending (0 for a diverging mode).
    growth : ndarray
        Real parts of the eigenvalues, 1/s: zero for a stable mode, positive for one that diverges.
    flapwise : ndarray of bool
        True for a mode whose motion is mostly along the spin axis d₁ (out of the plane of rotation), False
        for a lead-lag mode (u₂, in the plane).
    shapes : ndarray (n_dofs, n), complex
        On the beam's DOFs.
    """

    omega: np.ndarray
    growth: np.ndarray
    flapwise: np.ndarray
    shapes: np.ndarray

    @classmethod
    def from_eigenpairs(cls, lam, shapes, flap_rows, lag_rows):
        """The modes of the eigenvalues ``lam`` (one of each conjugate pair, lowest first) and their ``shapes``
        (complex columns), classified by the size of their motion on ``flap_rows`` (along the spin axis)
        against ``lag_rows`` (in the plane of rotation). A repeated frequency (no spin and equal bending
        stiffnesses; eigenvalues within 1e-6 of each other, as the state-space eigensolver leaves them) has any
        mix of its pair as a mode: the pair is turned into the one with the most and the one with the least
        flapwise motion first."""
        shapes = np.array(shapes, dtype=complex)
        for k in repeated_pairs(lam):
                pair = shapes[:, k:k + 2]
                _, _, vh = np.linalg.svd(pair[flap_rows])
                shapes[:, k:k + 2] = pair @ vh.conj().T
        flap = np.abs(shapes[flap_rows]).sum(axis=0)
        lag = np.abs(shapes[lag_rows]).sum(axis=0)
        return cls(np.abs(lam.imag), np.maximum(lam.real, 0.0), flap > lag, shapes)

    def first(self, flapwise):
        """(ω, growth) of the lowest flapwise (True) or lead-lag (False) mode."""
        k = int(np.flatnonzero(self.flapwise == bool(flapwise))[0])
        return float(self.omega[k]), float(self.growth[k])


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

    def _spin_matrices(self, r):
        """(K_σ, M_c, G) at Ω = 1 for the hub radius r, assembled once per r (they scale with Ω², Ω², Ω)."""
        cache = self.__dict__.setdefault("_spin_cache", {})
        if r not in cache:
            rhoA = self.section.rhoA
            cache[r] = (asm(forms.centrifugal_tension, self.basis, rhoA=rhoA, Omega=1.0, r=r, L=self.length),
                        asm(forms.centrifugal_softening, self.basis, rhoA=rhoA),
                        asm(forms.coriolis, self.basis, rhoA=rhoA))
        return cache[r]

    def rotating_modes(self, fixed, omega, hub_radius=0.0, stiffening=True, n_modes=8):
        r"""Modes about a steady spin Ω about the hub's axis d₁ (normal to the beam, through the root at radius
        ``hub_radius`` from the spin axis), in the rotating frame:

        .. math::  M \ddot q + 2Ω G \dot q + (K + K_σ − Ω² M_c) q = 0,

        with K_σ the geometric stiffness of the centrifugal tension N(s) = ρA Ω² (r (L − s) + (L² − s²)/2)
        (``stiffening=False`` leaves it out: the linear-strain model, whose lead-lag mode diverges beyond
        Ω² = K/M), M_c the centrifugal force of displacements in the plane of rotation and G the Coriolis
        coupling of the lead-lag and axial motion (forms in :mod:`.spatial_forms`; the section's rotary
        inertia enters M only). Solved as the first-order system of the free DOFs (dense).

        Parameters
        ----------
        fixed : array_like of int
            DOFs held at zero (the clamp, and e.g. every u₃ for an inextensible beam).
        omega : float
            Ω, rad/s.
        hub_radius : float
            r, m.
        stiffening : bool
        n_modes : int
            How many modes to return, lowest first.

        Returns
        -------
        RotatingModes
        """
        om = float(omega)
        r = float(hub_radius)
        if not (np.isfinite(om) and np.isfinite(r)):
            raise ValueError(f"omega and hub_radius must be finite, got {omega!r} and {hub_radius!r}")
        fixed = self._fixed(fixed)
        free = np.setdiff1d(np.arange(self.n_dofs), fixed)
        tension, softening, coriolis = self._spin_matrices(r)
        K = self.stiffness() - om ** 2 * softening + (om ** 2 * tension if stiffening else 0.0)
        G = 2.0 * om * coriolis
        M, K, G = (a.tocsr()[free][:, free].toarray() for a in (self.mass(), K, G))
        n = free.size
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, G)]])
        lam, vec = scipy.linalg.eig(A)
        # one of each pair: the eigenvalue with imag ≥ 0; diverging modes come as real pairs ±σ (keep +σ)
        keep = (lam.imag > 1e-9 * np.abs(lam).max()) | ((np.abs(lam.imag) <= 1e-9 * np.abs(lam).max())
                                                        & (lam.real > 0))
        lam, vec = lam[keep], vec[:n, keep]
        order = np.argsort(np.abs(lam.imag) + np.abs(lam.real))[:int(n_modes)]
        lam, vec = lam[order], vec[:, order]
        shapes = np.zeros((self.n_dofs, lam.size), dtype=complex)
        shapes[free] = vec
        return RotatingModes.from_eigenpairs(lam, shapes, self.node_dofs[:, 0], self.node_dofs[:, 1])
