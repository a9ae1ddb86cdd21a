r"""Linear planar Timoshenko beam on a scikit-fem line mesh.

:class:`TimoshenkoBeam` turns a :class:`skfem.MeshLine` and a
:class:`~skfem_flex.fem.section.Section` into scikit-fem bases, the constant
stiffness and consistent mass matrices, load vectors, static solutions and
natural modes. Fields: axial displacement u, transverse deflection w and
cross-section rotation θ, shear strain γ = w' − θ.

Stiffness follows eq. (42) of Liu & Yun, not eq. (41). Eq. (40) writes
the strain energy as ½ EA ∫ u'² dx + …, = ½ q_fᵀ K q_f, so every block of K is
the energy density's coefficient integrated without a further ½; eq. (41)
keeps a stray ½ on its axial block (halving the axial stiffness) while its
own assembled element matrix, eq. (42), has the correct EA/l. Eq. (42) is the
fully integrated P1 element; ``shear="reduced"`` (the default) integrates the
shear term with one Gauss point per P1 element instead, which replaces its
l²kGA/3 and l²kGA/6 entries by l²kGA/4 and removes shear locking.

Loads follow eq. (43): distributed axial f and transverse p are integrated
against the shape functions, point forces h (axial), Q (transverse) and a
point moment M act through the shape functions evaluated at their point.
"""
from __future__ import annotations

import numbers
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg
import skfem
from skfem import Basis, ElementLineP1, ElementLineP2, asm, condense, solve

from . import forms
from ..numerics.resources import BYTES_PER_ELEMENT, check_fits
from .section import Section

__all__ = ["TimoshenkoBeam", "LinearBeamAnalyses", "ElementQuadrature", "gauss_line", "line_mesh"]

# Fields of the composite element, in scikit-fem's node-major DOF order.
FIELDS = ("u", "w", "theta")


def gauss_line(n_points):
    """Gauss–Legendre rule on scikit-fem's reference line [0, 1].

    scikit-fem's own rules give at least two points on lines (``intorder``
    0–3 all give two), so a one-point rule has to be built by hand.

    Parameters
    ----------
    n_points : int
        Number of points; exact for polynomials of degree 2·n_points − 1.

    Returns
    -------
    tuple of ndarray
        Points of shape (1, n_points) and weights of shape (n_points,)
        summing to 1, as accepted by ``Basis(..., quadrature=...)``.
    """
    xi, weights = np.polynomial.legendre.leggauss(n_points)
    return np.array([(xi + 1.0) / 2.0]), weights / 2.0


@dataclass(frozen=True)
class ElementQuadrature:
    """Quadrature-point data of one scalar field, for vectorised element kernels.

    Local shape functions are ordered as the rows of
    :attr:`TimoshenkoBeam.element_dofs` group them: local node ``mesh.t[0]``,
    ``mesh.t[1]`` and, for P2, the element midpoint. The values of a field at
    the quadrature points are ``np.einsum("ie,iek->ek", q[dofs].T, N)`` with
    ``dofs = beam.element_dofs[:, field::3]``.

    Attributes
    ----------
    x : ndarray, shape (n_elements, n_points)
        Coordinates of the quadrature points in m.
    dx : ndarray, shape (n_elements, n_points)
        Integration weights in m (Gauss weight times element length), so that
        ∫ g dx = ``(g * dx).sum()``.
    N : ndarray, shape (n_local, n_elements, n_points)
        Shape function values (dimensionless).
    dNdx : ndarray, shape (n_local, n_elements, n_points)
        Shape function derivatives d/dx in 1/m.
    """

    x: np.ndarray
    dx: np.ndarray
    N: np.ndarray
    dNdx: np.ndarray

    @classmethod
    def from_basis(cls, basis):
        """Read the arrays off a scalar scikit-fem ``CellBasis``."""
        return cls(
            x=np.array(basis.global_coordinates()[0]),
            dx=np.array(basis.dx),
            N=np.array([np.asarray(phi[0]) for phi in basis.basis]),
            dNdx=np.array([phi[0].grad[0] for phi in basis.basis]),
        )


