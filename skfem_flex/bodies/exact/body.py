r"""Geometrically exact planar beam (Simo–Reissner) in absolute coordinates: the body.

:class:`ExactBeam` carries, at every node of the scikit-fem mesh of a
:class:`~skfem_flex.fem.beam.TimoshenkoBeam`, the position r = (x, y) of the
beam axis in the global (inertial) frame and the angle φ of the
cross-section (Simo & Vu-Quoc 1986; Lee & Yun, eq. 6); there is no
floating frame. They are stored as the global displacement u = r − X(s) from
the straight reference placement X(s) and the section rotation ψ = φ − α
from the reference angle α, so that round-off scales with the motion, not
with the distance from the origin (see the class notes). The kinetic energy

.. math::

    T = ½ \int ρA (\dot x² + \dot y²) + ρI \dot φ² \, ds

makes the mass matrix the constant consistent mass of the linear beam
(u_x, u_y, ψ play the roles of u, w, θ), assembled once by scikit-fem.

This module holds the body contract, the axis points (:class:`BeamPoint`), static
equilibrium under load stepping (:meth:`ExactBeam.solve_static`) and the output cells. The
strain measures, the strain energy and its energy-conserving (equivariant) discrete gradient,
with their theory and references, are in :mod:`skfem_flex.bodies.exact.strain`; their compiled
counterparts in :mod:`skfem_flex.bodies.exact.kernel`. Loads on the beam are force elements
(:mod:`skfem_flex.elements.forces.exact_beam_loads`: ``NodalLoad``, ``ExactDistributedLoad``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ...errors import ConvergenceError
from ...fem.beam import TimoshenkoBeam, line_mesh
from ...fem.section import Section
from ...numerics.newton import NewtonSettings, newton_solve
from ..base import (DENSE_LIMIT, Body, BodyGeometry, BodyPoint, StrainPointsPotential, check_finite_number,
                    check_finite_vector, to_dense)
from .strain import ElementInversionError, StrainPoints

__all__ = ["ExactBeam", "BeamPoint"]


class ExactBeam(StrainPointsPotential, Body):
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
    Strains and the energy-conserving discrete gradient: see
    :mod:`skfem_flex.bodies.exact.strain` (:attr:`strain_points`). The strain kernels are vectorised over elements on arrays
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
    #: the compiled family of its strain energy (:mod:`skfem_flex.compiled.families.exact_beam`)
    strain_family = "exact beam"

    def __init__(self, beam, start=(0.0, 0.0), angle=0.0, q0=None, v0=None, name="exact_beam",
                 rotation_rate="cayley"):
        if not isinstance(beam, TimoshenkoBeam):
            raise ValueError(f"beam must be a skfem_flex TimoshenkoBeam, got {beam!r}")
        self.beam = beam
        self.section = beam.section
        self.name = str(name)
        self.start = check_finite_vector("start", start, 2)
        self.angle = check_finite_number("angle", angle)
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
        names = [""] * n
        for i, (a, b, c) in enumerate(self.node_dofs):
            names[a], names[b], names[c] = f"ux{i}", f"uy{i}", f"psi{i}"
        self._names = tuple(names)

        #: the strain points (reduced rule) and the strain energy on them: :class:`.strain.StrainPoints`
        self.strain_points = StrainPoints(beam, self.angle, self.dense, self.name)
        self.ed = self.strain_points.ed                        # (n_el, 3k) node-major (x, y, φ)
        self.n_elements, self.k = self.strain_points.n_elements, self.strain_points.k

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
        kin = self.strain_points.kinematics(self.q0, check=False)
        bad = np.nonzero(kin["stretch"] <= 0.0)
        if bad[0].size:
            e = int(bad[0][0])
            sp = self.strain_points
            raise ValueError(f"initial state q0 of {self.name!r} folds element {e} "
                             f"(s in [{sp.element_lo[e]:.6g}, {sp.element_hi[e]:.6g}] m): "
                             f"stretch 1 + ε = {kin['stretch'][bad][0]:.3g} <= 0")


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


    # ------------------------------------------------------------- strains
    def strains(self, q):
        """(ε, γ, κ) at the strain points, each of shape (n_elements, n_points)."""
        return self.strain_points.strains(q)

    def section_forces(self, q):
        """Axial force N = EA ε (N), shear force Q = kGA γ (N), bending moment M = EI κ (N m).

        At the strain points, each of shape (n_elements, n_points).
        """
        eps, gam, kap = self.strains(q)
        return self.EA * eps, self.kGA * gam, self.EI * kap

    # ------------------------------------------------------------- potential
    def potential_discrete_gradient(self, q0, q1):
        """Equivariant discrete gradient: stress at the mean strain, strain increments in Cayley rates.

        Returns (g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0) to round-off
        (:meth:`.strain.StrainPoints.discrete_gradient`).

        Raises
        ------
        ElementInversionError
            If q1 folds an element.
        ConvergenceError
            If a nodal rotation increment abs(Δψ) reaches π (no Cayley parameter).
        """
        return self.strain_points.discrete_gradient(q0, q1)

    def compiled_strain_data(self):
        """The packed arrays of the compiled strain-energy kernels (:mod:`.kernel`), built once.

        An :class:`~skfem_flex.bodies.exact.kernel.ExactKernelData` (element DOF map, shape functions
        and weights at the strain points, EA, kGA, EI, reference direction and angle, the tangent's
        CSR pattern). The exact-beam family (:mod:`skfem_flex.compiled.families.exact_beam`) takes a
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
        s = check_finite_number("s", s)
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
        return pt.jr.T @ f + check_finite_number("moment", moment) * pt.jphi

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
            sp = self.strain_points
            self._seg_element = np.array([int(np.nonzero((sp.element_lo <= m) & (m <= sp.element_hi))[0][0])
                                          for m in mid])
        kin = self.strain_points.kinematics(q, check=False)
        W = self.strain_points.W
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

