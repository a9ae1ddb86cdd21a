r"""A meshed 3D solid in the spatial floating frame, reduced by Craig–Bampton: :class:`FloatingSolid3D`.

The solid (:class:`~skfem_flex.fem.elasticity3d.ElasticSolid3D`) is clamped to the body frame at one node set,
the ``frame`` interface, held rigidly (an RBE2 connection: its nodes move as the frame does, so they have no
elastic displacement); the frame's origin is that set's centre and its axes the mesh's axes. Further
``interfaces`` are node sets tied rigidly to an interface point at their centre, with six DOFs each (a small
translation t and rotation θ: u = t + θ × (X − centre) on the set).

**Craig–Bampton.** With the frame set removed and every interface set replaced by its six DOFs (u = T w),
the reduction basis on w is

.. math::  Φ_w = \begin{bmatrix} Φ_i & Ψ \\ 0 & I \end{bmatrix},\qquad Ψ = −K_{ii}^{-1} K_{ib},

Φ_i the lowest ``n_modes`` fixed-interface modes (every interface held), Ψ the static constraint modes of
the interface DOFs (one sparse factorization, :mod:`~skfem_flex.fem.spd_solver`, and ``eigsh`` in shift-invert
mode on it: the reduction stays sparse), and Φ = T Φ_w
on the mesh's DOFs. The elastic coordinates are η = (modal amplitudes, interface DOFs): the interface
DOFs are coordinates of their own, so an interface point's displacement is three of them.

**Invariants.** With X₀ the node positions from the origin, Φ_k the rows of Φ on the u_k DOFs and M_s the
scalar mass ∫ρN_aN_b, the floating-frame invariants (``inertia.py``, ``kinetics.py``) are
m = 1ᵀM_s1, S₀ = 1ᵀM_sX₀, S̄_k = 1ᵀM_sΦ_k, I₀ = X₀ᵀM_sX₀, P_ik = X₀ᵢᵀM_sΦ_k and N_ik = Φ_iᵀM_sΦ_k, exact for
the mesh's interpolation, computed once from sparse products.

**Strain and stress.** The strain energy is ½ηᵀΦᵀKΦη (linear elasticity in the body frame: a finite rigid
motion strains nothing), or with ``strain="green-lagrange"`` the Green–Lagrange energy of ``solid_strain.py``
(geometric stiffening, with modal derivatives and spin shapes in the basis). Stresses come back per cell from
η: σ = C ε̄ with the cell-mean strains ε̄ of the modes, precomputed (the linear stress); von Mises from σ.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.linalg

from ...fem.elasticity3d import ElasticSolid3D, von_mises_3d
from ...fem.spd_solver import lowest_modes, spd_factor
from ..base import BodyGeometry, check_finite_vector
from ..modal.stiffening import QUARTIC_LIMIT
from ..spatial import SpatialPoint
from . import kinetics
from .frame import ElasticPoint, FloatingFrame3D
from .inertia import SpatialFrameInertia
from .reduction import m_complement
from .solid_strain import SolidGreenLagrange, stiffening_loads

__all__ = ["FloatingSolid3D", "QuadraticEnergy", "FrequencyCheck"]

#: VTK's hexahedron corner order as indices into scikit-fem's (``skfem.io.meshio``'s mapping)
_HEX_TO_VTK = (0, 3, 6, 2, 1, 5, 7, 4)


class FrequencyCheck(NamedTuple):
    """A reduced body's natural frequencies against its full mesh's (:meth:`FloatingSolid3D.frequency_errors`).

    Attributes
    ----------
    reduced, full : ndarray (n,)
        The reduced body's and the full mesh's lowest natural frequencies, rad/s.
    error : ndarray (n,)
        reduced / full − 1.
    """

    reduced: np.ndarray
    full: np.ndarray
    error: np.ndarray


class QuadraticEnergy:
    """V(η) = ½ ηᵀ K η with a constant K: its gradient, Hessian and (exact, mid-point) discrete gradient."""

    nonlinear = False

    def __init__(self, K):
        self.K = np.asarray(K, dtype=float)

    def energy(self, y):
        return 0.5 * float(y @ (self.K @ y))

    def gradient(self, y):
        return self.K @ y

    def hessian(self, y):
        return self.K.copy()

    def discrete_gradient(self, y0, y1):
        return self.K @ (0.5 * (y0 + y1)), 0.5 * self.K

    def compiled_strain(self):
        """The compiled core's form of this energy, keyword arguments of :func:`.kernel.kernel_data`: K."""
        return {"K": self.K}


