"""Force elements: gravity, springs and loads that act on the coordinates of bodies.

A force element names the ``bodies`` whose coordinates it reads; the scene
hands it the concatenation of those bodies' coordinate blocks (``q_loc``) in
that order. A conservative element provides a potential with gradient,
Hessian and discrete gradient; a non-conservative one a generalized force
(f, ∂f/∂q, ∂f/∂v) at (q, v, t), whose work the integrators record as
external work.
"""
from __future__ import annotations

import copy

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps

from ..bodies.base import DENSE_LIMIT, BodyPoint, check_finite_vector, keeps_methods
from ..bodies.rigid import E_MATRIX, rotation
from .point_terms import Difference, Dot, PointLayout, Position, angle_term

__all__ = ["ForceElement", "Gravity", "NonlinearSpring", "split_blocks", "LinearSpring", "LinearDamper",
           "RotationalSpring", "RotationalDamper", "PointForce", "PointMoment", "time_function", "half_sine_pulse"]


def split_blocks(bodies, q_loc):
    """Split a concatenated local vector into one view per body."""
    out, start = [], 0
    for b in bodies:
        out.append(q_loc[start:start + b.n_dofs])
        start += b.n_dofs
    return out


#: the methods of a conservative element's compiled form (a subclass redefining one runs in Python)
CONSERVATIVE = ("potential_energy", "potential_gradient", "potential_hessian", "potential_discrete_gradient")


class ForceElement:
    """Base class. ``conservative`` selects which half of the interface applies."""

    bodies: tuple = ()
    conservative: bool = True
    name: str = "force"

    # conservative elements
    def potential_energy(self, q):
        raise NotImplementedError

    def potential_gradient(self, q):
        raise NotImplementedError

    def potential_hessian(self, q):
        raise NotImplementedError

    def potential_discrete_gradient(self, q0, q1):
        """(g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0)."""
        raise NotImplementedError

    def compiled_form(self):
        """How the compiled mechanism loop (:mod:`skfem_flex.compiled.scene_loop`) evaluates this element,
        or None (the default: the scene runs on the Python path).

        ``("gravity", g)``; ``("coordinate spring", i, k, p)`` for V = ½ k q_i^p (i over the element's
        own coordinates); ``("point force", point, F)`` for Q = r_qᵀ F(t) (F in the global frame);
        ``("generalized force", G, F)`` for Q = Gᵀ F(t) (G constant, (k, the element's coordinates),
        F(t) of k values); ``("follower force", point, g, c, F)`` for Q = r_qᵀ A(g · q + c) F(t);
        ``("quadratic spring", g, c, k)`` for V = ½ k (g · q + c)²; ``("linear damper", g, c)`` for
        Q = −c (g · v) g; ``("two-point spring", a, b, anchor, k, l₀)`` for V = ½ k (‖r_a − r_b‖ − l₀)²
        and ``("two-point damper", a, b, anchor, c)`` for the damper along r_a − r_b (b None: the
        ground point ``anchor``). Vectors g are over the element's own coordinates.
        """
        return None

    # non-conservative elements
    def generalized_force(self, q, v, t):
        """(f, ∂f/∂q, ∂f/∂v) at time t (s)."""
        raise NotImplementedError


