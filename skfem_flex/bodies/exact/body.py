r"""Geometrically exact planar beam (Simo–Reissner) in absolute coordinates.

:class:`ExactBeam` carries, at every node of the scikit-fem mesh of a
:class:`~skfem_flex.fem.beam.TimoshenkoBeam`, the position r = (x, y) of the
beam axis in the global (inertial) frame and the angle φ of the
cross-section (Simo & Vu-Quoc 1986; Lee & Yun, eq. 6); there is no
floating frame. They are stored as the global displacement u = r − X(s) from
the straight reference placement X(s) and the section rotation ψ = φ − α
from the reference angle α, so that round-off scales with the motion, not
with the distance from the origin (see the class notes). With ' = d/ds along
the reference arc length s (the mesh coordinate) and t = (cos φ, sin φ),
n = (−sin φ, cos φ) the section's tangent and normal, the strain measures are

.. math::

    ε = t · r' − 1 = x' \cos φ + y' \sin φ − 1, \qquad
    γ = n · r' = −x' \sin φ + y' \cos φ, \qquad
    κ = φ',

zero in the straight, stress-free reference configuration (placed anywhere,
at any angle), and invariant under rigid motions. Strain and kinetic energy

.. math::

    V = ½ \int EA ε² + kGA γ² + EI κ² \, ds, \qquad
    T = ½ \int ρA (\dot x² + \dot y²) + ρI \dot φ² \, ds,

so the mass matrix is the constant consistent mass of the linear beam
(u_x, u_y, ψ play the roles of u, w, θ), assembled once by scikit-fem. The
strains are sampled on the reduced Gauss rule (one point per P1 element, two
per P2 element), which keeps slender beams free of shear and membrane
locking; for P1 the curvature is constant per element and exact.

Energy-conserving discrete gradient
-----------------------------------
Lee & Yun, eqs. (3b), (17)–(22): the section forces are taken at the
mean strain, f_m = C (e_0 + e_1)/2, and the strain increment is written
exactly through the incremental rotation. In the plane the incremental
rotation is one angle Δφ with Rodrigues/Cayley parameter w = W(Δφ) =
2 tan(Δφ/2) (:mod:`skfem_flex.numerics.rotations`); with \bar t = (t_0 + t_1)/2 and
\bar r' = (r_0' + r_1')/2,

.. math::

    t_1 − t_0 = w \, E \bar t, \qquad
    ε_1 − ε_0 = \bar t · Δr' + w_p \, (E \bar t · \bar r'), \qquad
    γ_1 − γ_0 = E \bar t · Δr' − w_p \, (\bar t · \bar r')

exactly at every strain point p (Simo, Tarnow & Doblaré 1995: \bar Λᵀ(Δr' −
w E \bar r')). The point's Cayley parameter w_p = W(Δφ_p), Δφ_p = Σ N_a Δφ_a,
and the curvature increment Δκ_p = Σ N_a' Δφ_a are written *exactly and
linearly* in the nodal parameters w_a = W(Δφ_a) by divided differences of W
about the element's first node a = 0 (W[x, y] = (W(x) − W(y))/(x − y) =
sinc((x − y)/2)/(cos(x/2) cos(y/2)), smooth at x = y):

.. math::

    w_p = w_0 + W[Δφ_0, Δφ_p] \sum_{a ≥ 1} \frac{N_a}{W[Δφ_0, Δφ_a]} (w_a − w_0),
    \qquad
    Δκ_p = \sum_{a ≥ 1} \frac{N_a'}{W[Δφ_0, Δφ_a]} (w_a − w_0).

The coefficients of w_a sum to 1 in w_p and to 0 in Δκ_p. The discrete
gradient D_w V = Σ_p W_p f_mᵀ ∂Δe_p/∂(Δr, w) is then (i) exact,
D_w V · (Δr, w) = V_1 − V_0, and (ii) *equivariant*: orthogonal to the
infinitesimal rotation ξ = (E \bar r_a, 1) at the mean configuration, because
a step (Δr_a, w_a) = c ξ leaves every strain unchanged (Δr' = c E \bar r'
and w_p = c turn r' and t alike). Only r' enters, so its force resultant
vanishes too.

The energy-momentum integrator takes w_a/Δt as the mean angular velocity of
the sections (the body declares its ψ coordinates as ``cayley_coordinates``)
and this discrete gradient for the force; with the constant mass matrix both
momenta then change only by external impulses, and energy by external work,
to the Newton tolerance (flying beam: 1e-14). The body hands the gradient
out conjugate to Δq (ψ rows times w/Δψ), so it is a valid exact discrete
gradient for any caller; :meth:`ExactBeam.potential_discrete_gradient`
differentiates it by complex steps.

With the plain mid-point rate Δφ/Δt (``rotation_rate="mid-point"``)
exact energy and exact angular momentum exclude each other: the step along
ξ(q_m) turns nodes by 2 atan(c/2) but sections by c and changes V. Then the
angular momentum changes per step by ΔL = −Δt D V · ξ(q_m) = O(Δt³), an
O(Δt²) drift (flying beam: 5e-4 relative at Δt = 0.1, 6e-6 at Δt = 0.01).

References
----------
J. C. Simo, L. Vu-Quoc, "On the dynamics of flexible beams under large
overall motions — the plane case", J. Appl. Mech. 53 (1986) 849–863.
J. C. Simo, N. Tarnow, M. Doblaré, "Non-linear dynamics of three-dimensional
rods: exact energy and momentum conserving algorithms", IJNME 38 (1995).
Lee & Yun, "The dynamics analysis for nonlinear flexible mechanisms using finite
elements and algebraic quaternions" (mean velocity, stress at the mean strain).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import Basis, ElementLineP1, ElementLineP2

from ...fem.beam import ElementQuadrature, TimoshenkoBeam, gauss_line, line_mesh
from ...elements.forces import ForceElement
from ...errors import ConvergenceError
from ...numerics.newton import NewtonSettings, newton_solve
from ...numerics.rotations import MAX_INCREMENT as _MAX_INCREMENT, cayley_divided_difference, cayley_ratio
from ...fem.section import Section
from ..base import Body, BodyGeometry, BodyPoint, check_finite_vector, keeps_methods, to_dense

__all__ = ["ExactBeam", "NodalLoad", "ExactDistributedLoad", "ElementInversionError"]

#: bodies with at most this many coordinates hand out dense matrices
DENSE_LIMIT = 400
_E = np.array([[0.0, -1.0], [1.0, 0.0]])
#: imaginary step of the complex-step tangent (any tiny value: no subtraction, no truncation error)
_COMPLEX_STEP = 1e-30


class ElementInversionError(ConvergenceError, ValueError):
    """A configuration in which an element of an :class:`ExactBeam` folds inside out (1 + ε ≤ 0).

    A :class:`~skfem_flex.schemes.integrators.ConvergenceError` (and a ``ValueError``):
    raised during a time step, ``simulate`` first retries the step in halves
    (a Newton iterate of a too-large step may fold transiently) and finally
    reports the time, the step and this message, which names the element.
    """


def _finite(name, value):
    try:
        val = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if isinstance(value, bool) or not np.isfinite(val):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    return val


class ExactBeam(Body):
    r"""Planar geometrically exact (Simo–Reissner) beam in absolute nodal coordinates.

    Parameters
    ----------
    beam : TimoshenkoBeam
        Mesh, section and element order (P1 or P2). The beam's DOFs become
        this body's coordinates: at every node the global displacement
        u_x, u_y (m) of the axis from its reference placement and the section
        rotation ψ (rad) from the reference angle take the places of u, w, θ.
        The mesh coordinate s (m) is the reference arc length.
    start : array_like, shape (2,)
        Global position (m) of the first mesh node (smallest s) in the
        straight, stress-free reference configuration.
    angle : float
        Direction of the reference axis (rad from the global x axis); the
        material point s sits at ``start + (s − s_min)(cos angle, sin angle)``
        with section angle ``angle``.
    q0 : array_like, optional
        Initial coordinates (default zero: the reference configuration); see
        :meth:`coordinates_from` to build them from positions and angles.
    v0 : array_like, optional
        Initial velocities ẋ, ẏ (m/s), φ̇ (rad/s) (default: rest).
    name : str
    rotation_rate : {"cayley", "mid-point"}
        Mean angular velocity of the sections in the energy-momentum scheme:
        ``"cayley"`` (default) 2 tan(Δψ/2)/Δt, which conserves angular
        momentum exactly together with energy; ``"mid-point"`` Δψ/Δt, which
        conserves energy exactly and angular momentum to O(Δt²) (kept for
        comparison). The other integrators do not use it.

    Notes
    -----
    Strains and the energy-conserving discrete gradient: see the module
    docstring. The strain kernels are vectorised over elements on arrays
    precomputed from scikit-fem bases; only the constant mass matrix is
    assembled (once). Coordinates are named ``ux{i}``, ``uy{i}``, ``psi{i}``
    for the i-th node along the beam (ascending s, P2 midpoints included);
    positions r = X + u and angles φ = α + ψ (:meth:`nodal_positions`,
    :meth:`nodal_angles`, :meth:`point`). Storing displacements rather than
    positions keeps the strains ε = (cos ψ − 1) + t·u', γ = −sin ψ + n·u'
    accurate to round-off *relative to the motion*: with positions ~10 m
    the strains would carry an absolute noise ~1e-15, i.e. forces of EA·1e-15,
    which a start from rest under a slowly prescribed motion (the spin-up
    manoeuvre) cannot get below the Newton tolerance.

    Raises
    ------
    ValueError
        For a ``beam`` that is not a TimoshenkoBeam, non-finite ``start``,
        ``angle``, ``q0`` or ``v0`` of the wrong length, or an initial state
        with a folded element (1 + ε ≤ 0).

    Examples
    --------
    >>> import numpy as np, skfem
    >>> sec = Section(EA=1e4, EI=100.0, kGA=1e4, rhoA=1.0, rhoI=10.0)
    >>> body = ExactBeam.from_points(sec, (6.0, 0.0), (0.0, 8.0), n_elements=10)
    >>> body.n_dofs
    33
    """

    constant_mass = True
    has_potential = True

    def __init__(self, beam, start=(0.0, 0.0), angle=0.0, q0=None, v0=None, name="exact_beam",
                 rotation_rate="cayley"):
        if not isinstance(beam, TimoshenkoBeam):
            raise ValueError(f"beam must be a skfem_flex TimoshenkoBeam, got {beam!r}")
        self.beam = beam
        self.section = beam.section
        self.name = str(name)
        self.start = check_finite_vector("start", start, 2)
        self.angle = _finite("angle", angle)
        n = self.n_dofs = int(beam.n_dofs)
        self.dense = n <= DENSE_LIMIT
        sec = beam.section
        self.EA, self.kGA, self.EI = sec.EA, sec.kGA, sec.EI

        # nodes along the beam and the reference configuration
        self.node_dofs = np.asarray(beam.node_dofs)             # (n_nodes, 3), ascending s
        self.s_nodes = np.asarray(beam.x_nodes, dtype=float)
        self.s_min, self.s_max = float(self.s_nodes[0]), float(self.s_nodes[-1])
        self.length = self.s_max - self.s_min
        self.direction = np.array([np.cos(self.angle), np.sin(self.angle)])
        #: reference positions X of the nodes along the beam, (n_nodes, 2)
        self.reference_positions = self.start + np.outer(self.s_nodes - self.s_min, self.direction)
        xref = np.zeros(n)
        xref[self.node_dofs[:, 0]] = self.reference_positions[:, 0]
        xref[self.node_dofs[:, 1]] = self.reference_positions[:, 1]
        self._x_ref = xref                     # reference positions in the x, y slots, zero in the ψ slots
        names = [""] * n
        for i, (a, b, c) in enumerate(self.node_dofs):
            names[a], names[b], names[c] = f"ux{i}", f"uy{i}", f"psi{i}"
        self._names = tuple(names)

        # element kernels: strains on the reduced rule (order points per element)
        scalar = ElementLineP1() if beam.order == 1 else ElementLineP2()
        quad = ElementQuadrature.from_basis(Basis(beam.mesh, scalar, quadrature=gauss_line(beam.order)))
        self.ed = np.asarray(beam.element_dofs)                # (n_el, 3k) node-major (x, y, φ)
        self.n_elements, nloc = self.ed.shape
        self.k = nloc // 3
        self._N = np.ascontiguousarray(np.transpose(quad.N, (1, 2, 0)))      # (n_el, n_p, k)
        self._dN = np.ascontiguousarray(np.transpose(quad.dNdx, (1, 2, 0)))
        self._W = np.asarray(quad.dx)                                        # (n_el, n_p), m
        self._s_points = np.asarray(quad.x)
        self._ex = self.ed[:, 0::3]
        self._ey = self.ed[:, 1::3]
        self._ep = self.ed[:, 2::3]
        el_s = beam.mesh.p[0, beam.mesh.t]
        self._el_lo, self._el_hi = el_s.min(axis=0), el_s.max(axis=0)

        # scatter patterns into a fixed structure
        rows = np.broadcast_to(self.ed[:, :, None], (self.n_elements, nloc, nloc)).ravel()
        cols = np.broadcast_to(self.ed[:, None, :], (self.n_elements, nloc, nloc)).ravel()
        keys = rows.astype(np.int64) * n + cols
        if self.dense:
            self._flat = keys
        else:
            uniq, inv = np.unique(keys, return_inverse=True)
            self._inv = inv
            self._csr_indices = (uniq % n).astype(np.int32)
            self._csr_indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
            self._nnz = uniq.size

        # constant operators, assembled once by scikit-fem
        mass = beam.mass().tocsr()
        self._mass = mass.toarray() if self.dense else mass
        ones_x = np.zeros(n)
        ones_x[self.node_dofs[:, 0]] = 1.0
        ones_y = np.zeros(n)
        ones_y[self.node_dofs[:, 1]] = 1.0
        gam = np.zeros((2, n))
        gam[0] = mass @ ones_x                     # ∫ ρA N_i ds on the x DOFs
        gam[1] = mass @ ones_y
        self._gamma = gam
        self._gamma_c = gam @ xref             # ∫ ρA X ds
        self.total_mass = float(gam[0].sum())

        if rotation_rate not in ("cayley", "mid-point"):
            raise ValueError(f"rotation_rate must be 'cayley' or 'mid-point', got {rotation_rate!r}")
        self.rotation_rate = rotation_rate
        self.cayley_coordinates = tuple(int(i) for i in self.node_dofs[:, 2]) if rotation_rate == "cayley" else ()
        self.q0 = np.zeros(n) if q0 is None else check_finite_vector("q0", q0, n)
        self.v0 = np.zeros(n) if v0 is None else check_finite_vector("v0", v0, n)
        kin = self._kinematics(self.q0, check=False)
        bad = np.nonzero(kin["stretch"] <= 0.0)
        if bad[0].size:
            e = int(bad[0][0])
            raise ValueError(f"initial state q0 of {self.name!r} folds element {e} "
                             f"(s in [{self._el_lo[e]:.6g}, {self._el_hi[e]:.6g}] m): "
                             f"stretch 1 + ε = {kin['stretch'][bad][0]:.3g} <= 0")
        self._cache_q = None
        self._cache_kin = None

    # -------------------------------------------------------------- builders
    @classmethod
    def from_points(cls, section, start, end, n_elements=10, order=1, name="exact_beam", **kwargs):
        """A straight beam from ``start`` to ``end`` (global points in m) on ``n_elements`` elements.

        Builds the mesh s ∈ [0, ‖end − start‖] and the TimoshenkoBeam; other
        keywords (q0, v0) go to the constructor.
        """
        if not isinstance(section, Section):
            raise ValueError(f"section must be a skfem_flex Section, got {section!r}")
        a = check_finite_vector("start", start, 2)
        b = check_finite_vector("end", end, 2)
        length = float(np.hypot(*(b - a)))
        if length <= 0.0:
            raise ValueError(f"start and end must differ, got {start!r} and {end!r}")
        if isinstance(n_elements, bool) or int(n_elements) != n_elements or int(n_elements) < 1:
            raise ValueError(f"n_elements must be a positive integer, got {n_elements!r}")
        mesh = line_mesh(length, n_elements, order if order in (1, 2) else 1)
        beam = TimoshenkoBeam(mesh, section, order=order)
        return cls(beam, a, float(np.arctan2(*(b - a)[::-1])), name=name, **kwargs)

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        return self._names

    def dofs_at(self, s):
        """Indices of (x, y, φ) of the node at reference coordinate ``s`` (m); ValueError if none."""
        return self.beam.dofs_at(s)

    def nodal_positions(self, q):
        """Positions r = X + u of the nodes along the beam, shape (n_nodes, 2), m."""
        return self.reference_positions + np.column_stack([q[self.node_dofs[:, 0]], q[self.node_dofs[:, 1]]])

    def nodal_angles(self, q):
        """Section angles φ = α + ψ of the nodes along the beam, rad."""
        return self.angle + np.asarray(q)[self.node_dofs[:, 2]]

    def coordinates_from(self, positions, angles):
        """Coordinates q of the configuration with nodal ``positions`` (n_nodes, 2) m and ``angles`` (rad).

        Nodes are ordered along the beam (ascending s), as :meth:`nodal_positions` returns them.
        """
        nn = self.node_dofs.shape[0]
        pos = np.asarray(positions, dtype=float)
        ang = np.asarray(angles, dtype=float)
        if pos.shape != (nn, 2) or ang.shape != (nn,) or not (np.all(np.isfinite(pos)) and np.all(np.isfinite(ang))):
            raise ValueError(f"positions must be a finite ({nn}, 2) array and angles a finite ({nn},) array, got "
                             f"shapes {pos.shape} and {ang.shape}")
        q = np.zeros(self.n_dofs)
        d = pos - self.reference_positions
        q[self.node_dofs[:, 0]], q[self.node_dofs[:, 1]] = d[:, 0], d[:, 1]
        q[self.node_dofs[:, 2]] = ang - self.angle
        return q

    def centre_of_mass(self, q):
        """∫ r dm / m, m."""
        return (self._gamma @ q + self._gamma_c) / self.total_mass

    # ------------------------------------------------------------- kinematics
    def _kinematics(self, q, check=True):
        """Strain-point values r', φ, φ', t, n and the strains ε, γ, κ."""
        q = np.asarray(q, dtype=float)
        U, V, P = q[self._ex], q[self._ey], q[self._ep]
        ux = np.einsum("ek,epk->ep", U, self._dN)
        uy = np.einsum("ek,epk->ep", V, self._dN)
        psi = np.einsum("ek,epk->ep", P, self._N)
        kap = np.einsum("ek,epk->ep", P, self._dN)
        phi = self.angle + psi
        c, s = np.cos(phi), np.sin(phi)
        # ε = t·r' − 1 and γ = n·r' with r' = e_α + u', written so that no O(1) terms cancel
        sh = np.sin(0.5 * psi)
        eps = -2.0 * sh * sh + c * ux + s * uy
        gam = -np.sin(psi) + (-s * ux + c * uy)
        kin = dict(rx=self.direction[0] + ux, ry=self.direction[1] + uy, psi=psi, c=c, s=s, stretch=1.0 + eps,
                   eps=eps, gam=gam, kap=kap)
        if check:
            self._check(kin)
        return kin

    def _check(self, kin):
        st = kin["stretch"]
        if not np.all(np.isfinite(st)):
            raise ElementInversionError(f"{self.name}: non-finite strain (the configuration escaped)")
        bad = np.nonzero(st <= 0.0)
        if bad[0].size:
            e = int(bad[0][0])
            raise ElementInversionError(
                f"{self.name}: element {e} (s in [{self._el_lo[e]:.6g}, {self._el_hi[e]:.6g}] m) folds inside "
                f"out: stretch 1 + ε = {st[bad][0]:.3g} <= 0 ({bad[0].size} strain point(s) reversed)")

    def _kin_cached(self, q):
        if self._cache_q is not None and np.array_equal(self._cache_q, q):
            return self._cache_kin
        kin = self._kinematics(q)
        self._cache_q, self._cache_kin = np.array(q, dtype=float), kin
        return kin

    def strains(self, q):
        """(ε, γ, κ) at the strain points, each of shape (n_elements, n_points)."""
        kin = self._kinematics(q, check=False)
        return kin["eps"], kin["gam"], kin["kap"]

    def section_forces(self, q):
        """Axial force N = EA ε (N), shear force Q = kGA γ (N), bending moment M = EI κ (N m).

        At the strain points, each of shape (n_elements, n_points).
        """
        eps, gam, kap = self.strains(q)
        return self.EA * eps, self.kGA * gam, self.EI * kap

    # ----------------------------------------------------- element assembly
    def _vec(self, crx, cry, cphi, cphip):
        """Element vectors of a linear form c_r · δr' + c_φ δφ + c_φ' δφ', shape (n_el, n_p, 3k)."""
        ne, npt, k = self._N.shape
        out = np.empty((ne, npt, k, 3))
        out[..., 0] = crx[..., None] * self._dN
        out[..., 1] = cry[..., None] * self._dN
        out[..., 2] = cphi[..., None] * self._N + cphip * self._dN
        return out.reshape(ne, npt, 3 * k)

    def _second(self, out, crphi_x, crphi_y, cphir_x, cphir_y, cphiphi):
        """Add Σ_p of the bilinear form δr'·c_rφ Δφ + δφ c_φr·Δr' + δφ c_φφ Δφ (weights included)."""
        N, dN = self._N, self._dN
        out[:, :, 0, :, 2] += np.einsum("ep,epa,epb->eab", crphi_x, dN, N)
        out[:, :, 1, :, 2] += np.einsum("ep,epa,epb->eab", crphi_y, dN, N)
        out[:, :, 2, :, 0] += np.einsum("ep,epa,epb->eab", cphir_x, N, dN)
        out[:, :, 2, :, 1] += np.einsum("ep,epa,epb->eab", cphir_y, N, dN)
        out[:, :, 2, :, 2] += np.einsum("ep,epa,epb->eab", cphiphi, N, N)

    def _scatter_vector(self, g_el):
        return np.bincount(self.ed.ravel(), weights=g_el.ravel(), minlength=self.n_dofs)

    def _scatter_matrix(self, k_el):
        n = self.n_dofs
        if self.dense:
            return np.bincount(self._flat, weights=k_el.ravel(), minlength=n * n).reshape(n, n)
        data = np.bincount(self._inv, weights=k_el.ravel(), minlength=self._nnz)
        return sps.csr_matrix((data, self._csr_indices, self._csr_indptr), shape=(n, n))

    def _grads(self, kin):
        """∇ε, ∇γ, ∇κ as element vectors at the strain points."""
        zero = np.zeros_like(kin["c"])
        b_eps = self._vec(kin["c"], kin["s"], kin["gam"], 0.0)
        b_gam = self._vec(-kin["s"], kin["c"], -kin["stretch"], 0.0)
        b_kap = self._vec(zero, zero, zero, 1.0)
        return b_eps, b_gam, b_kap

    # ------------------------------------------------------------- potential
    def potential_energy(self, q):
        """V = ½ ∫ EA ε² + kGA γ² + EI κ² ds, J."""
        kin = self._kin_cached(q)
        dens = self.EA * kin["eps"] ** 2 + self.kGA * kin["gam"] ** 2 + self.EI * kin["kap"] ** 2
        return 0.5 * float(np.sum(self._W * dens))

    def potential_gradient(self, q):
        kin = self._kin_cached(q)
        b_eps, b_gam, b_kap = self._grads(kin)
        W = self._W
        g_el = np.einsum("ep,epi->ei", W * self.EA * kin["eps"], b_eps)
        g_el += np.einsum("ep,epi->ei", W * self.kGA * kin["gam"], b_gam)
        g_el += np.einsum("ep,epi->ei", W * self.EI * kin["kap"], b_kap)
        return self._scatter_vector(g_el)

    def potential_hessian(self, q):
        kin = self._kin_cached(q)
        b_eps, b_gam, b_kap = self._grads(kin)
        W = self._W
        k_el = np.einsum("ep,epi,epj->eij", W * self.EA, b_eps, b_eps)
        k_el += np.einsum("ep,epi,epj->eij", W * self.kGA, b_gam, b_gam)
        k_el += np.einsum("ep,epi,epj->eij", W * self.EI, b_kap, b_kap)
        ne, k = self.n_elements, self.k
        k_el = k_el.reshape(ne, k, 3, k, 3)
        wn, wq = W * self.EA * kin["eps"], W * self.kGA * kin["gam"]
        c, s = kin["c"], kin["s"]
        # ∇²ε: δr'·n δφ twice, −(1 + ε) δφ²;  ∇²γ: −δr'·t δφ twice, −γ δφ²
        self._second(k_el, wn * -s - wq * c, wn * c - wq * s, wn * -s - wq * c, wn * c - wq * s,
                     -wn * kin["stretch"] - wq * kin["gam"])
        return self._scatter_matrix(k_el.reshape(ne, 3 * k, 3 * k))

    def _discrete_gradient_elements(self, ql0, ql1):
        """Element vectors of the discrete gradient, (n_el, batch, 3k), in Δq-space.

        ``ql0`` (n_el, 3k) and ``ql1`` (n_el, batch, 3k) are element coordinates
        (node-major x, y, ψ); ``ql1`` may be complex (complex-step tangent).
        See the module docstring for the equations.
        """
        N, dN, W = self._N, self._dN, self._W                   # (e, p, k), (e, p, k), (e, p)
        ql0 = ql0[:, None, :]

        def ends(ql):
            U, V, P = ql[..., 0::3], ql[..., 1::3], ql[..., 2::3]
            ux = np.einsum("ebk,epk->ebp", U, dN)
            uy = np.einsum("ebk,epk->ebp", V, dN)
            psi = np.einsum("ebk,epk->ebp", P, N)
            kap = np.einsum("ebk,epk->ebp", P, dN)
            phi = self.angle + psi
            c, s = np.cos(phi), np.sin(phi)
            sh = np.sin(0.5 * psi)
            eps = -2.0 * sh * sh + c * ux + s * uy
            gam = -np.sin(psi) + (-s * ux + c * uy)
            return ux, uy, c, s, eps, gam, kap, P

        ux0, uy0, c0, s0, eps0, gam0, kap0, P0 = ends(ql0)
        ux1, uy1, c1, s1, eps1, gam1, kap1, P1 = ends(ql1)
        wb = W[:, None, :]
        n_bar = wb * self.EA * 0.5 * (eps0 + eps1)
        q_bar = wb * self.kGA * 0.5 * (gam0 + gam1)
        m_bar = wb * self.EI * 0.5 * (kap0 + kap1)
        rbx = self.direction[0] + 0.5 * (ux0 + ux1)              # r̄'
        rby = self.direction[1] + 0.5 * (uy0 + uy1)
        tbx, tby = 0.5 * (c0 + c1), 0.5 * (s0 + s1)              # t̄ = mean section tangent at the point
        a = -tby * rbx + tbx * rby                               # r̄' · E t̄
        b = tbx * rbx + tby * rby                                # r̄' · t̄

        # nodal Cayley rates w_a = W(Δψ_a) → point rate w_p and curvature increment, exactly and linearly,
        # through divided differences about the element's first node (coefficients sum to 1 and to 0)
        X = P1 - P0                                              # (e, b, k)
        Xp = np.einsum("ebk,epk->ebp", X, N)
        dd_p = cayley_divided_difference(X[..., :1], Xp)         # (e, b, p)
        dd_a = cayley_divided_difference(X[..., :1], X[..., 1:])  # (e, b, k−1)
        beta = dd_p[..., None] * N[:, None, :, 1:] / dd_a[:, :, None, :]
        c_w = np.concatenate([1.0 - beta.sum(axis=-1, keepdims=True), beta], axis=-1)      # (e, b, p, k)
        k_w = dN[:, None, :, 1:] / dd_a[:, :, None, :]
        k_w = np.concatenate([-k_w.sum(axis=-1, keepdims=True), k_w], axis=-1)

        fx = np.einsum("ebp,epk->ebk", n_bar * tbx - q_bar * tby, dN)
        fy = np.einsum("ebp,epk->ebk", n_bar * tby + q_bar * tbx, dN)
        fw = (np.einsum("ebp,ebpk->ebk", n_bar * a - q_bar * b, c_w)
              + np.einsum("ebp,ebpk->ebk", m_bar, k_w))
        out = np.empty(ql1.shape, dtype=np.result_type(ql1, float))
        out[..., 0::3] = fx
        out[..., 1::3] = fy
        out[..., 2::3] = fw / cayley_ratio(X)                   # conjugate to w → conjugate to Δψ
        return out

    def potential_discrete_gradient(self, q0, q1):
        """Equivariant discrete gradient: stress at the mean strain, strain increments in Cayley rates.

        Returns (g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0) to round-off;
        its ψ rows are those of the Cayley-rate gradient times w/Δψ (module
        docstring), so that the integrator's scaling by Δψ/w recovers it.
        The tangent is the complex-step derivative of the element vectors
        (exact to round-off; the coefficients of the divided differences make
        a closed form long and error-prone).

        Raises
        ------
        ElementInversionError
            If q1 folds an element.
        ConvergenceError
            If a nodal rotation increment abs(Δψ) reaches π (no Cayley parameter).
        """
        self._kin_cached(q0)
        self._kinematics(q1)                                    # folded elements are reported here
        q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
        dpsi = np.abs(q1[self.node_dofs[:, 2]] - q0[self.node_dofs[:, 2]])
        if dpsi.size and dpsi.max() >= _MAX_INCREMENT:
            i = int(np.argmax(dpsi))
            raise ConvergenceError(f"{self.name}: the section at node {i} turns by {dpsi[i]:.3g} rad in one step; "
                                   f"the Cayley parameter 2 tan(Δψ/2) needs |Δψ| < π (take a smaller step)")
        ql0, ql1 = q0[self.ed], q1[self.ed]
        nloc = ql1.shape[1]
        h = _COMPLEX_STEP
        probe = ql1[:, None, :] + (1j * h) * np.eye(nloc)[None]
        g = self._discrete_gradient_elements(ql0, probe)        # (e, j, i): perturbation j, row i
        g_el = g[:, 0, :].real
        k_el = np.transpose(g.imag, (0, 2, 1)) / h
        return self._scatter_vector(g_el), self._scatter_matrix(k_el)

    def compiled_strain_data(self):
        """The packed arrays of the compiled strain-energy kernels (:mod:`.exact_kernel`), built once.

        An :class:`~skfem_flex.bodies.exact.kernel.ExactKernelData` (element DOF map, shape functions
        and weights at the strain points, EA, kGA, EI, reference direction and angle, the tangent's
        CSR pattern). The compiled mechanism loop (:mod:`skfem_flex.compiled.scene_loop`) takes a
        constant-mass body that provides it; the kernels do not depend on the rotation rate.
        """
        kd = getattr(self, "_kernel_data", None)
        if kd is None:
            from .kernel import pack
            kd = self._kernel_data = pack(self)
        return kd

    # --------------------------------------------------------------- kinetic
    def mass_matrix(self, q):
        """Constant consistent mass ∫ ρA (δx x + δy y) + ρI δφ φ ds (kg, kg m²)."""
        return self._mass

    def momentum(self, q, v):
        return self._mass @ v

    def mass_moment(self):
        """(Γ, c) with ∫ r dm = Γ q + c, c = ∫ ρA X ds (consistent gravity and centre of mass)."""
        return self._gamma.copy(), self._gamma_c.copy()

    def linear_momentum(self, q, v):
        """∫ ρA ṙ ds, kg m/s."""
        return self._gamma @ v

    def angular_momentum(self, q, v):
        """∫ ρA r × ṙ + ρI φ̇ ds about the global origin (consistent mass), kg m²/s."""
        p = self._mass @ v
        nd = self.node_dofs
        r = self.nodal_positions(q)
        return float(r[:, 0] @ p[nd[:, 1]] - r[:, 1] @ p[nd[:, 0]] + p[nd[:, 2]].sum())

    def momentum_layout(self):
        """(i_x, i_y, X, Y, i_angle): L = Σ (X + q[i_x]) p[i_y] − (Y + q[i_y]) p[i_x] + Σ p[i_angle] and
        linear momentum (Σ p[i_x], Σ p[i_y]) with p = M v (the nodes' positions and section angles;
        how the compiled loop records the momenta)."""
        nd = self.node_dofs
        return nd[:, 0].copy(), nd[:, 1].copy(), self.reference_positions[:, 0].copy(), \
            self.reference_positions[:, 1].copy(), nd[:, 2].copy()

    # ---------------------------------------------------------- body points
    def _shape_at(self, s):
        """(indices, values) of the scalar shape functions at reference coordinate s."""
        if isinstance(s, bool) or not np.isscalar(s):
            raise ValueError(f"a point of ExactBeam {self.name!r} is located by its reference coordinate s "
                             f"(a number in m), got {s!r}")
        s = _finite("s", s)
        tol = 1e-9 * self.length
        if not self.s_min - tol <= s <= self.s_max + tol:
            raise ValueError(f"s = {s!r} lies outside ExactBeam {self.name!r}, whose reference coordinate "
                             f"runs over [{self.s_min}, {self.s_max}] m")
        s = float(np.clip(s, self.s_min, self.s_max))
        probe = self.beam.field_basis.probes(np.array([[s]])).tocsr()
        return probe.indices, probe.data

    def point(self, locator=None):
        """The axis point at reference coordinate ``locator`` = s (m); position and angle interpolated.

        Both are affine in q (constant Jacobians): r = Σ N_a(s) r_a, ϑ = Σ N_a(s) φ_a.
        """
        if locator is None:
            raise ValueError(f"ExactBeam {self.name!r}: give the reference coordinate s (m) of the point")
        idx, val = self._shape_at(locator)
        fd = self.beam.field_dofs
        jr = np.zeros((2, self.n_dofs))
        jr[0, fd[0][idx]] = val
        jr[1, fd[1][idx]] = val
        jphi = np.zeros(self.n_dofs)
        jphi[fd[2][idx]] = val
        s = float(locator)
        x0 = self.start + (min(max(s, self.s_min), self.s_max) - self.s_min) * self.direction
        return BeamPoint(self, s, jr, jphi, x0, self.angle)

    def point_load_vector(self, s, force=(0.0, 0.0), moment=0.0):
        """Generalized force of a dead global force (N) and moment (N m) at the axis point s."""
        pt = self.point(s)
        f = check_finite_vector("force", force, 2)
        return pt.jr.T @ f + _finite("moment", moment) * pt.jphi

    # -------------------------------------------------------------- statics
    def solve_static(self, load, fixed, load_steps=10, q_start=None, tol=1e-10, max_iterations=40):
        """Static equilibrium ∇V(q) = λ F, λ = 1/load_steps, …, 1, by Newton with load stepping.

        Each load level is solved by the package's Newton core
        (:func:`~skfem_flex.numerics.newton.newton_solve`: its convergence test and its exits
        at round-off) with full Newton steps, from the equilibrium of the level before. A level
        Newton does not reach (no convergence, or an element folding inside out, which counts as
        a non-finite residual) is approached in halved load increments instead.

        Parameters
        ----------
        load : array_like (n_dofs,) or callable q -> (F, ∂F/∂q)
            Generalized load (dead, e.g. from :meth:`point_load_vector`) or a
            configuration-dependent one (follower loads); N and N m.
        fixed : array_like of int
            Coordinates held at their values in ``q_start`` (e.g. ``dofs_at(0)`` for a clamp).
        load_steps : int
            Load levels; a level Newton does not reach from the last equilibrium is approached in
            halved increments.
        q_start : array_like, optional
            Start (default ``q0``).
        tol : float
            Converged when ‖r‖∞ ≤ tol · max(‖λF‖∞, 1e-12 · max(EA, kGA, EI/L²) · L), r the residual
            ∇V(q) − λF on the free coordinates (N), or when the core's round-off exits end the
            iteration.
        max_iterations : int
            Newton iterations per load level.

        Returns
        -------
        ndarray
            The equilibrium coordinates.

        Raises
        ------
        ConvergenceError
            If Newton fails at a load level (the message names it).
        """
        q = self.q0.copy() if q_start is None else check_finite_vector("q_start", q_start, self.n_dofs)
        fixed = np.unique(np.asarray(fixed, dtype=int).ravel())
        free = np.setdiff1d(np.arange(self.n_dofs), fixed)
        if callable(load):
            load_fn = load
        else:
            vec = check_finite_vector("load", load, self.n_dofs)
            load_fn = lambda q_: (vec, None)  # noqa: E731
        steps = int(load_steps)
        if steps < 1:
            raise ValueError(f"load_steps must be >= 1, got {load_steps!r}")
        floor = 1e-12 * max(self.EA, self.kGA, self.EI / self.length ** 2) * self.length
        # full Newton steps, globalized by the load steps: the linear step of a section rotation
        # stretches the axis by about θ²/2, so the residual's norm first grows by orders of magnitude
        # before Newton converges quadratically; a line search on that norm would crawl
        settings = NewtonSettings(max_iterations=int(max_iterations), line_search=False)

        def level(lam):
            def fun(x):
                q_ = q.copy()
                q_[free] = x
                try:
                    f, fq = load_fn(q_)
                    r = (self.potential_gradient(q_) - lam * f)[free]
                    jac = self.potential_hessian(q_)
                except ElementInversionError:
                    return np.full(free.size, np.nan), None, np.nan
                if fq is not None:
                    jac = jac - lam * fq
                jac = sps.csr_matrix(jac)[free][:, free] if sps.issparse(jac) else jac[np.ix_(free, free)]
                scale = max(lam * float(np.max(np.abs(f))), floor)
                return r, jac, float(np.max(np.abs(r), initial=0.0)) / (tol * scale)
            return fun

        done = 0.0
        for i in range(1, steps + 1):
            target = i / steps
            lam = target
            while done < target:
                try:
                    # the coordinates are displacements from the reference placement: the length is
                    # the size of the positions they change
                    x, _, _ = newton_solve(level(lam), q[free], settings, f"{self.name}: static equilibrium",
                                           f"load level {lam:.4g}", x_scale=self.length)
                except ConvergenceError as exc:
                    # a load step too large for Newton from the last equilibrium (large rotations):
                    # halve it, down to 1/1024 of the step asked for
                    if lam - done <= 1.0 / (1024 * steps):
                        raise ConvergenceError(f"{exc} (load steps down to {lam - done:.3g} of the load)",
                                               **exc.info) from None
                    lam = done + 0.5 * (lam - done)
                    continue
                q[free] = x
                done, lam = lam, target
        return q

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        """Line cells through the nodes; point data displacement, velocity, angle; cell data section forces.

        Cell data are element means over the strain points: axial force N,
        shear force Q (N), bending moment M (N m) and strain energy density
        ½(EA ε² + kGA γ² + EI κ²) (J/m).
        """
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        pts = self.nodal_positions(q)
        vel = np.column_stack([v[self.node_dofs[:, 0]], v[self.node_dofs[:, 1]]])
        disp = pts - self.reference_positions
        n_nodes = pts.shape[0]
        cells = np.column_stack([np.arange(n_nodes - 1), np.arange(1, n_nodes)])
        if not hasattr(self, "_seg_element"):
            mid = 0.5 * (self.s_nodes[:-1] + self.s_nodes[1:])
            self._seg_element = np.array([int(np.nonzero((self._el_lo <= m) & (m <= self._el_hi))[0][0])
                                          for m in mid])
        kin = self._kinematics(q, check=False)
        W = self._W
        wsum = W.sum(axis=1)
        mean = lambda a: (W * a).sum(axis=1) / wsum  # noqa: E731
        sed = 0.5 * (self.EA * kin["eps"] ** 2 + self.kGA * kin["gam"] ** 2 + self.EI * kin["kap"] ** 2)
        seg = self._seg_element
        cell_data = {"axial_force": [mean(self.EA * kin["eps"])[seg]],
                     "shear_force": [mean(self.kGA * kin["gam"])[seg]],
                     "bending_moment": [mean(self.EI * kin["kap"])[seg]],
                     "strain_energy_density": [mean(sed)[seg]]}
        return BodyGeometry(pts, [("line", cells)],
                            {"displacement": disp, "velocity": vel, "angle": self.nodal_angles(q).copy()},
                            cell_data)


