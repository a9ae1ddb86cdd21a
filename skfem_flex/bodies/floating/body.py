r"""Floating frame of reference (FFR): a Timoshenko beam in large overall motion.

A :class:`FloatingBeam` carries the coordinates of a body frame, q_r = (R_x, R_y, θ),
and elastic coordinates q_f of a :class:`~skfem_flex.fem.beam.TimoshenkoBeam` measured in that
frame. A material point of the axis at x is at (Liu & Yun, eqs. 10–11, 31–33)

.. math::

    r(x) = R + A(θ)\,(x_0 + S(x)\,q_f),\qquad x_0 = (x, 0),

where S(x) = [N_u; N_w] maps q_f to the axial and transverse displacement (u, w); the
cross-section turns by θ + N_φ(x) q_f. Reference conditions remove the rigid-body modes
from q_f: ``"clamped"`` eliminates u, w, φ at the root node (the frame is tangent to the
root), ``"pinned"`` eliminates u, w at the root and w at the tip (chord frame).

Kinetic energy T = ½ ∫ ρA |ṙ|² + ρI (θ̇ + φ̇)² dx = ½ q̇ᵀ M(q) q̇ (eqs. 14–17) with

.. math::

    M = \begin{bmatrix} m I & A E \bar s & A \bar S \\
                        \cdot & J(q_f) & a(q_f)^T \\
                        \cdot & \cdot & M_{ff} \end{bmatrix},\quad
    \begin{aligned}
    \bar s &= S_0 + \bar S q_f, &  J &= I_{00} + J_r + 2 c^T q_f + q_f^T M_A q_f,\\
    a &= k_0 + n_φ + H q_f, & M_{ff} &= M_A + M_I,
    \end{aligned}

E = [[0, −1], [1, 0]], built from inertia shape integrals that scikit-fem assembles once:
m = ∫ρA, S_0 = ∫ρA x_0, I_00 = ∫ρA x², S̄ = ∫ρA S, c = ∫ρA Sᵀx_0, k_0 = ∫ρA SᵀE x_0,
M_A = ∫ρA SᵀS, H = ∫ρA SᵀE S (skew), J_r = ∫ρI, n_φ = ∫ρI N_φ, M_I = ∫ρI N_φᵀN_φ.
Only the reference rows and columns depend on q; M_ff is constant.

Quadratic-velocity force (eq. 26, Q_v = ∂T/∂q − Ṁ q̇), with ω = θ̇, f = q̇_f and
c_m = c + M_A q_f::

    Q_R = A (ω² s̄ − 2 ω E S̄ f),   Q_θ = −2 ω c_m · f,   Q_f = ω² c_m − 2 ω H f

(centrifugal ω² c_m, Coriolis −2ωHf; no term depends on Ṙ).

Strain energy: bending EI κ², κ = φ', and shear kGA γ², γ = w' − φ, as in the linear beam
(constant matrices from scikit-fem); axial EA ε² with the Green–Lagrange strain
ε = u' + ½(u'² + w'²) (``strain="green-lagrange"``, default) or ε = u' (``strain="linear"``,
which misses the centrifugal stiffening). The nonlinear axial kernel is vectorised over
elements on the beam's precomputed quadrature arrays; nothing is assembled in the time loop.

Discrete gradients for the energy-conserving scheme (``docs/energy_scheme.md``) are
exact closed forms: stress at the mean strain for V, and for G(q) = ½ v₀ᵀ M(q) v₁ the identities
A(θ₁) − A(θ₀) = sinc(Δθ/2) A(θ_m) E Δθ and (A(θ₀) + A(θ₁))/2 = cos(Δθ/2) A(θ_m). Energy and
linear momentum are then conserved to round-off; angular momentum only to O(Δt²) (bounded, about
1e-6 relative at Δt = 1e-3 s): the frozen-velocity G is not invariant under rotations of the whole
system. The analytic tangents include the derivatives of sinc and cos.

Choice of frame: the clamped (root-tangent) frame has a stiff "frame turns, root counter-turns"
mode of little inertia; a free-flying body integrates with fewer Newton iterations and larger steps
in the chord frame (``reference="pinned"``).

This module holds the body contract; the pieces it is built from live beside it:

=================  ==========================================================================
``reference.py``   reference conditions → elastic coordinates q_f (free DOFs, names), K check
``inertia.py``     inertia integrals (scikit-fem forms → the ``BeamInertia`` invariants)
``strain.py``      stiffness K and the vectorised Green–Lagrange axial kernel, strains
``pattern.py``     the sparse CSR pattern, dense element scatter, compiled-kernel packing
``kernel.py``      the compiled (Numba) kinetic and strain arithmetic
``rotation.py``    centrifugal equilibrium and rotating-frame modes
``model.py``       the beam as an ``ElasticModel`` for reduction
=================  ==========================================================================

Loads on the beam are force elements (:class:`~skfem_flex.elements.forces.floating_beam_loads.DistributedLoad`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ...fem.beam import TimoshenkoBeam
from . import kernel as _kernel
from ..base import DENSE_LIMIT, BodyGeometry, check_finite_vector
from ..ffr import FloatingFrame, FramePoint
from .inertia import beam_inertia
from .model import beam_elastic_model
from .pattern import (compose_sparse, dense_scatter, kernel_data, scatter_elements,
                               sparse_pattern)
from .reference import FIELD_NAMES, check_stiffness, elastic_coordinates, restrict
from .rotation import centrifugal_equilibrium, rotating_modes
from .strain import (axial_derivatives, axial_element_tangent, axial_gradient, axial_quadrature,
                              elastic_stiffness, element_strain_energy, section_strains)
from ..rigid import E_MATRIX as E2, rotation as _rot
from ..probes import LinearProbe

__all__ = ["FloatingBeam"]


class FloatingBeam(FloatingFrame):
    """A Timoshenko beam in the floating frame of reference.

    Coordinates q = (R_x, R_y, θ, q_f), named ``"Rx", "Ry", "theta"`` and then
    ``"u1", "w1", "th1", ...`` (field and node number, nodes counted from the
    root along the beam) for the elastic DOFs left after the reference condition.

    Parameters
    ----------
    beam : TimoshenkoBeam
        Straight beam along the body x axis (its mesh coordinates are x).
    reference : {"clamped", "pinned"} or sequence of (x, field)
        Elastic DOFs eliminated to remove the rigid-body modes. ``"clamped"``:
        u, w, φ at the root (the node of smallest x); ``"pinned"``: u, w at the
        root and w at the tip. A sequence of (x, field) pairs, field in
        {"u", "w", "theta"}, gives them explicitly; it must remove exactly the
        three rigid modes.
    strain : {"green-lagrange", "linear"}
        Axial strain measure (see module docstring).
    position : array_like (2,)
        Initial R, m.
    angle : float
        Initial θ, rad.
    velocity : array_like (2,)
        Initial Ṙ, m/s.
    angular_velocity : float
        Initial θ̇, rad/s.
    elastic, elastic_velocity : array_like, optional
        Initial q_f and q̇_f (length ``n_elastic``; see :meth:`elastic_vector`).
    name : str
    sparse : bool, optional
        Matrix format; default: sparse when the body has more than
        :data:`~skfem_flex.bodies.base.DENSE_LIMIT` coordinates.

    Raises
    ------
    ValueError
        On a reference condition that leaves rigid modes (singular elastic
        stiffness) or over-constrains the beam, an unknown strain measure, or
        non-finite / wrongly sized initial data.
    """

    constant_mass = False
    has_potential = True

    def __init__(self, beam, reference="clamped", strain="green-lagrange", position=(0.0, 0.0), angle=0.0,
                 velocity=(0.0, 0.0), angular_velocity=0.0, elastic=None, elastic_velocity=None, name="beam",
                 sparse=None):
        if not isinstance(beam, TimoshenkoBeam):
            raise ValueError(f"FloatingBeam needs a TimoshenkoBeam, got {beam!r}")
        if strain not in ("green-lagrange", "linear"):
            raise ValueError(f"strain must be 'green-lagrange' or 'linear', got {strain!r}")
        self.beam, self.strain, self.name = beam, strain, name
        self.section = beam.section
        self.reference = reference
        self.x_min, self.x_max = float(beam.x_nodes[0]), float(beam.x_nodes[-1])

        # ------------------------------------------------ reference condition -> elastic coordinates
        coords = elastic_coordinates(beam, reference)
        self.free_dofs, self.fixed_dofs = coords.free_dofs, coords.fixed_dofs
        free = self.free_dofs
        self.n_elastic = nf = free.size
        self.n_dofs = n = 3 + nf
        self.sparse = (n > DENSE_LIMIT) if sparse is None else bool(sparse)
        self._names = ("Rx", "Ry", "theta") + coords.names

        # ------------------------------------------------ inertia, stiffness, axial kernel (assembled once)
        inertia = beam_inertia(beam, free, self.sparse)
        self.set_invariants(mass=inertia.mass, S0=inertia.S0, I0=inertia.I0, Sbar=inertia.Sbar, c=inertia.c,
                             k0n=inertia.k0n, MA=inertia.MA, H=inertia.H, Mff=inertia.Mff)
        self._pcache = (None, None)                       # ((q, v) bytes, M(q) v) of the last momentum

        K = elastic_stiffness(beam, free, strain)
        self._K = K if self.sparse else K.toarray()
        check_stiffness(beam, restrict(beam.stiffness(), free))   # the whole linear K, whatever the strain
        self._ax = axial_quadrature(beam, free, self.sparse)
        self._gl_cache = {}
        # ------------------------------------------------ matrix layout and compiled-kernel data
        blocks = dict(MA=self.invariants.MA, H=self.invariants.H, Mff=self.invariants.Mff, K=self._K)
        # the compiled kernels work on the sparse pattern for dense bodies too: the elastic block is a
        # band, and the full n × n pattern made them touch 4× the entries (flexible pendulum, 16 el.)
        self._pattern = sparse_pattern(n, nf, blocks, self._ax.loc)
        if not self.sparse:
            self.elastic_blocks = blocks
            self._scatter = dense_scatter(self._ax.loc, nf)
            self._pattern_rows = np.repeat(np.arange(n), np.diff(self._pattern.indptr))
        self._kd = kernel_data(n, nf, strain == "green-lagrange", inertia, blocks, self._pattern, self._ax.dNt,
                               self._ax.loc, self._ax.wq)

        # ------------------------------------------------ initial state
        qf0 = np.zeros(nf) if elastic is None else check_finite_vector("elastic", elastic, nf)
        vf0 = np.zeros(nf) if elastic_velocity is None else check_finite_vector("elastic_velocity",
                                                                                elastic_velocity, nf)
        pos = check_finite_vector("position", position, 2)
        vel = check_finite_vector("velocity", velocity, 2)
        ang = check_finite_vector("angle", angle, 1)
        om = check_finite_vector("angular_velocity", angular_velocity, 1)
        self.q0 = np.concatenate([pos, ang, qf0])
        self.v0 = np.concatenate([vel, om, vf0])

    # ================================================================ coordinates
    @property
    def coordinate_names(self):
        return self._names

    #: elastic coordinates beyond this many beam lengths (m, or rad for section rotations) are no small
    #: deformation of the floating frame any more: the run has diverged (the run's guard reads
    #: :meth:`divergence_bounds` at every recorded state)
    ELASTIC_BOUND = 10.0

    def divergence_bounds(self):
        """Largest sane absolute value of each coordinate: none for the frame (R, θ; the run's global rule holds), and
        :attr:`ELASTIC_BOUND` × max(L, 1 m) for the elastic coordinates, L the beam's length (m)."""
        bound = self.ELASTIC_BOUND * max(self.x_max - self.x_min, 1.0)
        return np.concatenate([np.full(3, np.inf), np.full(self.n_elastic, bound)])

    def elastic_vector(self, u=None, w=None, theta=None):
        """q_f from nodal fields: callables of x (m) or arrays over ``beam.x_nodes``.

        Raises ``ValueError`` if a value at an eliminated DOF is not zero.
        """
        full = np.zeros(self.beam.n_dofs)
        x = self.beam.x_nodes
        for k, fld in enumerate((u, w, theta)):
            if fld is None:
                continue
            vals = np.asarray(fld(x) if callable(fld) else fld, dtype=float)
            vals = np.broadcast_to(vals, x.shape)
            if not np.all(np.isfinite(vals)):
                raise ValueError(f"elastic field {FIELD_NAMES[k]} is not finite")
            full[self.beam.node_dofs[:, k]] = vals
        bad = np.abs(full[self.fixed_dofs])
        if bad.size and bad.max() > 1e-12 * max(1.0, np.abs(full).max()):
            raise ValueError(f"elastic fields are not zero at the DOFs the reference condition "
                             f"{self.reference!r} eliminates: {full[self.fixed_dofs]}")
        return full[self.free_dofs].copy()

    def full_elastic(self, q):
        """Beam DOF vector (u, w, φ per node, scikit-fem numbering) of the body coordinates q."""
        d = np.zeros(self.beam.n_dofs)
        d[self.free_dofs] = q[3:]
        return d

    def nodal_fields(self, q):
        """(x, u, w, φ) at the nodes along the beam, in the body frame (m, m, m, rad)."""
        d = self.full_elastic(q)
        nd = self.beam.node_dofs
        return self.beam.x_nodes.copy(), d[nd[:, 0]], d[nd[:, 1]], d[nd[:, 2]]

    # ================================================================ matrix composition
    def compose_matrix(self, top, left, terms=(), extra=None, loc=None):
        """n × n matrix from its reference rows ``top`` (3, n), the block ``left`` (nf, 3) below
        them and an elastic block Σ coef · X[key] for ``terms`` = [(coef, key)], key in
        {"MA", "H", "Mff", "K"}, plus ``extra`` (dense (nf, nf), dense bodies) or ``loc``
        (element matrices of the axial kernel, sparse bodies). ``top``/``left`` None mean zero.

        Sparse bodies fill their one fixed CSR pattern (:func:`.floating_pattern.compose_sparse`)."""
        if not self.sparse:
            return super().compose_matrix(top, left, terms, extra)
        return compose_sparse(self._pattern, top, left, terms, loc)

    def _axial_tangent(self, w, a, b, weps):
        """Σ_k w_k dε_k(a)ᵀ dε_k(b) + Σ_k weps_k d²ε_k, d²ε = D_uᵀD_u + D_wᵀD_w, for the strain states
        a = (u', w') and b, as the keyword :meth:`compose_matrix` takes: ``extra`` (the elements scattered
        into the dense elastic block) or ``loc`` (the element matrices, sparse bodies)."""
        out = axial_element_tangent(self._ax, w, a, b, weps)
        if not self.sparse:
            return dict(extra=scatter_elements(self._scatter, out))
        return dict(loc=out)

    def compiled_kernel_data(self):
        """The packed arrays of the compiled kernels (:mod:`.floating_kernel`), built once at construction
        (:func:`.floating_pattern.kernel_data`)."""
        return self._kd

    # ================================================================ kinetic
    def momentum(self, q, v):
        """p = M(q) v (compiled kernel :func:`.floating_kernel.momentum`; cached for the last (q, v))."""
        q, v = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float)
        key = (q.tobytes(), v.tobytes())
        if self._pcache[0] != key:
            self._pcache = (key, _kernel.momentum(self._kd, q, v))
        return self._pcache[1].copy()

    def kinetic_energy(self, q, v):
        return 0.5 * float(v @ self.momentum(q, v))

    # ================================================================ strain energy
    def _gl(self, qf):
        """(u', w', ε) at the quadrature points; two-entry cache (q0 is reused through a step)."""
        key = qf.tobytes()
        hit = self._gl_cache.get(key)
        if hit is not None:
            return hit
        up, wp = axial_derivatives(self._ax, qf)
        val = (up, wp, up + 0.5 * (up * up + wp * wp))
        if len(self._gl_cache) >= 2:
            self._gl_cache.pop(next(iter(self._gl_cache)))
        self._gl_cache[key] = val
        return val

    def potential_energy(self, q):
        """Strain energy V(q_f) = ½ q_fᵀ K q_f + ½ Σ EA dx ε², J (compiled kernel)."""
        return float(_kernel.potential_energy(self._kd, np.ascontiguousarray(q, dtype=float)))

    def potential_gradient(self, q):
        qf = q[3:]
        g = np.zeros(self.n_dofs)
        g[3:] = self._K @ qf
        if self.strain == "green-lagrange":
            up, wp, eps = self._gl(qf)
            g[3:] += axial_gradient(self._ax, up, wp, self._ax.wq * eps)
        return g

    def potential_hessian(self, q):
        qf = q[3:]
        if self.strain == "linear":
            return self.compose_matrix(None, None, [(1.0, "K")])
        up, wp, eps = self._gl(qf)
        wq = self._ax.wq
        return self.compose_matrix(None, None, [(1.0, "K")], **self._axial_tangent(wq, (up, wp), (up, wp), wq * eps))

    def potential_discrete_gradient(self, q0, q1):
        """Stress at the mean strain: g · (q1 − q0) = V(q1) − V(q0) exactly; with ∂g/∂q1.

        Axial part (ε quadratic in q_f, so ε(q1) − ε(q0) = dε(q_m)·Δq exactly)::

            g = Σ_k EA dx ½(ε_k(q0) + ε_k(q1)) dε_k(q_m)
            ∂g/∂q1 = ½ Σ_k EA dx [dε_k(q_m)ᵀ dε_k(q1) + ½(ε_k(q0) + ε_k(q1)) d²ε_k]
        """
        qm = 0.5 * (q0[3:] + q1[3:])
        g = np.zeros(self.n_dofs)
        g[3:] = self._K @ qm
        if self.strain == "linear":
            return g, self.compose_matrix(None, None, [(0.5, "K")])
        up0, wp0, e0 = self._gl(q0[3:])
        up1, wp1, e1 = self._gl(q1[3:])
        upm, wpm = 0.5 * (up0 + up1), 0.5 * (wp0 + wp1)
        wq = self._ax.wq
        t = wq * (0.5 * (e0 + e1))
        g[3:] += axial_gradient(self._ax, upm, wpm, t)
        return g, self.compose_matrix(None, None, [(0.5, "K")], **self._axial_tangent(0.5 * wq, (upm, wpm),
                                                                                (up1, wp1), 0.5 * t))

    def energy_momentum_terms(self, q0, q1, v0, v1, dt):
        """Everything one Newton evaluation of the energy-momentum scheme needs, in one call.

        Optional fused form of the body contract (the scene uses it when present): the same
        numbers as :meth:`momentum`, :meth:`mass_matrix`, :meth:`momentum_jacobian`,
        :meth:`kinetic_discrete_gradient` and :meth:`potential_discrete_gradient` (to round-off).
        Computed by the compiled kernel :func:`.floating_kernel.energy_momentum_terms`; the
        contract methods, in numpy, are its reference (tests/test_floating_kernel.py).

        Returns
        -------
        p1 : ndarray (n,)
            M(q1) v1.
        g_kin, g_pot : ndarray (n,)
            Discrete gradients of G(q) = ½ v0ᵀ M(q) v1 and of the strain energy V.
        jac : ndarray or csr_matrix (n, n)
            (2/Δt) M(q1) + B(q1, v1) − Δt ∂g_kin/∂q1 − 2 ∂g_kin/∂v1 + Δt ∂g_pot/∂q1
            (dense for dense bodies, CSR in the body's fixed pattern for sparse ones).
        floor : ndarray (n,)
            Δt ‖∂g_pot/∂q1‖ (‖q0‖ + ‖q1‖): round-off floor of the internal forces.
        """
        n = self.n_dofs
        q0, q1, v0, v1 = (np.ascontiguousarray(x, dtype=float) for x in (q0, q1, v0, v1))
        p, gk, gp, data, floor = _kernel.energy_momentum_terms(self._kd, q0, q1, v0, v1, float(dt))
        self._pcache = ((q1.tobytes(), v1.tobytes()), p.copy())
        if self.sparse:
            jac = sps.csr_matrix((data, self._pattern.indices, self._pattern.indptr), shape=(n, n))
        else:
            jac = np.zeros((n, n))
            jac[self._pattern_rows, self._pattern.indices] = data
        return p, gk, gp, jac, floor

    def strains(self, q):
        """Axial strain ε and force N (exact rule), curvature κ and moment M (exact rule), shear strain
        γ and force (shear rule), each of shape (n_elements, n_points)."""
        return section_strains(self._ax, self.section, self.full_elastic(q), self.strain == "green-lagrange")

    def element_strain_energy(self, q):
        """Strain energy of each element, J (sums to :meth:`potential_energy`)."""
        return element_strain_energy(self._ax, self.section, self.strains(q))

    # ================================================================ points, probes, output
    def axial_coordinate(self, x, what="point"):
        """``x`` (m) as a float on the beam; ValueError (naming ``what``) if not finite or off the beam."""
        if isinstance(x, bool) or not np.isscalar(x) or not np.isfinite(x):
            raise ValueError(f"{what}: axial coordinate x must be a finite number, got {x!r}")
        tol = 1e-9 * self.beam.length
        if not self.x_min - tol <= x <= self.x_max + tol:
            raise ValueError(f"{what}: x = {x!r} lies outside beam {self.name!r} [{self.x_min}, {self.x_max}]")
        return float(np.clip(x, self.x_min, self.x_max))

    def full_shape_at(self, x):
        """(u, w, φ) at axial coordinate x per beam DOF, (3, beam.n_dofs)."""
        x = self.axial_coordinate(x)
        beam = self.beam
        pr = beam.field_basis.probes(np.array([[x]])).tocsr()
        S = np.zeros((3, beam.n_dofs))
        for k in range(3):
            S[k, beam.field_dofs[k][pr.indices]] = pr.data
        return S

    def shape_at(self, x):
        """(S(x) (2, n_elastic), N_φ(x) (n_elastic,)) at axial coordinate x (m)."""
        S = self.full_shape_at(x)[:, self.free_dofs]
        return S[:2].copy(), S[2].copy()

    def point(self, locator=None):
        """The material point of the axis at x = ``locator`` (m; default the tip)."""
        x = self.x_max if locator is None else locator
        x = self.axial_coordinate(x)
        S, Nphi = self.shape_at(x)
        return FramePoint(self, (x, 0.0), S, Nphi)

    def displacement(self, q, x=None):
        """Elastic displacement (u, w) of the axis at x in the body frame, m (default: tip)."""
        S, _ = self.shape_at(self.x_max if x is None else x)
        return S @ q[3:]

    def displacement_probe(self, x=None):
        """Probe ``(scene, t, q, v) -> (u, w)`` of the body-frame displacement at x (default: tip).

        Raises ``ValueError`` if x lies outside the beam."""
        S, _ = self.shape_at(self.x_max if x is None else x)
        return LinearProbe(self, np.hstack([np.zeros((2, 3)), S]))

    def geometry(self, q, v):
        """Nodes in the global frame as line cells, with displacement, velocity, angle and section forces."""
        x, u, w, ph = self.nodal_fields(q)
        dv = self.full_elastic(v)
        nd = self.beam.node_dofs
        du, dw = dv[nd[:, 0]], dv[nd[:, 1]]
        A = _rot(q[2])
        s = np.stack([x + u, w], axis=1)
        pts = q[:2] + s @ A.T
        ref = self.q0[:2] + np.stack([x, np.zeros_like(x)], axis=1) @ _rot(self.q0[2]).T
        om = v[2]
        vel = v[:2] + (om * (s @ E2.T) + np.stack([du, dw], axis=1)) @ A.T
        node_of_u = np.empty(self.beam.n_dofs, dtype=int)
        node_of_u[nd[:, 0]] = np.arange(nd.shape[0])
        conn = node_of_u[self._ax.eu]
        cell = "line" if conn.shape[1] == 2 else "line3"
        st = self.strains(q)
        h = self.beam.element_lengths
        cd = {"axial_force": [st["axial_force"].mean(axis=1)],
              "shear_force": [st["shear_force"].mean(axis=1)],
              "bending_moment": [st["bending_moment"].mean(axis=1)],
              "strain_energy_density": [self.element_strain_energy(q) / h]}
        pd = {"displacement": pts - ref, "velocity": vel, "angle": q[2] + ph}
        return BodyGeometry(pts, [(cell, conn)], pd, cd)

    # ================================================================ reduction
    def elastic_model(self):
        """The beam as an :class:`~skfem_flex.bodies.modal.body.ElasticModel` on all its DOFs (u, w, φ per node).

        Interfaces ``"root"`` and ``"tip"`` (u, w, φ of the end nodes); Green–Lagrange data: the axial
        strain ε = u' + ½(u'² + w'²) with EA on the exact rule (its linear part is the axial part of
        the beam stiffness). Built once per body (:func:`.floating_model.beam_elastic_model`)."""
        if getattr(self, "_model", None) is None:
            self._model = beam_elastic_model(self)
        return self._model

    def reduced(self, n_modes, interfaces=("root", "tip"), **kwargs):
        """This beam reduced to a :class:`~skfem_flex.bodies.modal.body.ModalBody` (same initial frame state).

        ``n_modes`` fixed-interface (Craig–Bampton) or free-interface modes; interfaces ``"root"``,
        ``"tip"``; further keywords go to :func:`~skfem_flex.bodies.modal.reduction.reduce` (``method``,
        ``reference``, ``strain`` (default: this beam's), ``n_derivatives``, ``interface_derivatives``,
        ``centrifugal``, ``name``).
        The beam's elastic initial state is not carried over (η starts at 0)."""
        from ..modal.reduction import reduce
        state = dict(position=self.q0[:2], angle=self.q0[2], velocity=self.v0[:2], angular_velocity=self.v0[2],
                     strain=self.strain, name=self.name)
        state.update(kwargs)
        return reduce(self.elastic_model(), n_modes, interfaces=list(interfaces), **state)

    # ================================================================ steady rotation
    def centrifugal_equilibrium(self, omega, tol=1e-12, max_iterations=50):
        """Static elastic state q_f (n_elastic,) of the beam turning at constant ω (rad/s) with R fixed
        (:func:`.floating_rotation.centrifugal_equilibrium`).

        Raises
        ------
        ValueError
            If ω is not finite or Newton does not converge (e.g. beyond a divergence speed).
        """
        return centrifugal_equilibrium(self, omega, tol, max_iterations)

    def rotating_modes(self, omega, n_modes=3, bending_only=True):
        """Natural frequencies (rad/s, ascending) and real mode shapes (n_elastic, n_modes) in the frame
        turning at constant ω (rad/s), about the stretched state (:func:`.floating_rotation.rotating_modes`:
        centrifugal stiffening and softening, Coriolis coupling)."""
        return rotating_modes(self, omega, n_modes, bending_only)
