r"""Force elements on spatial bodies: springs and dampers between two points, torsional springs and dampers
about a hinge axis, point forces and moments (fixed in space or following the body), with time functions.

Positions and body directions of spatial bodies are affine in q (:class:`~..constraints.quadratic.Affine`):
r = A q + a, so the squared length s = d·d of a spring is quadratic and its mid-point gradient is an exact
discrete gradient. The spring's potential V(s) = ½ k (√s − l₀)² then has the exact discrete gradient
(V₁ − V₀)/(s₁ − s₀) ∇s(q_m) = ½ k (1 − 2 l₀/(l₀ + l₁)) ∇s(q_m) (free of cancellation). A torsional spring's
angle θ = atan2(u·n₂, u·n₁) is not a polynomial; its discrete gradient is Gonzalez's mid-point gradient
with the correction along Δq, exact, and equivariant under rotations of the whole system (so it conserves
angular momentum too).

A moment M on a director body acts through the generalized forces f_{d_i} = ½ M × d_i on its directors
(their virtual work Σ f_{d_i}·(δφ × d_i) = M·δφ for orthonormal directors).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ...bodies.base import BodyPoint, check_finite_vector, keeps_methods
from ...numerics.quaternions import skew
from ..constraints.quadratic import Affine, hinge_directions
from ..point_terms import PointLayout
from .base import CONSERVATIVE, ForceElement, check_nonnegative
from .point_loads import time_function

__all__ = ["SpatialSpring", "SpatialDamper", "SpatialTorsionalSpring", "SpatialTorsionalDamper", "SpatialPointForce",
           "SpatialDistributedLoad", "SpatialMoment", "distributed_moments"]


def _spatial_point(name, point):
    if not isinstance(point, BodyPoint) or getattr(point, "dimension", 2) != 3:
        raise ValueError(f"{name} must be a point of a spatial body (body.point(...)), got {point!r}")
    return point


class _Line(ForceElement):
    """d = r_a − r_b between two points or a point and a ground point: the layout and the affine d."""

    def _setup(self, point_a, point_b, what):
        pa = _spatial_point(f"{what}: point_a", point_a)
        if point_b is None or isinstance(point_b, BodyPoint):
            pb = None if point_b is None else _spatial_point(f"{what}: point_b", point_b)
            anchor = pa.position(np.asarray(pa.body.q0, dtype=float)) if pb is None else None
        else:
            pb, anchor = None, check_finite_vector(f"{what}: ground point", point_b, 3)
        self.layout = PointLayout([pa] if pb is None else [pa, pb])
        self.bodies = self.layout.bodies
        n = self.layout.n
        ra = Affine.of(pa, self.layout.slices[0], n)
        rb = Affine.constant(anchor, n) if pb is None else Affine.of(pb, self.layout.slices[1], n)
        self.d = ra - rb
        self.points, self.anchor = (pa, pb), anchor

    def vector(self, q):
        """d = r_a − r_b, m."""
        return self.d.value(q)

    def length(self, q):
        """l = ‖r_a − r_b‖, m."""
        return float(np.linalg.norm(self.d.value(q)))


class SpatialSpring(_Line):
    """Linear spring between two points of spatial bodies, or a point and a ground point: V = ½ k (l − l₀)².

    Parameters
    ----------
    point_a : SpatialPoint
    point_b : SpatialPoint, array_like (3,) or None
        A body point, a ground point (m), or None for the ground point where ``point_a`` starts.
    stiffness : float
        k, N/m (> 0).
    rest_length : float, optional
        l₀, m (≥ 0); default the initial length.
    name : str
    """

    conservative = True

    def __init__(self, point_a, point_b, stiffness, rest_length=None, name="spring"):
        self._setup(point_a, point_b, "SpatialSpring")
        self.k = float(stiffness)
        if not np.isfinite(self.k) or self.k <= 0.0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r} N/m")
        length = self.length(self.layout.initial())
        self.rest_length = length if rest_length is None else check_nonnegative("rest_length", rest_length)
        self.name = name

    def compiled_form(self):
        """("spatial spring", A, a, k, l₀) of the spatial-spring family (d = A q + a on the element's coordinates),
        when both points are affine in q; None otherwise (a floating-frame body's material point: the Python
        path)."""
        if self.d.H is not None or not keeps_methods(self, SpatialSpring, CONSERVATIVE + ("length", "_ds")):
            return None
        return "spatial spring", self.d.A, self.d.a, self.k, self.rest_length

    def _ds(self, q):
        """∇s (n,) with s = d·d: 2 Aᵀ d."""
        return 2.0 * self.d.A.T @ self.d.value(q)

    def potential_energy(self, q):
        return 0.5 * self.k * (self.length(q) - self.rest_length) ** 2

    def potential_gradient(self, q):
        ln = self.length(q)
        if ln == 0.0 and self.rest_length > 0.0:
            raise ValueError(f"spring {self.name!r}: its two points coincide, the direction is undefined")
        return 0.5 * self.k * (1.0 - self.rest_length / ln if self.rest_length else 1.0) * self._ds(q)

    def potential_hessian(self, q):
        ln, lr = self.length(q), self.rest_length
        ds = self._ds(q)
        coef = 0.5 * self.k * (1.0 - lr / ln if lr else 1.0)
        h = coef * 2.0 * self.d.A.T @ self.d.A
        if lr:
            h = h + 0.25 * self.k * lr / ln ** 3 * np.outer(ds, ds)
        return h

    def potential_discrete_gradient(self, q0, q1):
        l0, l1, lr = self.length(q0), self.length(q1), self.rest_length
        total = l0 + l1
        if lr and total == 0.0:
            raise ValueError(f"spring {self.name!r}: its two points coincide, the direction is undefined")
        kappa = 0.5 * self.k * (1.0 - 2.0 * lr / total) if lr else 0.5 * self.k
        ds = self._ds(0.5 * (q0 + q1))
        h = kappa * self.d.A.T @ self.d.A
        if lr:
            h = h + (self.k * lr / (2.0 * l1 * total ** 2)) * np.outer(ds, self._ds(q1))
        return kappa * ds, h

    def tension(self, q):
        """k (l − l₀), N (positive when stretched)."""
        return self.k * (self.length(q) - self.rest_length)


class SpatialDamper(_Line):
    """Linear damper along the line of two points (or a point and the ground): F_a = −c (u·(ṙ_a − ṙ_b)) u.

    Parameters
    ----------
    point_a, point_b : as for :class:`SpatialSpring`.
    damping : float
        c, N s/m (≥ 0).
    name : str
    """

    conservative = False

    def __init__(self, point_a, point_b, damping, name="damper"):
        self._setup(point_a, point_b, "SpatialDamper")
        self.c = check_nonnegative("damping", damping)
        self.name = name

    def compiled_form(self):
        """("spatial damper", A, a, c) of the spatial-spring and damper family (d = A q + a), when both points are
        affine in q; None otherwise (the Python path)."""
        if self.d.H is not None or not keeps_methods(self, SpatialDamper, ("generalized_force",)):
            return None
        return "spatial damper", self.d.A, self.d.a, self.c

    def generalized_force(self, q, v, t):
        d, A = self.d.value(q), self.d.A
        ln = float(np.linalg.norm(d))
        if ln == 0.0:
            raise ValueError(f"damper {self.name!r}: its two points coincide, the direction is undefined")
        u = d / ln
        w = A @ v
        rate = float(u @ w)
        jtu = A.T @ u
        du = (np.eye(3) - np.outer(u, u)) @ A / ln                # ∂u/∂q
        f = -self.c * rate * jtu
        fq = -self.c * (np.outer(jtu, w @ du) + rate * A.T @ du)
        fv = -self.c * np.outer(jtu, jtu)
        return f, fq, fv


class _HingeAngle(ForceElement):
    """θ = atan2(u·n₂, u·n₁) between two spatial rigid bodies about a hinge axis (or a body and the ground):
    u a direction of body b perpendicular to the axis e, n₁, n₂ directions of body a perpendicular to e, all
    fixed in the bodies at the start (θ = 0 there). Beside a :class:`~skfem_flex.Revolute3D` about the same
    axis θ is the hinge angle (abs(θ) < π)."""

    def _setup(self, body_a, body_b, axis):
        self.layout, self.u, self.n1, self.n2 = hinge_directions(body_a, body_b, axis)
        self.bodies = self.layout.bodies
        # against the ground, u is body a's own direction: θ of the ground against a is −θ of a
        self.sign = -1.0 if body_b is None else 1.0

    def angle(self, q):
        """θ, rad (in (−π, π])."""
        x, y = self._xy(q)
        return self.sign * float(np.arctan2(y, x))

    def _xy(self, q):
        u = self.u.value(q)
        return float(u @ self.n1.value(q)), float(u @ self.n2.value(q))

    def _forms(self):
        """(H_x, b_x, c_x, H_y, b_y, c_y) of x = u·n₁ = ½ qᵀH_x q + b_x·q + c_x and of y = u·n₂."""
        return tuple(part for p in (self.u.dot(self.n1), self.u.dot(self.n2))
                     for part in (p[0][0], p[1][0], float(p[2][0])))

    def _invariant_gradients(self, q):
        """∇x, ∇y (n,) of x = u·n₁, y = u·n₂."""
        u = self.u.value(q)
        return (self.u.A.T @ self.n1.value(q) + self.n1.A.T @ u, self.u.A.T @ self.n2.value(q) + self.n2.A.T @ u)

    def angle_gradient(self, q):
        """∇θ (n,) and ∇²θ (n, n) from x = u·n₁, y = u·n₂ (θ = atan2(y, x))."""
        u, a1, a2 = self.u.value(q), self.n1.value(q), self.n2.value(q)
        x, y = float(u @ a1), float(u @ a2)
        r2 = x * x + y * y
        if r2 == 0.0:
            raise ValueError(f"{self.name!r}: body b's direction lies along the axis, the angle is undefined")
        gx = self.u.A.T @ a1 + self.n1.A.T @ u
        gy = self.u.A.T @ a2 + self.n2.A.T @ u
        hx = self.u.A.T @ self.n1.A + self.n1.A.T @ self.u.A
        hy = self.u.A.T @ self.n2.A + self.n2.A.T @ self.u.A
        g = (x * gy - y * gx) / r2
        dg = (np.outer(gy, gx) - np.outer(gx, gy)) / r2 + (x * hy - y * hx) / r2 \
            - 2.0 * np.outer(x * gy - y * gx, x * gx + y * gy) / r2 ** 2
        return self.sign * g, self.sign * dg


class SpatialTorsionalSpring(_HingeAngle):
    """Torsional spring about a hinge axis: V = ½ k (θ − θ₀)² (θ: :class:`_HingeAngle`).

    Parameters
    ----------
    body_a : SpatialRigidBody
    body_b : SpatialRigidBody or None
        None: the ground.
    axis : array_like (3,)
        The hinge axis in space axes at the initial state.
    stiffness : float
        k, N m/rad (> 0).
    angle : float
        θ₀, rad.
    name : str
    """

    conservative = True

    def __init__(self, body_a, body_b, axis, stiffness, angle=0.0, name="torsional spring"):
        self._setup(body_a, body_b, axis)
        self.k = float(stiffness)
        if not np.isfinite(self.k) or self.k <= 0.0:
            raise ValueError(f"stiffness must be finite and positive, got {stiffness!r} N m/rad")
        self.rest = float(angle)
        self.name = name

    def compiled_form(self):
        """("torsional spring", H_x, b_x, c_x, H_y, b_y, c_y, σ, k, θ₀): the spatial torsional family, with
        x = u·n₁ and y = u·n₂ as quadratic forms; None for a subclass that changes the energy."""
        if not keeps_methods(self, SpatialTorsionalSpring, CONSERVATIVE + ("angle", "angle_gradient", "_xy")):
            return None
        return ("torsional spring", *self._forms(), self.sign, self.k, self.rest)

    def potential_energy(self, q):
        return 0.5 * self.k * (self.angle(q) - self.rest) ** 2

    def potential_gradient(self, q):
        return self.k * (self.angle(q) - self.rest) * self.angle_gradient(q)[0]

    def potential_hessian(self, q):
        g, dg = self.angle_gradient(q)
        return self.k * (np.outer(g, g) + (self.angle(q) - self.rest) * dg)

    def potential_discrete_gradient(self, q0, q1):
        """Through the invariants x = u·n₁, y = u·n₂ (quadratic: their mid-point gradients are exact): Gonzalez's
        discrete gradient of Ṽ(x, y) in the plane of (x, y), times ∇x(q_m), ∇y(q_m). Exact, and equivariant:
        x and y do not change when the whole system turns, so the spring exerts no net moment."""
        qm = 0.5 * (q0 + q1)
        z0, z1, zm = (np.array(self._xy(q)) for q in (q0, q1, qm))
        zm = 0.5 * (z0 + z1)
        dz = z1 - z0

        def v_of(z):
            return 0.5 * self.k * (self.sign * np.arctan2(z[1], z[0]) - self.rest) ** 2

        r2 = float(zm @ zm)
        theta = self.sign * np.arctan2(zm[1], zm[0])
        grad_z = self.k * (theta - self.rest) * self.sign * np.array([-zm[1], zm[0]]) / r2
        nrm2 = float(dz @ dz)
        if nrm2 > 0.0:
            grad_z = grad_z + (v_of(z1) - v_of(z0) - grad_z @ dz) / nrm2 * dz
        gx, gy = self._invariant_gradients(qm)
        return grad_z[0] * gx + grad_z[1] * gy, 0.5 * self.potential_hessian(qm)


class SpatialTorsionalDamper(_HingeAngle):
    """Torsional damper about a hinge axis: the moment −c θ̇ about it (θ: :class:`_HingeAngle`).

    Parameters
    ----------
    body_a, body_b, axis : as for :class:`SpatialTorsionalSpring`.
    damping : float
        c, N m s/rad (≥ 0).
    name : str
    """

    conservative = False

    def __init__(self, body_a, body_b, axis, damping, name="torsional damper"):
        self._setup(body_a, body_b, axis)
        self.c = check_nonnegative("damping", damping)
        self.name = name

    def compiled_form(self):
        """("torsional damper", H_x, b_x, c_x, H_y, b_y, c_y, σ, c, 0): the spatial torsional family; None for a
        subclass that changes the load."""
        if not keeps_methods(self, SpatialTorsionalDamper, ("generalized_force", "angle_gradient", "_xy")):
            return None
        return ("torsional damper", *self._forms(), self.sign, self.c, 0.0)

    def generalized_force(self, q, v, t):
        g, dg = self.angle_gradient(q)
        rate = float(g @ v)
        return -self.c * rate * g, -self.c * (np.outer(g, dg @ v) + rate * dg), -self.c * np.outer(g, g)


class SpatialPointForce(ForceElement):
    """A force F(t) at a point of a spatial body, in space axes or following the body (body axes).

    Parameters
    ----------
    point : SpatialPoint
    force : array_like (3,) or callable t -> (3,)
        N. In space axes, or with ``following=True`` in the body's axes (F = R F_body).
    following : bool
        The force turns with the body: with a rigid body, a beam's node, or a floating-frame body's material
        point that has an orientation (a beam's section, a rigid interface of a solid: F = D (f + (Θy) × f),
        :meth:`~skfem_flex.bodies.floating_spatial.frame.ElasticPoint.turned`; on the Python path).
    name : str
    """

    conservative = False

    def __init__(self, point, force, following=False, name="point force"):
        self.point = _spatial_point("point", point)
        body = point.body
        if following and point.triad is None and getattr(point, "Theta", None) is None:
            raise ValueError("a following force needs a point with an orientation (of a spatial rigid body, a "
                             "beam's node, or a floating-frame beam's section), got one without")
        self.force = time_function(force, 3, "force")
        self.following = bool(following)
        self.bodies = (body,)
        n = body.n_dofs
        # a point whose position is affine in q (rigid bodies, beam nodes) has a constant Jacobian G; any
        # other (a floating-frame beam's axis) gives its Jacobian and Hessian at each state
        self.G = getattr(point, "G", None)
        self._axes = ([Affine.of(point.axis(e), slice(0, n), n).A for e in np.eye(3)]
                      if following and self.G is not None else None)
        self.name = name

    def compiled_form(self):
        """A force fixed in space: ("generalized force", G, F) of the point-load family, or at a point whose
        position is quadratic in q (a floating-frame body's material point) ("quadratic point force", H, A, F)
        of the same family; a following one: ("spatial following force", G, triad, F) of the spatial-load
        family; any other point: None (the Python path)."""
        if type(self).generalized_force is not SpatialPointForce.generalized_force:
            return None
        if self.G is None:
            quadratic = getattr(self.point, "quadratic", None)
            if self.following or quadratic is None:
                return None
            H, A, _ = quadratic()
            return "quadratic point force", H, A, self.force
        if not self.following:
            return "generalized force", self.G, self.force
        return "spatial following force", self.G, tuple(self.point.triad), self.force

    def generalized_force(self, q, v, t):
        F = self.force(t)
        if self.G is None:
            J = self.point.position_jacobian(q)
            if self.following:
                # Q = Jᵀ F(q): ∂Q/∂q = (∂J/∂q)ᵀ F + Jᵀ ∂F/∂q
                F, dF = self.point.turned(q, F)
                return J.T @ F, self.point.position_hessian_product(q, F) + J.T @ dF, None
            return J.T @ F, self.point.position_hessian_product(q, F), None
        n = self.G.shape[1]
        if not self.following:
            return self.G.T @ F, np.zeros((n, n)), np.zeros((n, n))
        # F = Σ F_i d_i = Σ F_i A_i q: Q = Gᵀ Σ F_i A_i q
        B = sum(Fi * Ai for Fi, Ai in zip(F, self._axes))
        return self.G.T @ (B @ q), self.G.T @ B, np.zeros((n, n))


class SpatialMoment(ForceElement):
    """A moment M(t) on a spatial rigid body or a beam's node, in space axes or following it (its axes).

    Generalized forces on the directors f_{d_i} = W × d_i with S W = M, S = Σ_i (‖d_i‖² I − d_i d_iᵀ) (= 2 I
    for orthonormal directors): their moment Σ d_i × f_{d_i} = S W is M exactly at any state, so the
    angular momentum gains exactly ∫ M dt also at the mid-point of a step, where the directors are not
    quite orthonormal.

    Parameters
    ----------
    target : SpatialRigidBody or SpatialPoint or ElasticPoint
        A rigid body, or a point whose frame carries the moment (a beam's node: ``beam.point(s)``), or a
        floating-frame body's material point with an orientation (a beam's section, a solid's rigid
        interface): the moment then works on the frame's rotation and on the section's small elastic
        rotation θ = Θ y, Q_y = Θᵀ Dᵀ M (the Python path).
    moment : array_like (3,) or callable t -> (3,)
        N m.
    following : bool
        M given in the body's (node's, section's) axes (M = Σ M_j d_j turns with it; at a material point
        M = D (m + θ × m)).
    name : str
    """

    conservative = False

    def __init__(self, target, moment, following=False, name="moment"):
        #: the floating-frame material point the moment acts at, or None
        self.elastic = None
        if isinstance(target, BodyPoint):
            body, triad = target.body, getattr(target, "triad", None)
            if triad is None and getattr(target, "Theta", None) is not None:
                self.elastic, triad = target, (3, 6, 9)           # the frame's directors
        else:
            body, triad = target, (tuple(target.directors) if hasattr(target, "director_triads") else None)
        if triad is None:
            raise ValueError(f"a moment needs a spatial rigid body or a point with directors (a beam's node), "
                             f"got {target!r}")
        self.moment = time_function(moment, 3, "moment")
        self.following = bool(following)
        self.bodies = (body,)
        self.body = body
        self.triad = tuple(triad)
        self.name = name

    def compiled_form(self):
        """("spatial moment", triad, following, M): the spatial-load family."""
        if type(self).generalized_force is not SpatialMoment.generalized_force or self.elastic is not None:
            return None
        return "spatial moment", self.triad, self.following, self.moment

    def generalized_force(self, q, v, t):
        """(Q, ∂Q/∂q, 0): the class docstring's director forces f_{d_i} = W × d_i with S W = M(q), and at a
        floating-frame material point also Q_y = Θᵀ Dᵀ M; M's own derivative enters through ∂W/∂q."""
        n = self.body.n_dofs
        m = self.moment(t)
        d = np.array([q[o:o + 3] for o in self.triad], dtype=float)         # rows d_i
        if self.elastic is not None and self.following:
            M, dM = self.elastic.turned(q, m)                                 # D (m + θ × m)
        else:
            M, dM = (d.T @ m if self.following else m), np.zeros((3, n))
            if self.following:                                                # M = Σ m_j d_j
                for j, o in enumerate(self.triad):
                    dM[:, o:o + 3] = m[j] * np.eye(3)
        S = float(np.sum(d * d)) * np.eye(3) - d.T @ d
        W = np.linalg.solve(S, M)
        # ∂W/∂q = S⁻¹ (∂M/∂q − ∂S/∂q W), ∂S/∂(d_j)_c W = 2 d_jc W − e_c (d_j·W) − d_j W_c
        rhs = dM.copy()
        for j, o in enumerate(self.triad):
            rhs[:, o:o + 3] -= 2.0 * np.outer(W, d[j]) - (d[j] @ W) * np.eye(3) - np.outer(d[j], W)
        dW = np.linalg.solve(S, rhs)
        f, fq = np.zeros(n), np.zeros((n, n))
        for i, o in enumerate(self.triad):
            f[o:o + 3] = skew(W) @ d[i]                                       # f_i = −d_i × W
            fq[o:o + 3] = -skew(d[i]) @ dW
            fq[o:o + 3, o:o + 3] += skew(W)
        if self.elastic is not None:
            # the section's elastic rotation: Q_y = Θᵀ (d_i · M)_i
            Theta = self.elastic.Theta
            f[12:] += Theta.T @ (d @ M)
            fq[12:] += Theta.T @ (d @ dM)
            for i, o in enumerate(self.triad):
                fq[12:, o:o + 3] += np.outer(Theta[i], M)
        return f, fq, np.zeros((n, n))


class SpatialDistributedLoad(ForceElement):
    """A force per length f(t) (N/m) along a spatial beam, fixed in space or following its sections.

    Fixed in space: Q = Gᵀ f with G = ∫ N_a ds on every node's position (the consistent load of the beam's
    interpolation; its resultant is f L). Following: f = Σ_i f_i d_i(s) with the interpolated directors, so
    the load on node b's position is Σ_a (∫ N_b N_a ds) Σ_i f_i d_i^a, linear in q (Q = Σ_i f_i C_i q).

    Parameters
    ----------
    beam : SpatialExactBeam
    force : array_like (3,) or callable t -> (3,)
        N/m, in space axes, or with ``following=True`` in the section's axes (d₁, d₂, d₃).
    following : bool
    name : str
    """

    conservative = False

    def __init__(self, beam, force, following=False, name="distributed load"):
        if not callable(getattr(beam, "line_integral", None)):
            raise ValueError(f"a distributed load needs a spatial beam (SpatialExactBeam), got {beam!r}")
        self.force = time_function(force, 3, "force")
        self.following = bool(following)
        self.bodies = (beam,)
        self.G = beam.line_integral()
        if self.following:
            # C_i = P ⊗ E_i: node a's director d_i onto node b's position, weighted by P_ba = ∫ N_b N_a ds
            self._C = []
            for i in range(3):
                E = np.zeros((12, 12))
                E[0:3, 3 + 3 * i:6 + 3 * i] = np.eye(3)
                self._C.append(sps.kron(beam.node_products, E, format="csr"))
        self.name = name

    def generalized_force(self, q, v, t):
        n = self.G.shape[1]
        if not self.following:
            return self.G.T @ self.force(t), np.zeros((n, n)), np.zeros((n, n))
        C = sum(fi * Ci for fi, Ci in zip(self.force(t), self._C))
        return C @ q, C, None

    def compiled_form(self):
        """("generalized force", G, f): the point-load family (fixed in space); following: None (Python)."""
        if type(self).generalized_force is not SpatialDistributedLoad.generalized_force or self.following:
            return None
        return "generalized force", self.G, self.force


def distributed_moments(beam, moment, following=False, name="distributed moment"):
    """A moment per length m(t) (N m/m) along a spatial beam, as one :class:`SpatialMoment` per node carrying
    ∫ N_a ds · m (its consistent share of a uniform field). Returns the list of those force elements.

    Parameters
    ----------
    beam : SpatialExactBeam
    moment : array_like (3,) or callable t -> (3,)
        N m/m, in space axes, or with ``following=True`` in each node's section axes.
    following : bool
    name : str
    """
    if not callable(getattr(beam, "line_integral", None)):
        raise ValueError(f"a distributed moment needs a spatial beam (SpatialExactBeam), got {beam!r}")
    field = time_function(moment, 3, "moment")
    return [SpatialMoment(beam.point(float(s)), lambda t, w=float(w): w * field(t), following=following,
                          name=f"{name} at node {k}")
            for k, (s, w) in enumerate(zip(beam.s_nodes, beam.node_weights))]