class Gravity(ForceElement):
    """Uniform gravity field acting on bodies.

    Parameters
    ----------
    g : array_like, shape (2,)
        Acceleration of gravity in m/s², default (0, −9.81) (y up).
    bodies : sequence of Body, optional
        Bodies it acts on; ``None`` (default) means every body of the scene.

    Notes
    -----
    V = −g · ∫ r dm, summed over the bodies; each body supplies its own
    :meth:`~skfem_flex.bodies.base.Body.gravity_potential`. For bodies whose
    positions are linear in q the gradient is constant and is built once.
    """

    conservative = True
    name = "gravity"

    def __init__(self, g=(0.0, -9.81), bodies=None):
        self.g = check_finite_vector("g", g, 2)
        self.bodies = None if bodies is None else tuple(bodies)
        if self.bodies is None:
            return
        self._slices, self._const_grad, start = [], [], 0
        for b in self.bodies:
            self._slices.append(slice(start, start + b.n_dofs))
            start += b.n_dofs
            try:
                gam, _ = b.mass_moment()
                self._const_grad.append(-(self.g @ gam))
            except NotImplementedError:
                self._const_grad.append(None)
        self._n = start
        self._linear = all(c is not None for c in self._const_grad)

    def on(self, bodies):
        """The same field acting on ``bodies`` (used by the scene for ``bodies=None``); a subclass stays
        itself (a copy, set up again for ``bodies``)."""
        new = copy.copy(self)
        Gravity.__init__(new, self.g, bodies)
        return new

    def compiled_form(self):
        if not keeps_methods(self, Gravity, CONSERVATIVE):
            return None
        return "gravity", self.g

    def potential_energy(self, q):
        return sum(b.gravity_potential(q[s], self.g)[0] for b, s in zip(self.bodies, self._slices))

    def potential_gradient(self, q):
        out = np.empty(self._n)
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            out[s] = c if c is not None else b.gravity_potential(q[s], self.g)[1]
        return out

    def potential_hessian(self, q):
        if self._linear:
            return None
        return self._block_diagonal([None if c is not None else b.gravity_potential(q[s], self.g)[2]
                                     for b, s, c in zip(self.bodies, self._slices, self._const_grad)])

    def potential_discrete_gradient(self, q0, q1):
        if self._linear:
            return self.potential_gradient(q0), None
        g = np.empty(self._n)
        blocks = []
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            if c is not None:
                g[s] = c
                blocks.append(None)
            else:
                gb, hb = b.gravity_discrete_gradient(q0[s], q1[s], self.g)
                g[s] = gb
                blocks.append(hb)
        return g, self._block_diagonal(blocks)

    def _block_diagonal(self, blocks):
        """Block diagonal of the bodies' blocks (None: zero block of that body's size).

        One body: its own block as it comes (dense stays dense, so that small scenes do no sparse
        work per Newton evaluation); several: dense if every block is and the total is small,
        sparse otherwise."""
        if len(blocks) == 1:
            return blocks[0]
        if self._n <= DENSE_LIMIT and not any(sps.issparse(blk) for blk in blocks):     # a small (dense) scene
            return sla.block_diag(*[np.zeros((b.n_dofs, b.n_dofs)) if blk is None else blk
                                    for b, blk in zip(self.bodies, blocks)])
        return sps.block_diag([sps.csr_matrix((b.n_dofs, b.n_dofs)) if blk is None else sps.csr_matrix(blk)
                               for b, blk in zip(self.bodies, blocks)], format="csr")


#: largest exponent n of a NonlinearSpring (V = ½ k u^(2n))
MAX_SPRING_EXPONENT = 100


class NonlinearSpring(ForceElement):
    """Spring on one coordinate with strain ε = u^n and energy V = ½ k ε².

    Parameters
    ----------
    body : Body
        The body whose coordinate stretches the spring.
    stiffness : float
        k in N/m^(2n−1) (N/m for n = 1), finite and positive.
    exponent : float
        n with 2n a positive integer, so that V = ½ k u^(2n) is a polynomial
        defined for all u: n = 1 linear, n = 2 gives m ü + 2 k u³ = 0, n = 1.5
        gives V = ½ k u³ (unbounded below; Lee & Yun, §4).
    coordinate : int or str
        Which coordinate of the body is u (default 0).

    Notes
    -----
    Discrete gradient (Lee & Yun, eq. 25a generalised): the exact
    divided difference (V(u1) − V(u0))/(u1 − u0) = ½ k Σ_j u1^j u0^(2n−1−j),
    free of cancellation; for n = 2 it equals k (u0² + u1²)/2 · (u0 + u1),
    the stress at the mean strain times the strain difference.
    """

    conservative = True
    name = "spring"

    def __init__(self, body, stiffness, exponent=1.0, coordinate=0):
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        n = float(exponent)
        two_n = 2.0 * n
        if not np.isfinite(n) or n <= 0 or abs(two_n - round(two_n)) > 1e-12:
            raise ValueError(f"exponent must be positive with 2*exponent an integer (1, 1.5, 2, ...), got {exponent!r}")
        if two_n > 2 * MAX_SPRING_EXPONENT:
            # u^(2n) of any u ≠ ±1 leaves double precision long before; the discrete gradient sums 2n terms
            raise ValueError(f"exponent must be at most {MAX_SPRING_EXPONENT}, got {exponent!r}")
        self.k, self.exponent, self.power = k, n, int(round(two_n))
        self.bodies = (body,)
        self.index = body.coordinate_index(coordinate)
        self.n = body.n_dofs

    def _u(self, q):
        return float(q[self.index])

    def potential_energy(self, q):
        return 0.5 * self.k * self._u(q) ** self.power

    def potential_gradient(self, q):
        g = np.zeros(self.n)
        p = self.power
        g[self.index] = 0.5 * self.k * p * self._u(q) ** (p - 1)
        return g

    def potential_hessian(self, q):
        h = np.zeros((self.n, self.n))
        p = self.power
        h[self.index, self.index] = 0.5 * self.k * p * (p - 1) * self._u(q) ** (p - 2) if p >= 2 else 0.0
        return h

    def potential_discrete_gradient(self, q0, q1):
        u0, u1, p = self._u(q0), self._u(q1), self.power
        j = np.arange(p)
        g = np.zeros(self.n)
        g[self.index] = 0.5 * self.k * np.sum(u1 ** j * u0 ** (p - 1 - j))
        h = np.zeros((self.n, self.n))
        if p >= 2:
            j = np.arange(1, p)
            h[self.index, self.index] = 0.5 * self.k * np.sum(j * u1 ** (j - 1) * u0 ** (p - 1 - j))
        return g, h

    def compiled_form(self):
        if not keeps_methods(self, NonlinearSpring, CONSERVATIVE):
            return None
        return "coordinate spring", self.index, self.k, self.power