class BeamPoint(BodyPoint):
    """A point of an :class:`ExactBeam` axis: r = X(s) + J_r q and ϑ = α + J_φ · q, both affine in q."""

    has_angle = True

    def __init__(self, body, s, jr, jphi, reference_position, reference_angle):
        self.body, self.s, self.jr, self.jphi = body, s, jr, jphi
        self.reference_position = np.asarray(reference_position, dtype=float)
        self.reference_angle = float(reference_angle)

    def _zeros(self):
        n = self.body.n_dofs
        return np.zeros((n, n)) if self.body.dense else sps.csr_matrix((n, n))

    def position(self, q):
        return self.reference_position + self.jr @ q

    def position_jacobian(self, q):
        return self.jr

    def position_hessian_product(self, q, f):
        return self._zeros()

    def position_discrete_gradient(self, q0, q1):
        return self.jr

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return self._zeros()

    def velocity(self, q, v):
        return self.jr @ v

    def angle(self, q):
        return self.reference_angle + float(self.jphi @ q)

    def angle_jacobian(self, q):
        return self.jphi

    def compiled_map(self):
        return "linear", to_dense(self.jr), self.reference_position.copy()


def _time_function(fn):
    if fn is None:
        return None
    if not callable(fn):
        raise ValueError(f"time_function must be callable t -> factor, got {fn!r}")
    val = fn(0.0)
    if not np.isfinite(float(val)):
        raise ValueError(f"time_function(0) must be finite, got {val!r}")
    return fn