def _interface_sets(solid, frame, interfaces):
    """{name: nodes} of the frame set and the interfaces (rigid and averaged); ValueError for overlapping sets."""
    sets = {"frame": solid.nodes(frame)}
    for name, spec in interfaces.items():
        if name == "frame":
            raise ValueError("'frame' names the frame's own interface: give the others other names")
        sets[name] = solid.nodes(spec)
    seen = {}
    for name, nodes in sets.items():
        for other, prev in seen.items():
            common = np.intersect1d(nodes, prev)
            if common.size:
                raise ValueError(f"interfaces {other!r} and {name!r} share {common.size} node(s): give disjoint sets")
        seen[name] = nodes
    return sets


class FloatingSolid3D(FloatingFrame3D):
    """A reduced 3D solid in the spatial floating frame (module docstring).

    Coordinates q = (x, d₁, d₂, d₃, η): the frame (origin at the centre of the ``frame`` node set, axes the
    mesh's) and η = (``n_modes`` modal amplitudes, then, Craig–Bampton: t_x, t_y, t_z, θ_x, θ_y, θ_z of each
    interface in the frame's axes; free-interface: the amplitudes ``static1``, … of the residual attachment
    modes, six per interface), then the averaged interfaces' attachment modes and the stiffening vectors.

    Parameters
    ----------
    solid : ElasticSolid3D
    frame : str, callable or array of int
        The node set clamped to the frame (a boundary name, a predicate on node positions or node indices).
    n_modes : int
        Fixed-interface modes kept.
    interfaces : dict of str to node-set spec, optional
        Further rigid interfaces.
    averaged : dict of str to node-set spec, optional
        Averaging (RBE3-like) interfaces: a point at the set's centre that moves with the set's mean
        displacement (:meth:`~skfem_flex.fem.elasticity3d.ElasticSolid3D.average_map`) while the set deforms
        freely; six attachment modes each (the static responses to unit loads spread over the set) join the
        basis, so a static load there is reproduced exactly.
    position, orientation, velocity, angular_velocity :
        The frame's initial state (as :class:`~skfem_flex.bodies.spatial.SpatialRigidBody`).
    name : str
    strain : {"linear", "green-lagrange"}
        Linear elasticity (default), or the Green–Lagrange strain on the reduced coordinates
        (``solid_strain.py``), with which a tension stiffens the body (a spinning blade).
    n_derivatives : int, optional
        With the Green–Lagrange strain: the modal derivatives of every pair of the lowest ``n_derivatives``
        fixed-interface modes join the basis (default min(3, n_modes)).
    centrifugal : bool, optional
        With the Green–Lagrange strain: the static responses to a unit spin about each frame axis join the
        basis (default True).
    reduction : {"craig-bampton", "free-interface"}
        Craig–Bampton (default: fixed-interface modes and the interfaces' static constraint modes, the
        interface DOFs coordinates of their own) or free-interface modes with static correction (the lowest
        ``n_modes`` modes with the interfaces free, and the residual attachment modes of the interface DOFs:
        the static response to a unit load there less its part in the kept modes, so that a static interface
        load is reproduced exactly). Either way the frame set is clamped (the frame's reference condition).

    Attributes
    ----------
    frequencies : ndarray (n_modes,)
        The kept modes' natural frequencies (fixed-interface or free-interface), rad/s (the first mode left out
        sets the cut-off).
    factorization : str
        Which factorization of the clamped stiffness the reduction used ("SuperLU" or "PARDISO",
        :mod:`~skfem_flex.fem.spd_solver`).

    Raises
    ------
    ValueError
        A solid that is not an ElasticSolid3D, empty, unknown or overlapping node sets, or more modes than
        the interior has DOFs.
    """

    def __init__(self, solid, frame, n_modes, interfaces=None, position=(0.0, 0.0, 0.0), orientation=None,
                 velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0), name=None, strain="linear",
                 n_derivatives=None, centrifugal=None, averaged=None, reduction="craig-bampton"):
        if not isinstance(solid, ElasticSolid3D):
            raise ValueError(f"FloatingSolid3D needs an ElasticSolid3D, got {solid!r}")
        self.solid, self.name = solid, solid.name if name is None else name
        averaged = dict(averaged or {})
        both = set(interfaces or {}) & set(averaged)
        if both:
            raise ValueError(f"interfaces {sorted(both)} are given as rigid and as averaged: give each once")
        sets = _interface_sets(solid, frame, {**(interfaces or {}), **averaged})
        X = solid.node_positions
        self._sets = sets
        self.origin = X[sets["frame"]].mean(axis=0)
        self.centres = {k: X[v].mean(axis=0) - self.origin for k, v in sets.items()}
        self.interface_names = tuple(k for k in sets if k != "frame" and k not in averaged)
        self.averaged_names = tuple(averaged)
        if strain not in ("linear", "green-lagrange"):
            raise ValueError(f"strain must be 'linear' or 'green-lagrange', got {strain!r}")
        self.strain = strain
        if reduction not in ("craig-bampton", "free-interface"):
            raise ValueError(f"reduction must be 'craig-bampton' or 'free-interface', got {reduction!r}")
        self.reduction = reduction
        self.basis, self.frequencies, tie = self._reduce(
            solid, {k: v for k, v in sets.items() if k not in averaged}, n_modes, reduction)
        self.factorization = tie[2].name
        self._averages = {k: solid.average_map(sets[k]) for k in averaged}
        if averaged:
            attach = np.hstack([self._attachment_modes(solid, tie, *self._averages[k]) for k in averaged])
            self.basis = np.hstack([self.basis, m_complement(attach, self.basis, solid.mass)])
        self.n_modes = int(n_modes)
        n_extra = 0
        if strain == "green-lagrange":
            nd = min(3, self.n_modes) if n_derivatives is None else n_derivatives
            if isinstance(nd, bool) or int(nd) != nd or not 0 <= nd <= self.n_modes:
                raise ValueError(f"n_derivatives must be an integer in [0, {self.n_modes}], got {n_derivatives!r}")
            extra = self._stiffening_vectors(solid, tie, self.basis[:, :int(nd)], self.origin,
                                             True if centrifugal is None else bool(centrifugal), self.basis)
            n_extra = extra.shape[1]
            self.basis = np.hstack([self.basis, extra])
        self.n_elastic = self.basis.shape[1]
        if strain == "green-lagrange" and self.n_elastic > QUARTIC_LIMIT:
            raise ValueError(f"strain='green-lagrange' keeps m⁴ modal tensors: at most {QUARTIC_LIMIT} elastic "
                             f"coordinates, got {self.n_elastic} (n_modes={n_modes}, n_derivatives={nd}, the "
                             f"interfaces' and the spin shapes' vectors); take fewer modes or derivatives")
        self.n_dofs = 12 + self.n_elastic
        # each rigid interface's (t, θ) per column: every column moves its set rigidly, so the fit is exact
        self._interface_motion = {}
        for k in self.interface_names:
            dofs, R = solid.rigid_map(sets[k], X[sets[k]].mean(axis=0))
            self._interface_motion[k] = np.linalg.lstsq(R, self.basis[dofs], rcond=None)[0]
        self.inertia = self._invariants(solid, self.basis, X - self.origin)
        #: ΦᵀKΦ: the linear energy's stiffness, the quadratic part of the Green–Lagrange one, the frequency check's
        self.reduced_stiffness = self.basis.T @ (solid.stiffness @ self.basis)
        self.strain_energy = (SolidGreenLagrange(solid, self.basis) if strain == "green-lagrange"
                              else QuadraticEnergy(self.reduced_stiffness))
        strain = (solid.cell_strain_operator() @ self.basis).reshape(-1, 6, self.n_elastic)
        self._stress_modes = np.einsum("ab,cbm->cam", solid.material, strain)
        self._names = (("x", "y", "z") + tuple(f"d{i}{c}" for i in (1, 2, 3) for c in "xyz")
                       + tuple(f"eta{k + 1}" for k in range(self.n_modes))
                       + (tuple(f"{itf}_{c}" for itf in self.interface_names
                                for c in ("tx", "ty", "tz", "rx", "ry", "rz")) if reduction == "craig-bampton"
                          else tuple(f"static{k + 1}" for k in range(6 * len(self.interface_names))))
                       + tuple(f"{itf}_a{k + 1}" for itf in self.averaged_names for k in range(6))
                       + tuple(f"xi{k + 1}" for k in range(n_extra)))
        if len(self._names) != self.n_dofs:
            raise AssertionError(f"{len(self._names)} coordinate names for {self.n_dofs} coordinates: the basis "
                                 f"dropped a dependent vector it should have kept")
        self.set_initial_state(position, orientation, velocity, angular_velocity, None, None)

    # ---------------------------------------------------------------- reduction
    @staticmethod
    def _reduce(solid, sets, n_modes, reduction):
        """(Φ on the mesh DOFs, the kept modes' frequencies, (T, n_solve, LU of the stiffness on the first
        n_solve tied DOFs)) of the Craig–Bampton or the free-interface reduction (class docstring)."""
        rigid = [nodes for name, nodes in sets.items() if name != "frame"]
        T, n_free = solid.tie(sets["frame"], rigid)
        nb = 6 * len(rigid)
        n_solve = n_free if reduction == "craig-bampton" else n_free + nb
        n_modes = int(n_modes) if not isinstance(n_modes, bool) and int(n_modes) == n_modes else -1
        if not 1 <= n_modes < n_solve - 1:
            raise ValueError(f"n_modes must be an integer in [1, {n_solve - 2}] for this mesh and these "
                             f"interfaces, got {n_modes!r}")
        Kw = (T.T @ solid.stiffness @ T).tocsc()
        Mw = (T.T @ solid.mass @ T).tocsc()
        K, M = Kw[:n_solve, :n_solve], Mw[:n_solve, :n_solve]
        # one factorization: the shift-invert eigensolve, the constraint modes and every load later
        lu = spd_factor(K)
        lam, vec = lowest_modes(K, M, n_modes, lu)
        if reduction == "craig-bampton":
            blocks = [np.vstack([vec, np.zeros((nb, n_modes))])]
            if nb:
                blocks.append(np.vstack([-lu.solve(Kw[:n_free, n_free:].toarray()), np.eye(nb)]))
            Phi = T @ np.hstack(blocks)
        else:
            # residual attachment modes: K⁻¹E − Φ Λ⁻¹ Φᵀ E (Φ M-normalized by eigsh), E the interface DOFs;
            # M-orthogonal to the kept modes up to the eigensolver's tolerance (ΦᵀMK⁻¹ = Λ⁻¹Φᵀ): the
            # complement removes that and conditions the block
            E = np.zeros((n_solve, nb))
            E[n_free:] = np.eye(nb)
            residual = lu.solve(E) - vec @ (vec[n_free:].T / lam[:, None])
            Phi = T @ vec
            if nb:
                Phi = np.hstack([Phi, m_complement(T @ residual, Phi, solid.mass)])
        return Phi, np.sqrt(np.maximum(lam, 0.0)), (T, n_solve, lu)

    @staticmethod
    def _attachment_modes(solid, tie, dofs, P):
        """The six static responses to unit loads spread over an averaged set, Pᵀe_k (the rigid interfaces held
        for Craig–Bampton, free for the free-interface reduction: the factorization's DOFs)."""
        T, n_solve, lu = tie
        loads = np.zeros((solid.n_dofs, 6))
        loads[dofs] = P.T
        return T[:, :n_solve] @ lu.solve(np.asarray((T.T @ loads)[:n_solve]))

    @staticmethod
    def _stiffening_vectors(solid, tie, modes, origin, spins, kept):
        """The static responses (on the factorization's DOFs, as :meth:`_attachment_modes`) to the stiffening loads
        (``solid_strain.stiffening_loads``),
        made M-orthogonal to the ``kept`` basis and to each other; the ones already spanned dropped."""
        T, n_solve, lu = tie
        loads = stiffening_loads(solid, modes, origin, pairs=modes.shape[1] > 0, spins=spins)
        if loads.shape[1] == 0:
            return np.zeros((solid.n_dofs, 0))
        size = np.abs(loads).max(axis=0)
        # modes bending in different planes do not couple: their third derivative is round-off
        loads = loads[:, size > 1e-8 * size.max()]
        w = -lu.solve(np.asarray((T.T @ loads)[:n_solve]))
        return m_complement(T[:, :n_solve] @ w, kept, solid.mass)

    @staticmethod
    def _invariants(solid, Phi, X0):
        Ms = solid.scalar_mass
        ones = np.ones(X0.shape[0])
        Phis = [Phi[solid.component_dofs[k]] for k in range(3)]          # (n_nodes, m) each
        MsX = Ms @ X0
        MsPhi = [Ms @ P for P in Phis]
        m = Phi.shape[1]
        N = np.zeros((3, 3, m, m))
        P = np.zeros((3, 3, m))
        for i in range(3):
            for k in range(3):
                N[i, k] = Phis[i].T @ MsPhi[k]
                P[i, k] = X0[:, i] @ MsPhi[k]
        return SpatialFrameInertia(mass=float(ones @ (Ms @ ones)), S0=ones @ MsX,
                                   Sbar=np.array([ones @ MsPhi[k] for k in range(3)]), I0=X0.T @ MsX, P=P, N=N)

    def frequency_errors(self, n=None):
        """How well the basis carries the body's vibration: its lowest ``n`` natural frequencies (the frame set
        clamped, the rest as reduced) against the full mesh's with the frame set clamped and the rigid interfaces
        free (rigid), averaged sets free.

        Parameters
        ----------
        n : int, optional
            How many (default: ``n_modes``).

        Returns
        -------
        FrequencyCheck
            ``reduced``, ``full`` (rad/s) and the relative ``error`` of each.
        """
        n = self.n_modes if n is None else n
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= self.n_elastic:
            raise ValueError(f"n must be in [1, {self.n_elastic}] (the elastic coordinates), got {n!r}")
        M = np.einsum("kkab->ab", self.inertia.N)          # ΦᵀMΦ = Σ_k Φ_kᵀ M_s Φ_k, from the invariants
        reduced = np.sqrt(np.maximum(scipy.linalg.eigh(self.reduced_stiffness, M, eigvals_only=True,
                                                       subset_by_index=(0, n - 1)), 0.0))
        full = self.solid.natural_frequencies(n, self._sets["frame"], [self._sets[k] for k in self.interface_names])
        return FrequencyCheck(reduced, full, reduced / full - 1.0)

    # ---------------------------------------------------------------- state and points
    @property
    def coordinate_names(self):
        return self._names

    def displacement_field(self, q):
        """The elastic displacement of every node in the frame's axes, (n_nodes, 3), m."""
        u = self.basis @ np.asarray(q, dtype=float)[12:]
        return np.stack([u[self.solid.component_dofs[k]] for k in range(3)], axis=1)

    def point(self, locator="frame"):
        """A point of the body: an interface by name (``"frame"``: the frame's own point, affine in q with the
        frame's orientation, so spatial joints take it; another interface: its centre, moving with its three
        translation DOFs), or the mesh node nearest to a position (3,) given in the mesh's axes."""
        if isinstance(locator, str):
            if locator == "frame":
                return SpatialPoint(self, self.centres["frame"])
            if locator in self.averaged_names:
                dofs, P = self._averages[locator]
                return ElasticPoint(self, self.centres[locator], P[:3] @ self.basis[dofs])
            if locator not in self.interface_names:
                raise ValueError(f"body {self.name!r} has no interface {locator!r}; it has "
                                 f"{['frame', *self.interface_names, *self.averaged_names]}")
            motion = self._interface_motion[locator]
            return ElasticPoint(self, self.centres[locator], motion[:3], Theta=motion[3:6])
        X = check_finite_vector("point", locator, 3)
        node = int(np.argmin(np.sum((self.solid.node_positions - X) ** 2, axis=1)))
        S = np.stack([self.basis[self.solid.component_dofs[k, node]] for k in range(3)])
        return ElasticPoint(self, self.solid.node_positions[node] - self.origin, S)

    def mesh_shapes(self, vectors):
        """Columns on η as columns on the mesh's displacement DOFs (Φ · columns)."""
        return self.basis @ np.asarray(vectors)

    def motion_rows(self, axis):
        """The mesh DOFs of the displacement along frame axis ``axis`` (0, 1, 2) at every node."""
        return self.solid.component_dofs[int(axis)]

    def stresses(self, q):
        """Cell stresses (n_cells, 6) = (σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy) in the frame's axes, Pa."""
        return self._stress_modes @ np.asarray(q, dtype=float)[12:]

    def geometry(self, q, v):
        """The mesh's vertices moved (x + D(X₀ + u)) with their displacement from the initial state and velocity;
        per cell the stresses and von Mises."""
        x, D, _ = kinetics.split(q)
        vx, V, _ = kinetics.split(v)
        nv = self.solid.mesh.p.shape[1]
        X0 = self.solid.node_positions[:nv] - self.origin
        u = self.displacement_field(q)[:nv]
        du = self.displacement_field(v)[:nv]
        pts = x + (X0 + u) @ D.T
        x0, D0, _ = kinetics.split(self.q0)
        ref = x0 + (X0 + self.displacement_field(self.q0)[:nv]) @ D0.T
        vel = vx + (X0 + u) @ V.T + du @ D.T
        sigma = self.stresses(q)
        t = self.solid.mesh.t
        # scikit-fem numbers a hexahedron's corners in its own order; VTK's is this permutation of it
        cells = ("tetra", t.T.copy()) if t.shape[0] == 4 else ("hexahedron", t[list(_HEX_TO_VTK)].T.copy())
        return BodyGeometry(pts, [cells], {"displacement": pts - ref, "velocity": vel},
                            {"stress": [sigma], "von_mises": [von_mises_3d(sigma)]})