# ============================================================ point elements
def time_function(value, size, name="load"):
    """A callable t -> array (size,) from a constant or a callable.

    Parameters
    ----------
    value : float, array_like or callable
        A constant (broadcast to ``size``) or a function of time t (s).
    size : int
        1 for scalars (moments), 2 for vectors (forces).
    name : str
        Used in error messages.
    """
    if callable(value):
        probe = np.atleast_1d(np.asarray(value(0.0), dtype=float)).ravel()
        if probe.size != size:
            raise ValueError(f"{name}(t) must return {size} value(s), got {probe.size}")

        def fun(t):
            out = np.atleast_1d(np.asarray(value(t), dtype=float)).ravel()
            if not np.all(np.isfinite(out)):
                raise ValueError(f"{name}({t!r}) is not finite: {out!r}")
            return out
        # the compiled loop tabulates a chunk of steps at once and checks the whole table (``fun``
        # raises the error for the first entry that is not finite)
        fun.unchecked = value
        return fun
    const = check_finite_vector(name, value, size)
    return lambda t: const


def half_sine_pulse(amplitude, duration, start=0.0):
    """F(t) = amplitude · sin(π (t − start)/duration) for start ≤ t ≤ start + duration, zero otherwise.

    Parameters
    ----------
    amplitude : float or array_like
        Peak value (N, N m or a force vector in N).
    duration : float
        Pulse length τ in s (> 0). Its impulse is 2 τ amplitude / π.
    start : float
        Start time in s.
    """
    amp = np.asarray(amplitude, dtype=float)
    tau = float(duration)
    if not np.isfinite(tau) or tau <= 0:
        raise ValueError(f"pulse duration must be finite and positive, got {duration!r}")
    if not np.all(np.isfinite(amp)):
        raise ValueError(f"pulse amplitude must be finite, got {amplitude!r}")

    def fun(t):
        s = (t - start) / tau
        return amp * (np.sin(np.pi * s) if 0.0 <= s <= 1.0 else 0.0)
    return fun


def _other(point_b, point_a, what):
    """(BodyPoint or None, ground anchor or None) from the second argument of a two-point element."""
    if point_b is None:
        return None, np.asarray(point_a.position(np.asarray(point_a.body.q0, dtype=float)), dtype=float)
    if isinstance(point_b, BodyPoint):
        return point_b, None
    return None, check_finite_vector(f"{what} ground anchor", point_b, 2)


def _nonnegative(name, value):
    value = float(value)
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
    return value