def _factor(fn, t):
    if fn is None:
        return 1.0
    val = float(fn(t))
    if not np.isfinite(val):
        raise ValueError(f"time_function({t!r}) is not finite: {val!r}")
    return val


class NodalLoad(ForceElement):
    """Point force and moment on an :class:`ExactBeam` axis point, dead or follower.

    Parameters
    ----------
    body : ExactBeam
    s : float
        Reference coordinate of the point (m); between nodes the load is
        shared by the shape functions.
    force : array_like, shape (2,)
        Force in N, global components (for a follower load: its components
        when the section has its reference angle).
    moment : float
        Moment in N m (counter-clockwise positive).
    time_function : callable t -> float, optional
        Dimensionless factor (default 1).
    follower : bool
        If True the force turns with the section: F(q) = A(ϑ(q) − ϑ_ref) F0,
        ϑ the section angle at the point, ϑ_ref its value in ``body.q0``.
    name : str

    Notes
    -----
    Non-conservative: the integrators evaluate it at the step midpoint (energy
    scheme) and record its work as external work. Generalized force
    f = c(t) (J_rᵀ F(q) + J_φ M), ∂f/∂q = c(t) J_rᵀ A E F0 ⊗ J_φ for a follower.
    """

    conservative = False

    def __init__(self, body, s, force=(0.0, 0.0), moment=0.0, time_function=None, follower=False,
                 name="nodal_load"):
        if not isinstance(body, ExactBeam):
            raise ValueError(f"NodalLoad acts on an ExactBeam, got {body!r}")
        self.bodies = (body,)
        self.body = body
        self.point = body.point(s)
        self.force = check_finite_vector("force", force, 2)
        self.moment = _finite("moment", moment)
        self.time_function = _time_function(time_function)
        self.follower = bool(follower)
        self.name = str(name)
        self.reference_angle = self.point.angle(body.q0)
        self._dead = self.point.jr.T @ self.force + self.moment * self.point.jphi

    def force_at(self, q, t):
        """Global force vector (N) at configuration q and time t."""
        c = _factor(self.time_function, t)
        if not self.follower:
            return c * self.force
        d = self.point.angle(q) - self.reference_angle
        cd, sd = np.cos(d), np.sin(d)
        return c * np.array([cd * self.force[0] - sd * self.force[1], sd * self.force[0] + cd * self.force[1]])

    def compiled_form(self):
        if self.follower or not keeps_methods(self, NodalLoad, ("generalized_force", "force_at")):
            return None
        base = np.array([self.force[0], self.force[1], self.moment])
        return ("generalized force", np.vstack([to_dense(self.point.jr), to_dense(self.point.jphi).reshape(1, -1)]),
                lambda t: _factor(self.time_function, t) * base)

    def generalized_force(self, q, v, t):
        c = _factor(self.time_function, t)
        if not self.follower or c == 0.0:
            return c * self._dead, None, None
        f_now = self.force_at(q, t)
        f = self.point.jr.T @ f_now + c * self.moment * self.point.jphi
        df = np.outer(self.point.jr.T @ (_E @ f_now), self.point.jphi)
        return f, df, None


