r"""Linear 3D elasticity on a scikit-fem mesh: the elastic model behind a spatial floating-frame solid.

:class:`ElasticSolid3D` assembles once, with scikit-fem, the stiffness
(``skfem.models.elasticity.linear_elasticity`` with the Lamé parameters of E and ν) and the consistent mass
∫ρ u·v of a vector field on a ``MeshTet`` (P1 or P2) or ``MeshHex`` (Q1), and gives

* node sets (a named boundary of the mesh, a predicate on the node positions, or node indices) for
  interfaces;
* the cell-mean strain operator (Voigt: ε_xx, ε_yy, ε_zz, 2ε_yz, 2ε_xz, 2ε_xy per cell) and the material
  matrix C, so that a reduced body recovers stresses σ = C ε and von Mises per cell from its modal
  amplitudes;
* the scalar mass ∫ρ N_a N_b and the node positions, from which the floating-frame invariants are taken.

Every figure is in SI units (m, Pa, kg/m³).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import skfem
from skfem import Basis, BilinearForm, ElementHex1, ElementTetP1, ElementTetP2, ElementVector, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from .mesh_files import read_mesh_file
from .node_sets import select_nodes
from .spd_solver import lowest_modes
from .section import positive_number

__all__ = ["ElasticSolid3D", "von_mises_3d", "load_mesh_3d"]

_ELEMENTS = {(skfem.MeshTet1, 1): ElementTetP1, (skfem.MeshTet1, 2): ElementTetP2, (skfem.MeshHex1, 1): ElementHex1}


@BilinearForm
def _vector_mass(u, v, w):
    return w.rho * dot(u, v)


@BilinearForm
def _scalar_mass(u, v, w):
    return w.rho * u * v


def von_mises_3d(stress):
    """Von Mises stress of Voigt stresses (…, 6) = (σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy), Pa."""
    s = np.asarray(stress, dtype=float)
    sx, sy, sz, syz, sxz, sxy = (s[..., k] for k in range(6))
    return np.sqrt(0.5 * ((sx - sy) ** 2 + (sy - sz) ** 2 + (sz - sx) ** 2) + 3.0 * (syz ** 2 + sxz ** 2 + sxy ** 2))


def _check_elements(mesh):
    """ValueError naming the first degenerate tetrahedron (zero volume; either node order is fine, scikit-fem
    integrates with |det J|) or inverted hexahedron (det J changes sign or vanishes inside it)."""
    if isinstance(mesh, skfem.MeshTet1):
        p = mesh.p[:, mesh.t]                                        # (3, 4, n_el)
        det = np.einsum("ik,ik->k", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], axis=0), p[:, 3] - p[:, 0])
        size = float(np.ptp(mesh.p, axis=1).max()) ** 3
        bad = np.flatnonzero(np.abs(det) <= 1e-14 * size)
    else:
        corners = np.array([[i, j, k] for i in (0.0, 1.0) for j in (0.0, 1.0) for k in (0.0, 1.0)]).T
        det = mesh.mapping().detDF(np.hstack([corners, np.full((3, 1), 0.5)]))      # (n_el, 9)
        bad = np.flatnonzero(~(np.all(det > 0, axis=1) | np.all(det < 0, axis=1)))
    if bad.size:
        raise ValueError(f"the mesh has {bad.size} inverted or degenerate element(s), the first element "
                         f"{int(bad[0])}: fix its node order or shape")


def load_mesh_3d(path):
    """A ``MeshTet`` or ``MeshHex`` from a mesh file (gmsh ``.msh`` …) read by meshio, its physical groups of
    triangles or quadrilaterals as named boundaries (``mesh.boundaries``: interface and clamp candidates).

    Raises
    ------
    ValueError
        The file does not exist or is no mesh meshio can read (the message names it), or it holds no
        tetrahedra or hexahedra (first order).
    """
    raw = read_mesh_file(path)
    cells = {c.type: c.data for c in raw.cells}
    if "tetra" in cells:
        kind, t, facet_type = skfem.MeshTet, cells["tetra"].T, "triangle"
    elif "hexahedron" in cells:
        # meshio's (VTK's) corner order to scikit-fem's
        kind, t, facet_type = skfem.MeshHex, cells["hexahedron"][:, [0, 4, 3, 1, 7, 5, 2, 6]].T, "quad"
    else:
        raise ValueError(f"mesh {str(path)!r} has no tetrahedra or hexahedra (cells: {sorted(cells)})")
    pts = np.asarray(raw.points, dtype=float)
    used = np.unique(t)
    new = -np.ones(pts.shape[0], dtype=np.int64)
    new[used] = np.arange(used.size)                  # drop gmsh's geometry-only points
    mesh = kind(np.ascontiguousarray(pts[used].T), np.ascontiguousarray(new[t]))
    names = {int(tag): name for name, (tag, dim) in raw.field_data.items() if dim == 2}
    groups = {}
    for block, tags in zip(raw.cells, raw.cell_data.get("gmsh:physical", [None] * len(raw.cells))):
        if block.type != facet_type or tags is None:
            continue
        for tag in np.unique(tags):
            nodes = new[block.data[tags == tag].ravel()]
            groups.setdefault(names.get(int(tag), f"group{int(tag)}"), []).append(nodes[nodes >= 0])
    if not groups:
        return mesh
    facets = {}
    for name, parts in groups.items():
        nodes = np.unique(np.concatenate(parts))
        facets[name] = np.flatnonzero(np.all(np.isin(mesh.facets, nodes), axis=0))
    return kind(mesh.p, mesh.t, _boundaries={k: np.asarray(v, dtype=np.int64) for k, v in facets.items()})


class ElasticSolid3D:
    """A linear-elastic solid on a 3D scikit-fem mesh (module docstring).

    Parameters
    ----------
    mesh : skfem.MeshTet or skfem.MeshHex
        Positions in the body frame, m.
    E : float
        Young's modulus, Pa.
    nu : float
        Poisson's ratio, −1 < ν < 0.5.
    rho : float
        Density, kg/m³.
    order : {1, 2}
        P1 or P2 tetrahedra (default 2: P1 tetrahedra lock in bending); Q1 only on hexahedra.
    name : str

    Attributes
    ----------
    stiffness, mass : csr_matrix (n_dofs, n_dofs)
    component_dofs : ndarray (3, n_nodes)
        The DOFs of u_x, u_y, u_z of every node (P2 mid-edge nodes included).
    node_positions : ndarray (n_nodes, 3)
    scalar_mass : csr_matrix (n_nodes, n_nodes)
        ∫ρ N_a N_b, kg.

    Raises
    ------
    ValueError
        A mesh that is not a 3D tetrahedral or hexahedral one, a degenerate or inverted element, ν outside (−1, 0.5),
        non-positive E or ρ, or an order the mesh has no element for.
    """

    def __init__(self, mesh, E, nu, rho, order=2, name="solid"):
        if not isinstance(mesh, (skfem.MeshTet1, skfem.MeshHex1)) or mesh.p.shape[0] != 3:
            raise ValueError(f"ElasticSolid3D needs a 3D skfem.MeshTet or skfem.MeshHex, got {mesh!r}")
        self.E, self.rho = positive_number("E", E), positive_number("rho", rho)
        if isinstance(nu, bool) or not np.isscalar(nu) or not np.isfinite(nu) or not -1.0 < nu < 0.5:
            raise ValueError(f"Poisson's ratio nu must lie in (-1, 0.5), got {nu!r}")
        key = (type(mesh), order)
        if isinstance(order, bool) or key not in _ELEMENTS:
            raise ValueError(f"order {order!r} is not available on a {type(mesh).__name__} (P1, P2 on tetrahedra; "
                             f"Q1 on hexahedra)")
        _check_elements(mesh)
        self.nu, self.order, self.mesh, self.name = float(nu), int(order), mesh, name
        scalar = _ELEMENTS[key]()
        self.basis = Basis(mesh, ElementVector(scalar))
        self.scalar_basis = Basis(mesh, scalar)
        lam, mu = lame_parameters(self.E, self.nu)
        self.stiffness = asm(linear_elasticity(lam, mu), self.basis).tocsr()
        self.mass = asm(_vector_mass, self.basis, rho=self.rho).tocsr()
        self.scalar_mass = asm(_scalar_mass, self.scalar_basis, rho=self.rho).tocsr()
        self.n_dofs = self.basis.N
        self.component_dofs = np.array(self.basis.split_indices())
        self.node_positions = self.scalar_basis.doflocs.T.copy()
        self.material = lam * np.outer(np.r_[1.0, 1.0, 1.0, 0.0, 0.0, 0.0], np.r_[1.0, 1.0, 1.0, 0.0, 0.0, 0.0]) \
            + mu * np.diag([2.0, 2.0, 2.0, 1.0, 1.0, 1.0])

    @property
    def volume(self):
        """∫ dV, m³."""
        return float(self.basis.dx.sum())

    def nodes(self, spec):
        """Node indices of a boundary name, a predicate ``X (3, n) -> bool mask`` on the node positions, or an
        index array (:func:`~skfem_flex.fem.node_sets.select_nodes`)."""
        return select_nodes(spec, self.node_positions, self.mesh.boundaries or {},
                            lambda facets: self.scalar_basis.get_dofs(facets).all(), self.name)

    def rigid_map(self, nodes, centre):
        """(dofs, R): the displacement DOFs of ``nodes`` and the (3k, 6) map of a small rigid motion
        (translation t, rotation θ about ``centre``) onto them, u = t + θ × (X − centre) (k nodes)."""
        r = self.node_positions[nodes] - np.asarray(centre, dtype=float)
        k = len(nodes)
        R = np.zeros((3, k, 6))
        for c in range(3):
            R[c, :, c] = 1.0
        # θ × r: x: θ_y r_z − θ_z r_y; y: θ_z r_x − θ_x r_z; z: θ_x r_y − θ_y r_x
        R[0, :, 4], R[0, :, 5] = r[:, 2], -r[:, 1]
        R[1, :, 5], R[1, :, 3] = r[:, 0], -r[:, 2]
        R[2, :, 3], R[2, :, 4] = r[:, 1], -r[:, 0]
        return self.component_dofs[:, nodes].ravel(), R.reshape(3 * k, 6)

    def average_map(self, nodes):
        """(dofs, P): the displacement DOFs of ``nodes`` and the (6, 3k) least-squares rigid motion of the set
        about its centre, w = (RᵀR)⁻¹Rᵀ u (R of :meth:`rigid_map`): the mean displacement and the rotation
        J⁻¹ Σ r × u, J = Σ (‖r‖²I − r rᵀ). The set itself stays free to deform (an averaging, RBE3-like
        connection); a rotation the set cannot show (nodes on one line) is left at zero."""
        dofs, R = self.rigid_map(nodes, self.node_positions[nodes].mean(axis=0))
        return dofs, np.linalg.pinv(R.T @ R) @ R.T

    def tie(self, clamped, rigid_sets):
        """(T, n_free): u = T w, w = (the free DOFs, then six DOFs (t, θ) of each rigid node set about its centre),
        with the ``clamped`` nodes' DOFs held at zero; ``n_free`` the number of free DOFs (csr T)."""
        held = [self.component_dofs[:, np.asarray(clamped, dtype=int)].ravel()]
        rows, cols, vals = [], [], []
        for k, nodes in enumerate(rigid_sets):
            dofs, R = self.rigid_map(nodes, self.node_positions[nodes].mean(axis=0))
            held.append(dofs)
            rr, cc = np.nonzero(R)
            rows.append(dofs[rr])
            cols.append(6 * k + cc)
            vals.append(R[rr, cc])
        free = np.setdiff1d(np.arange(self.n_dofs), np.concatenate(held))
        rows = np.concatenate([free] + rows)
        cols = np.concatenate([np.arange(free.size)] + [free.size + c for c in cols])
        vals = np.concatenate([np.ones(free.size)] + vals)
        return sps.csr_matrix((vals, (rows, cols)), shape=(self.n_dofs, free.size + 6 * len(rigid_sets))), free.size

    def natural_frequencies(self, n, clamped, rigid_sets=()):
        """The n lowest natural frequencies (rad/s) of the mesh with the ``clamped`` nodes held and each rigid
        node set tied to six DOFs (:meth:`tie`): sparse, ``eigsh`` in shift-invert mode about zero
        (:func:`~skfem_flex.fem.spd_solver.lowest_modes`)."""
        T, _ = self.tie(clamped, rigid_sets)
        lam = lowest_modes((T.T @ self.stiffness @ T).tocsc(), (T.T @ self.mass @ T).tocsc(), int(n))[0]
        return np.sqrt(np.maximum(lam, 0.0))

    def cell_strain_operator(self):
        """(n_cells · 6, n_dofs) csr: the cell-mean strains (Voigt, engineering shear) of a displacement vector."""
        b = self.basis
        nloc = b.element_dofs.shape[0]
        dx = b.dx                                                       # (n_cells, n_qp)
        vol = dx.sum(axis=1)
        rows, cols, vals = [], [], []
        voigt = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
        for a in range(nloc):
            grad = b.basis[a][0].grad                                   # (3 comp, 3 dir, n_cells, n_qp)
            mean = np.einsum("ijkq,kq->ijk", grad, dx) / vol            # (3, 3, n_cells)
            for v, (i, j) in enumerate(voigt):
                val = mean[i, j] if i == j else mean[i, j] + mean[j, i]
                rows.append(6 * np.arange(b.nelems) + v)
                cols.append(b.element_dofs[a])
                vals.append(val)
        return sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                              shape=(6 * b.nelems, self.n_dofs))