class _TwoPoint(ForceElement):
    """Shared set-up of elements between a body point and another point or the ground."""

    def _setup(self, point_a, point_b, what):
        if not isinstance(point_a, BodyPoint):
            raise ValueError(f"{what} needs a body point (body.point(...)) as its first end, got {point_a!r}")
        pb, anchor = _other(point_b, point_a, what)
        self.layout = PointLayout([point_a, pb])
        n = self.layout.n
        sa, sb = self.layout.slices
        self.points, self.anchor = (point_a, pb), anchor
        self.bodies = self.layout.bodies
        self.n = n
        self._d = Difference(n, point_a, sa, pb, sb, None if pb is not None else anchor)    # d = r_a − r_b
        self._s = Dot(n, self._d, self._d)                                                 # s = |d|²


class LinearSpring(_TwoPoint):
    """Linear spring between two body points, or a body point and a ground point.

    V = ½ k (l − l₀)² with l = ‖r_a − r_b‖.

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint, array_like (2,) or None
        The other end: a body point, a ground point (m), or ``None`` for the
        ground point where ``point_a`` starts.
    stiffness : float
        k in N/m (> 0).
    rest_length : float, optional
        l₀ in m (≥ 0); default the initial length.
    name : str

    Notes
    -----
    Exact discrete gradient in closed form (Simo & Tarnow's "stress at the
    mean strain" for a spring): with s = l², the divided difference of
    V(s) = ½ k (√s − l₀)² is (V1 − V0)/(s1 − s0) = ½ k (1 − 2 l₀/(l_0 + l_1)),
    free of cancellation, times the exact discrete gradient of s (the product
    rule Δ(d·d) = 2 d̄·Δd on the points' exact position gradients).
    """

    conservative = True

    def __init__(self, point_a, point_b, stiffness, rest_length=None, name="spring"):
        self._setup(point_a, point_b, "LinearSpring")
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        self.k = k
        q0 = self.layout.initial()
        l_init = float(np.sqrt(self._s.value(q0)[0]))
        self.rest_length = l_init if rest_length is None else _nonnegative("rest_length", rest_length)
        self.name = name

    def length(self, q):
        """l = ‖r_a − r_b‖ in m."""
        return float(np.sqrt(self._s.value(q)[0]))

    def tension(self, q):
        """k (l − l₀) in N (positive when stretched)."""
        return self.k * (self.length(q) - self.rest_length)

    def potential_energy(self, q):
        return 0.5 * self.k * (self.length(q) - self.rest_length) ** 2

    def _dvds(self, s):
        if self.rest_length == 0.0:
            return 0.5 * self.k, 0.0
        ln = np.sqrt(s)
        return 0.5 * self.k * (1.0 - self.rest_length / ln), 0.25 * self.k * self.rest_length / (s * ln)

    def potential_gradient(self, q):
        s = self._s.value(q)[0]
        return self._dvds(s)[0] * self._s.jacobian(q)[0]

    def potential_hessian(self, q):
        s = self._s.value(q)[0]
        d1, d2 = self._dvds(s)
        js = self._s.jacobian(q)[0]
        return d2 * np.outer(js, js) + self._s.hessian(q, np.array([d1]))

    def potential_discrete_gradient(self, q0, q1):
        l0, l1 = self.length(q0), self.length(q1)
        lr = self.rest_length
        ssum = l0 + l1
        kappa = 0.5 * self.k * (1.0 - 2.0 * lr / ssum) if lr > 0.0 else 0.5 * self.k
        ds = self._s.dgrad(q0, q1)[0]
        g = kappa * ds
        h = self._s.dgrad_jacobian(q0, q1, np.array([kappa]))
        if lr > 0.0:
            h = h + (self.k * lr / (2.0 * l1 * ssum ** 2)) * np.outer(ds, self._s.jacobian(q1)[0])
        return g, h

    def compiled_form(self):
        if not keeps_methods(self, LinearSpring, CONSERVATIVE + ("length", "_dvds")):
            return None
        return "two-point spring", self.points[0], self.points[1], self.anchor, self.k, self.rest_length