class ExactDistributedLoad(ForceElement):
    """Dead distributed load (N/m of reference length) on an :class:`ExactBeam`, global components.

    Consistent load vector ∫ p · N ds assembled once by scikit-fem
    (:meth:`TimoshenkoBeam.load` with x ↔ u, y ↔ w), scaled by ``time_function``.

    Parameters
    ----------
    body : ExactBeam
    px, py : float or callable s -> value, optional
        Load per unit reference length along global x and y, N/m.
    time_function : callable t -> float, optional
    """

    conservative = False

    def __init__(self, body, px=None, py=None, time_function=None, name="distributed_load"):
        if not isinstance(body, ExactBeam):
            raise ValueError(f"ExactDistributedLoad acts on an ExactBeam, got {body!r}")
        for label, val in (("px", px), ("py", py)):
            if val is not None and not callable(val):
                _finite(label, val)
        self.bodies = (body,)
        self.vector = body.beam.load(f=px, p=py)
        self.time_function = _time_function(time_function)
        self.name = str(name)

    def generalized_force(self, q, v, t):
        return _factor(self.time_function, t) * self.vector, None, None

    def compiled_form(self):
        if not keeps_methods(self, ExactDistributedLoad, ("generalized_force",)):
            return None
        return "generalized force", np.asarray(self.vector, dtype=float).reshape(1, -1), \
            lambda t: np.array([_factor(self.time_function, t)])
