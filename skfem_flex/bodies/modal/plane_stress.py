r"""Plane-stress bodies from any 2D scikit-fem mesh: the elastic model behind a floating-frame link.

:class:`PlaneStress` assembles once, with scikit-fem, the stiffness (``skfem.models.elasticity``:
``linear_elasticity`` with the plane-stress Lamé parameters λ* = Eν/(1 − ν²), μ = E/(2(1 + ν)),
times the thickness t) and the consistent mass ∫ρt u·v of a vector P1/P2 (triangles) or Q1/Q2
(quadrilaterals) field, and exposes them as an :class:`~skfem_flex.bodies.modal.body.ElasticModel`
(:meth:`PlaneStress.model`) with

* interfaces: node sets (mesh boundaries such as the facets around a hole, predicates, node lists)
  acting as one point at their centre — its displacement is the mean of the set's displacements
  and its rotation the least-squares rotation of the set about its centre, Σ r_i × u_i / Σ |r_i|²;
  the set is tied to that motion rigidly (default) or only by that average — or single nodes
  (no rotation);
* the Green–Lagrange strain E = ½(∇u + ∇uᵀ + ∇uᵀ∇u) at the quadrature points (St. Venant–Kirchhoff,
  Voigt (E_XX, E_YY, 2E_XY), C the plane-stress matrix), for geometric stiffening;
* stress recovery: the element-mean displacement gradient per DOF, so that a reduced body keeps its
  modal gradient fields and gets σ_xx, σ_yy, σ_xy and von Mises per cell from η (second
  Piola–Kirchhoff stress S = C E in the body frame; equal to the Cauchy stress to first order in the
  strain).

:func:`load_mesh` reads a gmsh file through meshio into a ``MeshTri``/``MeshQuad`` with its physical
groups as named boundaries (interface candidates).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import skfem
from skfem import Basis, BilinearForm, ElementVector, asm
from skfem.helpers import dot
from skfem.models.elasticity import linear_elasticity, plane_stress

from ...fem.mesh_files import read_mesh_file
from ...fem.node_sets import select_nodes
from ..base import check_finite_vector
from .body import ElasticModel, Interface
from .stiffening import GreenLagrange

__all__ = ["PlaneStress", "load_mesh", "von_mises"]

_ELEMENTS = {(skfem.MeshTri, 1): skfem.ElementTriP1, (skfem.MeshTri, 2): skfem.ElementTriP2,
             (skfem.MeshQuad, 1): skfem.ElementQuad1, (skfem.MeshQuad, 2): skfem.ElementQuad2}
#: Green–Lagrange strain in Voigt form (E_XX, E_YY, 2E_XY) of g = (u_x,X, u_x,Y, u_y,X, u_y,Y)
_LINEAR = np.array([[1.0, 0, 0, 0], [0, 0, 0, 1.0], [0, 1.0, 1.0, 0]])
_QUADRATIC = np.zeros((3, 4, 4))
_QUADRATIC[0, 0, 0] = _QUADRATIC[0, 2, 2] = 1.0
_QUADRATIC[1, 1, 1] = _QUADRATIC[1, 3, 3] = 1.0
_QUADRATIC[2, 0, 1] = _QUADRATIC[2, 1, 0] = _QUADRATIC[2, 2, 3] = _QUADRATIC[2, 3, 2] = 1.0


@BilinearForm
def vector_mass(u, v, w):
    """ρt u·v (parameter ``rho_t``, kg/m²)."""
    return w.rho_t * dot(u, v)


def von_mises(sxx, syy, sxy):
    """σ_vM = √(σxx² − σxx σyy + σyy² + 3σxy²) for plane stress, Pa."""
    return np.sqrt(sxx * sxx - sxx * syy + syy * syy + 3.0 * sxy * sxy)


def _positive(name, value):
    if isinstance(value, bool) or not np.isscalar(value) or not np.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return float(value)


def load_mesh(path):
    """A 2D ``MeshTri`` or ``MeshQuad`` from a mesh file (gmsh ``.msh`` …) read by meshio.

    Physical groups of lines become named boundaries (``mesh.boundaries``), so they can name
    interfaces. z coordinates must be zero.

    Raises
    ------
    ValueError
        The file does not exist or cannot be read as a mesh (the message names it), it has no
        triangles or quadrilaterals, or the mesh is not planar.
    """
    raw = read_mesh_file(path)
    pts = np.asarray(raw.points, dtype=float)
    if pts.shape[1] == 3:
        if np.abs(pts[:, 2]).max() > 1e-12 * max(np.abs(pts).max(), 1.0):
            raise ValueError(f"mesh {path!r} is not planar (z ≠ 0)")
        pts = pts[:, :2]
    cells = {c.type: c.data for c in raw.cells}
    if "triangle" in cells:
        mesh = skfem.MeshTri(np.ascontiguousarray(pts.T), np.ascontiguousarray(cells["triangle"].T))
    elif "quad" in cells:
        mesh = skfem.MeshQuad(np.ascontiguousarray(pts.T), np.ascontiguousarray(cells["quad"].T))
    else:
        raise ValueError(f"mesh {path!r} has no triangles or quadrilaterals (cells: {sorted(cells)})")
    used = np.unique(mesh.t)
    if used.size < mesh.p.shape[1]:                        # drop gmsh's geometry-only points
        new = -np.ones(mesh.p.shape[1], dtype=int)
        new[used] = np.arange(used.size)
        old_to_new = new
        mesh = type(mesh)(np.ascontiguousarray(mesh.p[:, used]), np.ascontiguousarray(new[mesh.t]))
    else:
        old_to_new = np.arange(mesh.p.shape[1])
    names = {int(tag): name for name, (tag, dim) in raw.field_data.items() if dim == 1}
    groups = {}
    for block, tags in zip(raw.cells, raw.cell_data.get("gmsh:physical", [None] * len(raw.cells))):
        if block.type != "line" or tags is None:
            continue
        for tag in np.unique(tags):
            name = names.get(int(tag), f"group{int(tag)}")
            nodes = old_to_new[block.data[tags == tag].ravel()]
            groups.setdefault(name, []).append(nodes[nodes >= 0])
    if groups:
        facets = {}
        f2n = np.sort(mesh.facets, axis=0)
        for name, nodes in groups.items():
            ns = np.unique(np.concatenate(nodes))
            facets[name] = np.nonzero(np.isin(f2n[0], ns) & np.isin(f2n[1], ns))[0]
        mesh = _with_facets(mesh, facets)
    return mesh


def _with_facets(mesh, facets):
    """``mesh`` with named boundaries given as facet indices."""
    return type(mesh)(mesh.p, mesh.t, _boundaries={k: np.asarray(v, dtype=np.int64) for k, v in facets.items()})


class PlaneStress:
    """A plane-stress body on a 2D scikit-fem mesh.

    Parameters
    ----------
    mesh : skfem.MeshTri or skfem.MeshQuad
        Body-frame coordinates X, m.
    E : float
        Young's modulus, Pa.
    nu : float
        Poisson's ratio, −1 < ν < 0.5.
    rho : float
        Density, kg/m³.
    thickness : float
        Out-of-plane thickness t, m.
    order : {1, 2}
        P1/Q1 or P2/Q2 vector elements (default 2: P1 triangles lock in bending).
    interfaces : dict of str to spec, optional
        Interface points. A spec is a boundary name of the mesh (its facets' nodes, averaging
        coupling), a callable ``X (2, n) -> bool mask`` on node positions (averaging coupling),
        an array of node indices, or a point (X, Y) of floats inside the body (the nearest node; no rotation).
        Node sets are coupled rigidly (see :meth:`add_interface`).
    name : str

    Raises
    ------
    ValueError
        A mesh that is not a 2D triangle/quad mesh, ν outside (−1, 0.5), non-positive E, ρ, t,
        an unknown boundary name, an empty node set or a point outside the body.
    """

    def __init__(self, mesh, E, nu, rho, thickness=1.0, order=2, interfaces=None, name="plate"):
        if not isinstance(mesh, (skfem.MeshTri, skfem.MeshQuad)) or mesh.p.shape[0] != 2:
            raise ValueError(f"PlaneStress needs a 2D skfem.MeshTri or skfem.MeshQuad, got {mesh!r}")
        self.E, self.rho, self.thickness = _positive("E", E), _positive("rho", rho), _positive("thickness", thickness)
        if isinstance(nu, bool) or not np.isscalar(nu) or not np.isfinite(nu) or not -1.0 < nu < 0.5:
            raise ValueError(f"Poisson's ratio nu must lie in (-1, 0.5), got {nu!r}")
        if order not in (1, 2) or isinstance(order, bool):
            raise ValueError(f"order must be 1 or 2, got {order!r}")
        self.nu, self.order, self.mesh, self.name = float(nu), int(order), mesh, name
        elem = _ELEMENTS[(type(mesh), self.order)]()
        self.basis = Basis(mesh, ElementVector(elem), intorder=2 * self.order + (1 if isinstance(mesh, skfem.MeshQuad)
                                                                                   else 0))
        b = self.basis
        lam, mu = plane_stress(self.E, self.nu)
        t = self.thickness
        self.stiffness = (t * asm(linear_elasticity(lam, mu), b)).tocsr()
        self.mass = asm(vector_mass, b, rho_t=self.rho * t).tocsr()
        self.n_dofs = b.N
        self.xdofs, self.ydofs = (np.asarray(i) for i in b.split_indices())
        self.dof_positions = b.doflocs[:, self.xdofs].T                 # (n_nodes, 2) incl. P2 mid-side nodes
        c = self.E / (1.0 - self.nu ** 2)
        self.material = c * np.array([[1.0, self.nu, 0.0], [self.nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - self.nu)]])
        self.interfaces = {}
        for key, spec in (interfaces or {}).items():
            self.add_interface(key, spec)

    # ------------------------------------------------------------- interfaces
    def nodes(self, spec):
        """Node indices (into ``dof_positions``) of a boundary name, predicate or index array
        (:func:`~skfem_flex.fem.node_sets.select_nodes`)."""
        return select_nodes(spec, self.dof_positions, self.mesh.boundaries or {},
                            lambda facets: np.nonzero(np.isin(self.xdofs, self.basis.get_dofs(facets).all()))[0],
                            self.name)

    def add_interface(self, key, spec, coupling="rigid"):
        """Add the interface ``key`` (spec as in the class docstring); returns it.

        ``coupling="rigid"`` ties the node set rigidly to the interface point (a clamp, a pin in a
        stiff bush); ``"average"`` only defines the point's motion as the set's mean displacement and
        least-squares rotation, so the set deforms freely."""
        if coupling not in ("rigid", "average"):
            raise ValueError(f"coupling must be 'rigid' or 'average', got {coupling!r}")
        n = self.n_dofs
        if isinstance(spec, (tuple, list, np.ndarray)) and np.size(spec) == 2 and not isinstance(spec[0], (int,
                                                                                                          np.integer)):
            X = check_finite_vector(f"interface {key!r}", spec, 2)
            try:
                self.mesh.element_finder()(np.array([X[0]]), np.array([X[1]]))
            except ValueError:
                raise ValueError(f"interface {key!r}: point {tuple(X)} lies outside body {self.name!r}") from None
            node = int(np.argmin(np.sum((self.dof_positions - X) ** 2, axis=1)))
            P = sps.csr_matrix(([1.0, 1.0], ([0, 1], [self.xdofs[node], self.ydofs[node]])), shape=(2, n))
            itf = Interface(key, self.dof_positions[node].copy(), P)
        else:
            nodes = self.nodes(spec)
            pos = self.dof_positions[nodes]
            centre = pos.mean(axis=0)
            r = pos - centre
            k = nodes.size
            rows = [np.zeros(k), np.ones(k)]
            cols = [self.xdofs[nodes], self.ydofs[nodes]]
            vals = [np.full(k, 1.0 / k), np.full(k, 1.0 / k)]
            r2 = float(np.sum(r * r))
            if k >= 2 and r2 > 0:
                rows += [np.full(k, 2), np.full(k, 2)]
                cols += [self.xdofs[nodes], self.ydofs[nodes]]
                vals += [-r[:, 1] / r2, r[:, 0] / r2]
            m = 3 if len(rows) == 4 else 2
            P = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows).astype(int), np.concatenate(cols))),
                               shape=(m, n))
            itf = Interface(key, centre, P)
            if coupling == "rigid" and m == 3:
                rmap = np.zeros((2 * k, 3))
                rmap[:k, 0], rmap[k:, 1] = 1.0, 1.0
                rmap[:k, 2], rmap[k:, 2] = -r[:, 1], r[:, 0]
                itf = Interface(key, centre, P, np.concatenate([self.xdofs[nodes], self.ydofs[nodes]]), rmap)
        self.interfaces[key] = itf
        self._model = None                       # a model built before no longer lists every interface
        return itf

    # ------------------------------------------------------------- strain and stress
    def _gradient_operators(self, average):
        """G_k (k = u_x,X, u_x,Y, u_y,X, u_y,Y) as sparse maps d ↦ values at quadrature points
        (n_el n_qp rows) or, with ``average``, element means (n_el rows)."""
        b = self.basis
        nel, nqp = b.dx.shape
        ed = b.element_dofs                                              # (n_local, n_el)
        ops = []
        for a in range(2):
            for c in range(2):
                vals = np.stack([b.basis[i][0].grad[a, c] for i in range(ed.shape[0])])   # (n_local, nel, nqp)
                if average:
                    vals = (vals * b.dx).sum(axis=2) / b.dx.sum(axis=1)
                    rows = np.broadcast_to(np.arange(nel), vals.shape)
                    shape = (nel, self.n_dofs)
                else:
                    rows = np.broadcast_to(np.arange(nel)[:, None] * nqp + np.arange(nqp), vals.shape)
                    shape = (nel * nqp, self.n_dofs)
                cols = np.broadcast_to(ed.reshape(ed.shape + (1,) * (vals.ndim - 2)), vals.shape)
                ops.append(sps.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=shape))
        return ops

    def green_lagrange(self):
        """The :class:`~skfem_flex.bodies.modal.stiffening.GreenLagrange` strain of this body."""
        return GreenLagrange(self._gradient_operators(False), _LINEAR, _QUADRATIC, self.material,
                             (self.basis.dx * self.thickness).ravel())

    def stresses(self, g):
        """σxx, σyy, σxy, von Mises (Pa) from displacement gradients g (…, 4): S = C E(g), E Green–Lagrange."""
        E = g @ _LINEAR.T + 0.5 * np.einsum("...g,agh,...h->...a", g, _QUADRATIC, g)
        s = E @ self.material.T
        return dict(sxx=s[..., 0], syy=s[..., 1], sxy=s[..., 2], von_mises=von_mises(s[..., 0], s[..., 1], s[..., 2]))

    # ------------------------------------------------------------- the model
    def model(self):
        """This body as an :class:`~skfem_flex.bodies.modal.body.ElasticModel` (built once)."""
        if getattr(self, "_model", None) is not None:
            return self._model
        n = self.n_dofs
        xd, yd = self.xdofs, self.ydofs
        trans = np.zeros((n, 2))
        trans[xd, 0] = 1.0
        trans[yd, 1] = 1.0
        pos = np.zeros(n)
        pos[xd], pos[yd] = self.dof_positions[:, 0], self.dof_positions[:, 1]
        turn = sps.csr_matrix((np.r_[-np.ones(xd.size), np.ones(xd.size)], (np.r_[xd, yd], np.r_[yd, xd])),
                              shape=(n, n))
        mesh, b = self.mesh, self.basis
        vx, vy = b.nodal_dofs                                         # vertex DOFs, in mesh.p order
        cell = "triangle" if isinstance(mesh, skfem.MeshTri) else "quad"
        cells = [(cell, mesh.t.T.copy())]
        finder = mesh.element_finder()

        def locate(X):
            try:
                finder(np.array([X[0]]), np.array([X[1]]))
            except ValueError:
                raise ValueError(f"point {tuple(X)} lies outside body {self.name!r}") from None
            return b.probes(np.array([[X[0]], [X[1]]])).toarray(), None

        def output(d):
            return mesh.p.T.copy(), np.stack([d[vx], d[vy]], axis=1), cells, {}

        self._model = ElasticModel(mass=self.mass, stiffness=self.stiffness, translation=trans, position=pos,
                                   turn=turn, interfaces=dict(self.interfaces), strain=self.green_lagrange(),
                                   name=self.name, locate=locate, output=output,
                                   stress_operators=self._gradient_operators(True), stresses=self.stresses)
        return self._model

    def reduced(self, n_modes, interfaces=None, **kwargs):
        """A reduced floating-frame body (:func:`~skfem_flex.bodies.modal.reduction.reduce`)."""
        from .reduction import reduce
        return reduce(self.model(), n_modes, interfaces=interfaces, **kwargs)

    def body(self, **kwargs):
        """The unreduced floating-frame body (:func:`~skfem_flex.bodies.modal.reduction.full_body`)."""
        from .reduction import full_body
        return full_body(self.model(), **kwargs)