class LinearDamper(_TwoPoint):
    """Linear damper along the line of two body points (or a body point and the ground).

    Force on point a: F = −c (u · (ṙ_a − ṙ_b)) u with u = (r_a − r_b)/l, the
    opposite on b; generalized force Q = J_dᵀ F (J_d = ∂(r_a − r_b)/∂q).

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint, array_like (2,) or None
        As for :class:`LinearSpring`.
    damping : float
        c in N s/m (≥ 0).
    name : str

    Notes
    -----
    Non-conservative: the energy scheme evaluates it at the midpoint
    q_m with v̄ = Δq/Δt, so its work −c Δt (u·J v̄)² ≤ 0 enters
    ``Result.external_work`` exactly.
    """

    conservative = False

    def __init__(self, point_a, point_b, damping, name="damper"):
        self._setup(point_a, point_b, "LinearDamper")
        self.c = _nonnegative("damping", damping)
        self.name = name

    def generalized_force(self, q, v, t):
        d = self._d.value(q)
        jd = self._d.jacobian(q)
        ln = float(np.hypot(*d))
        if ln == 0.0:
            raise ValueError(f"damper {self.name!r}: its two points coincide, the direction is undefined")
        u = d / ln
        w = jd @ v
        rate = float(u @ w)
        jtu = jd.T @ u
        f = -self.c * rate * jtu
        du = (np.eye(2) - np.outer(u, u)) @ jd / ln              # ∂u/∂q
        dw = np.vstack([self._d.hessian(q, e) @ v for e in np.eye(2)])   # ∂(J_d v)/∂q
        drate = w @ du + u @ dw
        fq = -self.c * (np.outer(jtu, drate) + rate * (self._d.hessian(q, u) + jd.T @ du))
        fv = -self.c * np.outer(jtu, jtu)
        return f, fq, fv

    def compiled_form(self):
        if not keeps_methods(self, LinearDamper, ("generalized_force",)):
            return None
        return "two-point damper", self.points[0], self.points[1], self.anchor, self.c


class _Rotational(ForceElement):
    def _setup(self, point_a, point_b, what):
        if not isinstance(point_a, BodyPoint):
            raise ValueError(f"{what} needs a body point (body.point(...)), got {point_a!r}")
        if point_b is not None and not isinstance(point_b, BodyPoint):
            raise ValueError(f"{what}: the second end must be a body point or None (ground), got {point_b!r}")
        self.layout = PointLayout([point_a, point_b])
        n = self.layout.n
        sa, sb = self.layout.slices
        ta = angle_term(n, point_a, sa)
        if point_b is None:
            self.grad = ta.grad.copy()
            self._angle = ta.fun
        else:
            tb = angle_term(n, point_b, sb)
            self.grad = ta.grad - tb.grad
            self._angle = lambda q: ta.fun(q) - tb.fun(q)
        self.bodies = self.layout.bodies
        self.points = (point_a, point_b)
        self.n = n

    def relative_angle(self, q):
        """ϑ_a − ϑ_b (ϑ_b = 0 for the ground), rad."""
        return float(self._angle(q))


class RotationalSpring(_Rotational):
    """Torsion spring on the relative angle of two body points (or a point's angle to the ground).

    V = ½ k (ϑ_a − ϑ_b − ϑ₀)². The angles are linear in q, so V is quadratic
    and the midpoint gradient k (ϑ̄ − ϑ₀) ∇ϑ is its exact discrete gradient.

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint or None
        ``None``: the ground (angle 0).
    stiffness : float
        k in N m/rad (> 0).
    rest_angle : float, optional
        ϑ₀ in rad; default the initial relative angle.
    name : str
    """

    conservative = True

    def __init__(self, point_a, point_b=None, stiffness=1.0, rest_angle=None, name="torsion spring"):
        self._setup(point_a, point_b, "RotationalSpring")
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r}")
        self.k = k
        a0 = self.relative_angle(self.layout.initial())
        self.rest_angle = a0 if rest_angle is None else float(check_finite_vector("rest_angle", rest_angle, 1)[0])
        self.name = name

    def potential_energy(self, q):
        return 0.5 * self.k * (self.relative_angle(q) - self.rest_angle) ** 2

    def potential_gradient(self, q):
        return self.k * (self.relative_angle(q) - self.rest_angle) * self.grad

    def potential_hessian(self, q):
        return self.k * np.outer(self.grad, self.grad)

    def potential_discrete_gradient(self, q0, q1):
        mean = 0.5 * (self.relative_angle(q0) + self.relative_angle(q1))
        return self.k * (mean - self.rest_angle) * self.grad, 0.5 * self.k * np.outer(self.grad, self.grad)

    def compiled_form(self):
        # the angles are linear in q: ϑ_a − ϑ_b − ϑ₀ = g · q + c with c its value at q = 0
        if not keeps_methods(self, RotationalSpring, CONSERVATIVE + ("relative_angle",)):
            return None
        return ("quadratic spring", self.grad.copy(), self.relative_angle(np.zeros(self.n)) - self.rest_angle,
                self.k)