def _coordinate(x, what):
    """Return ``x`` as a finite float or raise ``ValueError`` naming it."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise ValueError(f"{what}: x must be a real number, got {x!r}")
    if not np.isfinite(x):
        raise ValueError(f"{what}: x must be finite, got {x!r}")
    return float(x)


def check_mesh(mesh):
    """Raise ``ValueError`` unless ``mesh`` is a straight beam: a single chain of
    positive-length elements along x."""
    if not isinstance(mesh, skfem.MeshLine1):
        raise ValueError(f"mesh must be a skfem.MeshLine, got {type(mesh).__name__}")
    if mesh.p.shape[0] != 1:
        raise ValueError(
            "mesh points must be 1-D (coordinates of shape (1, n_points)), "
            f"got shape {mesh.p.shape}"
        )
    x = mesh.p[0]
    if not np.all(np.isfinite(x)):
        raise ValueError(f"mesh point coordinates must be finite, got {x}")
    if mesh.t.shape[1] < 1:
        raise ValueError(f"mesh has no elements ({x.size} point(s)); a beam needs at least one")
    x_sorted = np.sort(x)
    # Relative tolerance: points closer than this would give an element
    # with a (near) singular Jacobian.
    tol = 1e-12 * max(x_sorted[-1] - x_sorted[0], np.abs(x_sorted).max(), 1e-300)
    duplicates = x_sorted[1:][np.diff(x_sorted) <= tol]
    if duplicates.size:
        raise ValueError(
            f"mesh has duplicate points (zero-length elements) at x = {np.unique(duplicates)}"
        )
    # A straight beam is a chain: n + 1 points, elements sorted along x share
    # their inner points, none overlap and no point is left unused.
    lo = np.argmin(x[mesh.t], axis=0)
    left = mesh.t[lo, np.arange(mesh.t.shape[1])]
    right = mesh.t[1 - lo, np.arange(mesh.t.shape[1])]
    by_x = np.argsort(x[left])
    is_chain = x.size == mesh.t.shape[1] + 1 and np.array_equal(
        right[by_x][:-1], left[by_x][1:]
    )
    if not is_chain:
        raise ValueError(
            "mesh is not a single chain of elements from x = "
            f"{x_sorted[0]} to {x_sorted[-1]} (duplicate or overlapping elements, "
            "gaps or unused points)"
        )


#: longest beam :func:`line_mesh` builds, m
MAX_LENGTH = 1e12


def line_mesh(length, n_elements, order=1):
    """A uniform :class:`skfem.MeshLine` of ``n_elements`` on [0, length] (m).

    Checks first that a beam of that many elements fits in the memory available
    (:func:`skfem_flex.numerics.resources.check_fits`), so that a request of 10⁸ elements is
    refused at once instead of allocating its mesh.
    """
    if isinstance(n_elements, bool) or int(n_elements) != n_elements or n_elements < 1:
        raise ValueError(f"n_elements must be a positive integer, got {n_elements!r}")
    n = int(n_elements)
    length = float(length)
    if not np.isfinite(length) or length <= 0 or length > MAX_LENGTH:
        raise ValueError(f"length must be positive and at most {MAX_LENGTH:g} m (the inertia integrals ∫ρA x² dx "
                         f"overflow far beyond), got {length!r}")
    check_fits(BYTES_PER_ELEMENT * order * n, f"a beam of {n} elements (order {order})")
    return skfem.MeshLine(np.linspace(0.0, float(length), n + 1))


class LinearBeamAnalyses:
    """The analyses every linear beam shares: the DOFs of a node, statics K q = F and the modes K φ = ω² M φ.

    A subclass provides ``stiffness()``, ``mass()``, ``n_dofs``, ``length``, ``x_nodes`` (ascending node
    coordinates, m) and ``node_dofs`` (the DOFs of those nodes, one row each).
    """

    def dofs_at(self, x):
        """Global DOFs of the node at x (every field of the node, in field order).

        Parameters
        ----------
        x : float
            Node coordinate in m (P2 midpoints are nodes too).

        Returns
        -------
        ndarray of int, shape (n_fields,)

        Raises
        ------
        ValueError
            If no node lies at x (within 1e-9 of the beam length).
        """
        x = _coordinate(x, "dofs_at")
        nearest = int(np.argmin(np.abs(self.x_nodes - x)))
        if abs(self.x_nodes[nearest] - x) > 1e-9 * self.length:
            raise ValueError(f"no node at x = {x!r}; the nearest is at x = {self.x_nodes[nearest]}")
        return self.node_dofs[nearest].copy()

    def _fixed(self, fixed):
        fixed = np.unique(np.asarray(fixed, dtype=np.int64).ravel())
        if fixed.size and (fixed[0] < 0 or fixed[-1] >= self.n_dofs):
            raise ValueError(f"fixed DOFs must lie in [0, {self.n_dofs}), got {fixed}")
        return fixed

    # ------------------------------------------------------------------
    # analyses

    def solve_static(self, load, fixed):
        """Static displacements K q = F with the DOFs ``fixed`` held at zero.

        Parameters
        ----------
        load : array_like, shape (n_dofs,)
            Load vector, e.g. from :meth:`load`.
        fixed : array_like of int
            Global DOFs held at zero, e.g. ``beam.dofs_at(0.0)`` for a clamp.

        Returns
        -------
        ndarray, shape (n_dofs,)
            q with the fields of every node, in m and rad.

        Raises
        ------
        ValueError
            If the load is malformed or the supports leave a rigid-body mode
            (singular stiffness).
        """
        load = np.asarray(load, dtype=float)
        if load.shape != (self.n_dofs,) or not np.all(np.isfinite(load)):
            raise ValueError(
                f"load must be a finite vector of length {self.n_dofs}, got shape {load.shape}"
            )
        fixed = self._fixed(fixed)
        with warnings.catch_warnings():
            warnings.simplefilter("error", scipy.sparse.linalg.MatrixRankWarning)
            try:
                q = solve(*condense(self.stiffness(), load, D=fixed))
            except (scipy.sparse.linalg.MatrixRankWarning, RuntimeError):
                q = None
        if q is None or not np.all(np.isfinite(q)):
            raise ValueError(
                f"stiffness is singular with fixed DOFs {fixed}: the supports leave "
                "a rigid-body motion free"
            )
        return q

    def modes(self, fixed, n_modes=6, sigma=0.0):
        """Natural angular frequencies and mode shapes, K φ = ω² M φ.

        Solved with ``scipy.sparse.linalg.eigsh`` in shift-invert mode about
        ``sigma`` (the lowest modes for sigma = 0); tiny systems, where ARPACK
        cannot return that many modes, use a dense solver.

        Parameters
        ----------
        fixed : array_like of int
            Global DOFs held at zero.
        n_modes : int, optional
            Number of modes, lowest first.
        sigma : float, optional
            Shift in rad²/s². Unsupported (free) beams have a singular K; pass
            a small negative shift for them.

        Returns
        -------
        omega : ndarray, shape (n_modes,)
            Natural angular frequencies in rad/s, ascending.
        shapes : ndarray, shape (n_dofs, n_modes)
            Mode shapes, zero at the fixed DOFs, normalised to φᵀ M φ = 1
            (units 1/√kg) with their largest entry positive.
        """
        fixed = self._fixed(fixed)
        free = np.setdiff1d(np.arange(self.n_dofs), fixed)
        if isinstance(n_modes, bool) or int(n_modes) != n_modes or not 1 <= n_modes <= free.size:
            raise ValueError(f"n_modes must be an integer in [1, {free.size}], got {n_modes!r}")
        n_modes = int(n_modes)
        K = self.stiffness()[free][:, free]
        M = self.mass()[free][:, free]
        if n_modes < free.size - 1:
            try:
                eigenvalues, vectors = scipy.sparse.linalg.eigsh(
                    K.tocsc(), k=n_modes, M=M.tocsc(), sigma=sigma, which="LM"
                )
            except RuntimeError as err:
                raise ValueError(
                    f"K - sigma M is singular (sigma = {sigma}, fixed DOFs {fixed}); "
                    "free beams need a small negative sigma"
                ) from err
        else:
            eigenvalues, vectors = scipy.linalg.eigh(K.toarray(), M.toarray())
        by_value = np.argsort(eigenvalues)[:n_modes]
        # rigid-body modes come out as tiny negative numbers, not as NaN
        omega = np.sqrt(np.clip(eigenvalues[by_value], 0.0, None))
        shapes = np.zeros((self.n_dofs, n_modes))
        shapes[free] = vectors[:, by_value]
        shapes /= np.sqrt(np.einsum("ik,ik->k", shapes, self.mass() @ shapes))
        largest = np.argmax(np.abs(shapes), axis=0)
        shapes *= np.sign(shapes[largest, np.arange(n_modes)])
        return omega, shapes


class TimoshenkoBeam(LinearBeamAnalyses):
    r"""Linear Timoshenko beam: scikit-fem bases, K, M, loads, statics, modes.

    Weak form (eq. 40 of Liu & Yun; γ = w' − θ):

    .. math::

        \int_0^l EA\,u'δu' + EI\,θ'δθ' + kGA\,(w' − θ)(δw' − δθ)\,dx
        = \int_0^l f\,δu + p\,δw\,dx + h\,δu(x_h) + Q\,δw(x_Q) + M\,δθ(x_M).

    The stiffness reproduces eq. (42) of the paper (full integration, P1),
    not eq. (41), whose axial block carries a stray factor ½: the ½ of the
    strain energy ½ qᵀKq is already the ½ of eq. (40), so K_axial = EA ∫
    N₁'ᵀN₁' dx, which is what eq. (42) contains (EI/l · A/I = EA/l).

    Parameters
    ----------
    mesh : skfem.MeshLine
        Straight beam along x: a single chain of at least one element with
        distinct points (coordinates in m).
    section : Section
        Cross-section properties.
    order : {1, 2}, optional
        Polynomial order of all three fields (P1 or P2 Lagrange).
    shear : {"reduced", "full"}, optional
        Quadrature of the shear term. ``"reduced"`` uses one Gauss point per
        P1 element (two per P2 element) and does not lock; ``"full"``
        integrates it exactly (two points for P1, three for P2), reproduces
        eq. (42) for P1 and locks for slender beams.

    Attributes
    ----------
    basis : skfem.CellBasis
        Basis over the composite element (u, w, θ) with a Gauss rule of
        ``order + 1`` points, exact for stiffness, mass and polynomial loads
        up to degree ``order + 1``.
    shear_basis : skfem.CellBasis
        Same element on the rule of the shear term (``basis`` itself when
        ``shear="full"``). Shares DOF numbering with ``basis``.
    field_basis : skfem.CellBasis
        Basis of one scalar field on the rule of ``basis``; its DOF j is DOF
        ``field_dofs[k][j]`` of field k in the composite numbering.
    field_dofs : ndarray, shape (3, n_nodes)
        Global DOFs of u, w and θ in the scalar numbering of ``field_basis``.
    n_dofs : int
        Number of global DOFs, 3 per node. At node i of a P1 mesh, u, w, θ are
        DOFs 3i, 3i + 1, 3i + 2.
    element_dofs : ndarray, shape (n_elements, 6) for P1, (n_elements, 9) for P2
        Global DOFs of each element, node-major (u, w, θ of local node
        ``mesh.t[0]``, then of ``mesh.t[1]``, then of the midpoint for P2).
    element_lengths : ndarray, shape (n_elements,)
        Element lengths in m.
    x_nodes : ndarray, shape (n_nodes,)
        Node coordinates in m, ascending (P2 midpoints included).
    node_dofs : ndarray, shape (n_nodes, 3)
        Global (u, w, θ) DOFs of the nodes in ``x_nodes``; ``q[beam.node_dofs]``
        gives the nodal fields along the beam.
    length : float
        Beam length in m.
    quadrature, shear_quadrature : ElementQuadrature
        Quadrature-point arrays (points, weights, shape functions and their
        derivatives) of the exact rule and the shear rule.

    Examples
    --------
    >>> import numpy as np, skfem
    >>> from skfem_flex.fem.section import Section
    >>> sec = Section.rectangle(E=210e9, nu=0.3, b=0.1, h=0.1, rho=7850)
    >>> beam = TimoshenkoBeam(skfem.MeshLine(np.linspace(0, 1, 17)), sec)
    >>> q = beam.solve_static(beam.load(Q=(1.0, -1e3)), fixed=beam.dofs_at(0.0))
    >>> tip_deflection = q[beam.dofs_at(1.0)[1]]
    """

    def __init__(self, mesh, section, order=1, shear="reduced"):
        check_mesh(mesh)
        if not isinstance(section, Section):
            raise ValueError(f"section must be a skfem_flex Section, got {section!r}")
        if isinstance(order, bool) or order not in (1, 2):
            raise ValueError(f"order must be 1 or 2, got {order!r}")
        if not isinstance(shear, str) or shear not in ("reduced", "full"):
            raise ValueError(f"shear must be 'reduced' or 'full', got {shear!r}")
        n_el = mesh.t.shape[1]
        check_fits(BYTES_PER_ELEMENT * order * n_el, f"a beam of {n_el} elements (order {order})")
        self.mesh = mesh
        self.section = section
        self.order = int(order)
        self.shear = shear

        scalar = ElementLineP1() if self.order == 1 else ElementLineP2()
        self.element = scalar * scalar * scalar
        # The composite has maxdeg 3 so scikit-fem's default rule would be
        # chosen for the product; set every rule explicitly instead.
        exact = gauss_line(self.order + 1)
        reduced = gauss_line(self.order)
        self.basis = Basis(mesh, self.element, quadrature=exact)
        self.shear_basis = (
            self.basis if shear == "full" else Basis(mesh, self.element, quadrature=reduced)
        )
        self.field_basis = Basis(mesh, scalar, quadrature=exact)
        self.field_dofs = np.array(self.basis.split_indices())
        self.n_dofs = self.basis.N

        self.element_dofs = np.ascontiguousarray(self.basis.element_dofs.T)
        self.element_lengths = np.abs(np.diff(mesh.p[0, mesh.t], axis=0))[0]
        x_field = self.field_basis.doflocs[0]
        by_x = np.argsort(x_field, kind="stable")
        self.x_nodes = x_field[by_x]
        self.node_dofs = np.ascontiguousarray(self.field_dofs[:, by_x].T)
        self.length = float(self.x_nodes[-1] - self.x_nodes[0])

        self.quadrature = ElementQuadrature.from_basis(self.field_basis)
        self.shear_quadrature = (
            self.quadrature
            if shear == "full"
            else ElementQuadrature.from_basis(Basis(mesh, scalar, quadrature=reduced))
        )
        self._stiffness = None
        self._mass = None

    # ------------------------------------------------------------------
    # constant operators (assembled once, then cached)

    def stiffness(self):
        """Linear stiffness matrix K (axial + bending + shear), eq. (42).

        Axial and bending are integrated exactly; shear on the reduced rule
        unless ``shear="full"``. Assembled on the first call and cached: the
        same matrix object is returned every time, do not modify it in place.

        Returns
        -------
        scipy.sparse.csr_matrix, shape (n_dofs, n_dofs)
            Entries in N/m (force/displacement), N (force/rotation,
            moment/displacement) and N·m (moment/rotation).
        """
        if self._stiffness is None:
            s = self.section
            K = (
                asm(forms.axial, self.basis, EA=s.EA)
                + asm(forms.bending, self.basis, EI=s.EI)
                + asm(forms.shear, self.shear_basis, kGA=s.kGA)
            )
            self._stiffness = K.tocsr()
        return self._stiffness

    def mass(self):
        """Consistent mass matrix M: ∫ ρA (u δu + w δw) + ρI θ δθ dx.

        Integrated exactly. Assembled on the first call and cached (the same
        object is returned every time, do not modify it in place).

        Returns
        -------
        scipy.sparse.csr_matrix, shape (n_dofs, n_dofs)
            Entries in kg (translation) and kg·m² (rotation).
        """
        if self._mass is None:
            s = self.section
            M = asm(forms.translational_mass, self.basis, rhoA=s.rhoA) + asm(
                forms.rotary_mass, self.basis, rhoI=s.rhoI
            )
            self._mass = M.tocsr()
        return self._mass

    # ------------------------------------------------------------------
    # loads, eq. (43)

    def _point_x(self, x, what):
        """Validate a point coordinate and bring it inside the mesh."""
        x = _coordinate(x, what)
        x_min, x_max = self.x_nodes[0], self.x_nodes[-1]
        tol = 1e-9 * self.length
        if not x_min - tol <= x <= x_max + tol:
            raise ValueError(f"{what}: x = {x!r} lies outside the beam [{x_min}, {x_max}]")
        # scikit-fem's element finder rejects points a rounding error outside
        return float(np.clip(x, x_min, x_max))

    def point_load(self, x, h=0.0, Q=0.0, M=0.0):
        """Load vector of point forces and a point moment at x (eq. 43).

        The load enters through the shape functions at x: a point between
        nodes is shared by the element's nodes as the shape functions share
        it (linearly for P1), ``h N(x)``, ``Q N(x)``, ``M N(x)``.

        Parameters
        ----------
        x : float
            Point of application in m, on the beam.
        h : float, optional
            Axial point force in N.
        Q : float, optional
            Transverse point force in N.
        M : float, optional
            Point moment in N·m (positive in the sense of θ).

        Returns
        -------
        ndarray, shape (n_dofs,)
        """
        x = self._point_x(x, "point load")
        values = [float(v) for v in (h, Q, M)]
        if not np.all(np.isfinite(values)):
            raise ValueError(f"point load at x = {x} must be finite, got h, Q, M = {values}")
        shape_at_x = self.field_basis.probes(np.array([[x]])).tocsr()
        vector = np.zeros(self.n_dofs)
        for field, value in enumerate(values):
            np.add.at(vector, self.field_dofs[field][shape_at_x.indices], value * shape_at_x.data)
        return vector

    @staticmethod
    def point_pairs(name, spec):
        """Read None, one (x, value) pair or a sequence of pairs."""
        if spec is None:
            return np.zeros((0, 2))
        try:
            pairs = np.asarray(spec, dtype=float)
        except (TypeError, ValueError):
            pairs = None
        if pairs is not None and pairs.shape == (2,):
            pairs = pairs[None, :]
        if pairs is None or pairs.ndim != 2 or pairs.shape[1] != 2:
            raise ValueError(
                f"{name} must be an (x, value) pair or a sequence of such pairs, got {spec!r}"
            )
        return pairs

    def load(self, f=None, p=None, h=None, Q=None, M=None):
        """Generalised load vector of eq. (43).

        Build it once and scale it in time loops: distributed loads call
        ``asm``.

        Parameters
        ----------
        f : float or callable, optional
            Distributed axial load in N/m, constant or a function of x (m)
            taking and returning arrays.
        p : float or callable, optional
            Distributed transverse load in N/m, constant or a function of x.
        h, Q, M : (x, value) or sequence of (x, value), optional
            Axial point forces (N), transverse point forces (N) and point
            moments (N·m) at coordinates x (m) anywhere on the beam.

        Returns
        -------
        ndarray, shape (n_dofs,)

        Examples
        --------
        >>> F = beam.load(p=-1e3, Q=[(0.5, 200.0), (1.0, -50.0)])  # doctest: +SKIP
        """
        vector = np.zeros(self.n_dofs)
        if f is not None:
            vector += asm(forms.axial_load(f), self.basis)
        if p is not None:
            vector += asm(forms.transverse_load(p), self.basis)
        for name, spec in (("h", h), ("Q", Q), ("M", M)):
            for x, value in self.point_pairs(name, spec):
                vector += self.point_load(x, **{name: value})
        return vector

    # ------------------------------------------------------------------
    # DOFs