class RotationalDamper(_Rotational):
    """Torsion damper: moment −c (ϑ̇_a − ϑ̇_b) on point a (the opposite on b).

    Parameters
    ----------
    point_a : BodyPoint
    point_b : BodyPoint or None
        ``None``: the ground.
    damping : float
        c in N m s/rad (≥ 0).
    name : str
    """

    conservative = False

    def __init__(self, point_a, point_b=None, damping=0.0, name="torsion damper"):
        self._setup(point_a, point_b, "RotationalDamper")
        self.c = _nonnegative("damping", damping)
        self.name = name

    def generalized_force(self, q, v, t):
        rate = float(self.grad @ v)
        return -self.c * rate * self.grad, None, -self.c * np.outer(self.grad, self.grad)

    def compiled_form(self):
        if not keeps_methods(self, RotationalDamper, ("generalized_force",)):
            return None
        return "linear damper", self.grad.copy(), self.c


class PointForce(ForceElement):
    """A force F(t) (N) acting at a body point, in the global frame or following the body.

    Q = r_qᵀ F. A follower force is given in the frame of the point
    (the rigid body's frame or the beam's cross-section), F = A(ϑ) F_loc(t).

    Parameters
    ----------
    point : BodyPoint
    force : array_like (2,) or callable t -> (2,)
        The force (N), constant or a function of time (s).
    follower : bool
        False (default): ``force`` is in the global frame. True: in the
        point's frame (needs a point with an angle).
    name : str
    """

    conservative = False

    def __init__(self, point, force, follower=False, name="point force"):
        if not isinstance(point, BodyPoint):
            raise ValueError(f"PointForce needs a body point (body.point(...)), got {point!r}")
        self.layout = PointLayout([point])
        n = self.layout.n
        self.bodies = self.layout.bodies
        self.force = time_function(force, 2, "force")
        self.follower = bool(follower)
        self._pos = Position(n, point, self.layout.slices[0])
        if self.follower:
            self._angle = angle_term(n, point, self.layout.slices[0])
        self.point = point
        self.name = name

    def global_force(self, q, t):
        """F in the global frame (N)."""
        f = self.force(t)
        if self.follower:
            f = rotation(self._angle.fun(q)) @ f
        return f

    def generalized_force(self, q, v, t):
        f = self.global_force(q, t)
        jac = self._pos.jacobian(q)
        fq = self._pos.hessian(q, f)
        if self.follower:
            fq = fq + np.outer(jac.T @ (E_MATRIX @ f), self._angle.grad)
        return jac.T @ f, fq, None

    def compiled_form(self):
        if not keeps_methods(self, PointForce, ("generalized_force", "global_force")):
            return None
        if self.follower:
            n = self.layout.n
            return "follower force", self.point, self._angle.grad.copy(), float(self._angle.fun(np.zeros(n))), self.force
        return "point force", self.point, self.force


class PointMoment(ForceElement):
    """A moment M(t) (N m, counter-clockwise) acting at a body point (on its frame angle ϑ).

    Q = M ∇ϑ. In the plane a moment is the same in the global frame and
    following the body.

    Parameters
    ----------
    point : BodyPoint
        A point with an angle.
    moment : float or callable t -> float
    name : str
    """

    conservative = False

    def __init__(self, point, moment, name="point moment"):
        if not isinstance(point, BodyPoint):
            raise ValueError(f"PointMoment needs a body point (body.point(...)), got {point!r}")
        self.layout = PointLayout([point])
        self.bodies = self.layout.bodies
        self.moment = time_function(moment, 1, "moment")
        self._angle = angle_term(self.layout.n, point, self.layout.slices[0])
        self.point = point
        self.name = name

    def generalized_force(self, q, v, t):
        return float(self.moment(t)[0]) * self._angle.grad, None, None

    def compiled_form(self):
        if not keeps_methods(self, PointMoment, ("generalized_force",)):
            return None
        return "generalized force", self._angle.grad.reshape(1, -1).copy(), self.moment
