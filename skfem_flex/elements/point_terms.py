r"""Point and angle terms: the building blocks of joints and point force elements.

A *term* is a small function s(q) of the local coordinate vector of a
constraint or force element (the concatenated coordinate blocks of the
bodies it reads, laid out by :class:`PointLayout`): the position of a body
point, the difference of two points' positions (or of a point and a ground
point), a point's angle or a coordinate (linear), a constant, a vector
turned with a body, and the dot product of two terms. Each term gives

* ``value(q)``, shape (size,);
* ``jacobian(q)`` J = ∂s/∂q, shape (size, n);
* ``hessian(q, f)`` = ∂(Jᵀ f)/∂q, shape (n, n) (``None``-free: a zero block
  from :func:`~skfem_flex.bodies.base.zero_matrix`);
* ``dgrad(q0, q1)``, an exact discrete gradient D with
  D (q1 − q0) = s(q1) − s(q0), shape (size, n);
* ``dgrad_jacobian(q0, q1, f)`` = ∂(Dᵀ f)/∂q1 at fixed f, shape (n, n).

Products use Δ(f·g) = Δf·ḡ + f̄·Δg with f̄ the mean of the end values and
rotations use A(ϑ1) − A(ϑ0) = sinc(Δϑ/2) Δϑ A(ϑ_m) E, so a joint or a
spring built from terms has a discrete gradient that is exact to round-off
whatever the step (its force does no spurious work in the energy scheme).

The terms read bodies only through :class:`~skfem_flex.bodies.base.BodyPoint`
(``body.point(locator)``). :mod:`skfem_flex.elements.constraints` stacks them into
joint equations and :mod:`skfem_flex.elements.forces` builds springs, dampers and
point loads on them; both share this one implementation.
"""
from __future__ import annotations

import numpy as np

from ..bodies.base import BodyPoint, place_block, to_dense, zero_matrix
from ..bodies.rigid import E_MATRIX, rotation
from ..numerics.rotations import dsinc, sinc

__all__ = ["PointLayout", "Term", "Constant", "Position", "Difference", "Linear", "Rotated", "Dot",
           "angle_term", "linear_combination", "coordinate_term"]


# ============================================================== point layout
class PointLayout:
    """Bodies touched by a list of body points, each body once, and each point's slice of the local vector.

    A constraint or force element built on points names ``layout.bodies``
    as its ``bodies``; the scene then hands it the concatenation of those
    bodies' coordinate blocks (length ``layout.n``), and each point reads
    its body's block at ``layout.slices[k]``.

    Parameters
    ----------
    points : sequence of BodyPoint or None
        ``None`` stands for the ground (no coordinates).

    Attributes
    ----------
    bodies : tuple of Body
        The distinct bodies in order of first appearance.
    slices : list of slice or None
        Where each point's body block sits in the concatenated local vector.
    n : int
        Length of the local vector.
    """

    def __init__(self, points):
        self.bodies, self.slices = [], []
        offsets, start = [], 0
        for p in points:
            if p is None:
                self.slices.append(None)
                continue
            if not isinstance(p, BodyPoint):
                raise ValueError(f"expected a body point (body.point(...)) or None for the ground, got {p!r}")
            for b, o in zip(self.bodies, offsets):
                if b is p.body:
                    self.slices.append(slice(o, o + b.n_dofs))
                    break
            else:
                self.bodies.append(p.body)
                offsets.append(start)
                self.slices.append(slice(start, start + p.body.n_dofs))
                start += p.body.n_dofs
        self.bodies = tuple(self.bodies)
        self.n = start

    @classmethod
    def of_bodies(cls, bodies):
        """A layout over whole bodies (no points).

        Parameters
        ----------
        bodies : sequence of Body

        Returns
        -------
        PointLayout
            ``slices[k]`` is the block of ``bodies[k]``.
        """
        out = cls([])
        out.bodies = tuple(bodies)
        out.slices, start = [], 0
        for b in out.bodies:
            out.slices.append(slice(start, start + b.n_dofs))
            start += b.n_dofs
        out.n = start
        return out

    def initial(self):
        """The concatenated initial coordinates q0 of the bodies.

        Returns
        -------
        ndarray, shape (n,)
        """
        if not self.bodies:
            return np.zeros(0)
        return np.concatenate([np.asarray(b.q0, dtype=float) for b in self.bodies])


# ===================================================================== terms
class Term:
    """A vector- (size 2) or scalar-valued (size 1) function s(q) of the local coordinates.

    Subclasses implement :meth:`value`, :meth:`jacobian`, :meth:`hessian`,
    :meth:`dgrad` and :meth:`dgrad_jacobian`.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector q (``PointLayout.n``).

    Attributes
    ----------
    size : int
        Length of the value: 2 (a vector in the plane) or 1 (a scalar).
    linear : bool
        True when s is affine in q: then the Hessian products vanish and the
        constant Jacobian is an exact discrete gradient.
    """

    size = 2
    linear = False

    def __init__(self, n):
        self.n = n

    def value(self, q):
        """s(q), shape (size,)."""
        raise NotImplementedError

    def jacobian(self, q):
        """J = ∂s/∂q, shape (size, n)."""
        raise NotImplementedError

    def hessian(self, q, f):
        """∂(Jᵀ f)/∂q for a fixed f of shape (size,), shape (n, n)."""
        raise NotImplementedError

    def dgrad(self, q0, q1):
        """Exact discrete gradient D, shape (size, n): D (q1 − q0) = s(q1) − s(q0)."""
        raise NotImplementedError

    def dgrad_jacobian(self, q0, q1, f):
        """∂(Dᵀ f)/∂q1 for a fixed f of shape (size,), shape (n, n)."""
        raise NotImplementedError

    def mean(self, q0, q1):
        """½ (s(q0) + s(q1)), the mean of the end values the product rule needs."""
        return 0.5 * (self.value(q0) + self.value(q1))

    def compiled_form(self):
        """How the compiled mechanism loop (the element families of :mod:`skfem_flex.compiled.families`) evaluates this term,
        or None (the default: a constraint with such a term runs on the Python path).

        ``("constant", c)``; ``("points", [(point, sign), ...], c)`` for Σ sign · r(point) − c;
        ``("linear", g, c)`` for g · q + c (g over the local coordinates);
        ``("projected", nrm, points)`` for nrm · (a ``"points"`` form), a constant normal;
        ``("rotated", g, c, n_loc)`` for A(g · q + c) n_loc; ``("rotated projected", g, c, n_loc, points)``
        for that normal times a ``"points"`` form.
        """
        return None

    def _zero(self):
        return zero_matrix(self.n)


class Constant(Term):
    """A constant vector or scalar c (a ground line's normal, say).

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    c : array_like
        The value; its length is the term's ``size``.
    """

    linear = True

    def __init__(self, n, c):
        super().__init__(n)
        self.c = np.atleast_1d(np.asarray(c, dtype=float))
        self.size = self.c.size

    def value(self, q):
        return self.c.copy()

    def jacobian(self, q):
        return np.zeros((self.size, self.n))

    def hessian(self, q, f):
        return self._zero()

    def dgrad(self, q0, q1):
        return np.zeros((self.size, self.n))

    def dgrad_jacobian(self, q0, q1, f):
        return self._zero()

    def compiled_form(self):
        return "constant", self.c.copy()


class Position(Term):
    """r(q), the global position of a body point (m).

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    point : BodyPoint
    sl : slice
        The point's body block in the local vector (``PointLayout.slices``).
    """

    def __init__(self, n, point, sl):
        super().__init__(n)
        self.point, self.sl = point, sl

    def value(self, q):
        return np.asarray(self.point.position(q[self.sl]), dtype=float)

    def jacobian(self, q):
        out = np.zeros((2, self.n))
        out[:, self.sl] = to_dense(self.point.position_jacobian(q[self.sl]))
        return out

    def hessian(self, q, f):
        return place_block(self.n, self.sl, self.point.position_hessian_product(q[self.sl], f))

    def dgrad(self, q0, q1):
        out = np.zeros((2, self.n))
        out[:, self.sl] = to_dense(self.point.position_discrete_gradient(q0[self.sl], q1[self.sl]))
        return out

    def dgrad_jacobian(self, q0, q1, f):
        return place_block(self.n, self.sl,
                           self.point.position_discrete_gradient_jacobian(q0[self.sl], q1[self.sl], f))


class Difference(Term):
    """r_a(q) − r_b(q) of two body points, or r_a(q) − a for a ground point a.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    point_a : BodyPoint
    sl_a : slice
        Block of ``point_a``'s body in the local vector.
    point_b : BodyPoint, optional
    sl_b : slice, optional
        Block of ``point_b``'s body.
    anchor : array_like, shape (2,), optional
        The ground point a (m); exactly one of ``point_b`` and ``anchor``.

    Raises
    ------
    ValueError
        When both or neither of ``point_b`` and ``anchor`` are given.
    """

    def __init__(self, n, point_a, sl_a, point_b=None, sl_b=None, anchor=None):
        super().__init__(n)
        self.pa, self.sa, self.pb, self.sb = point_a, sl_a, point_b, sl_b
        self.anchor = None if anchor is None else np.asarray(anchor, dtype=float)
        if (point_b is None) == (anchor is None):
            raise ValueError("a point difference needs exactly one of a second point and a ground anchor")

    def value(self, q):
        ra = np.asarray(self.pa.position(q[self.sa]), dtype=float)
        if self.pb is None:
            return ra - self.anchor
        return ra - np.asarray(self.pb.position(q[self.sb]), dtype=float)

    def jacobian(self, q):
        out = np.zeros((2, self.n))
        out[:, self.sa] = to_dense(self.pa.position_jacobian(q[self.sa]))
        if self.pb is not None:
            out[:, self.sb] -= to_dense(self.pb.position_jacobian(q[self.sb]))
        return out

    def hessian(self, q, f):
        out = place_block(self.n, self.sa, self.pa.position_hessian_product(q[self.sa], f))
        if self.pb is not None:
            out = place_block(self.n, self.sb, self.pb.position_hessian_product(q[self.sb], f), -1.0, out)
        return out

    def dgrad(self, q0, q1):
        out = np.zeros((2, self.n))
        out[:, self.sa] = to_dense(self.pa.position_discrete_gradient(q0[self.sa], q1[self.sa]))
        if self.pb is not None:
            out[:, self.sb] -= to_dense(self.pb.position_discrete_gradient(q0[self.sb], q1[self.sb]))
        return out

    def dgrad_jacobian(self, q0, q1, f):
        out = place_block(self.n, self.sa, self.pa.position_discrete_gradient_jacobian(q0[self.sa], q1[self.sa], f))
        if self.pb is not None:
            out = place_block(self.n, self.sb, self.pb.position_discrete_gradient_jacobian(q0[self.sb], q1[self.sb], f),
                              -1.0, out)
        return out

    def compiled_form(self):
        if self.pb is None:
            return "points", [(self.pa, 1.0)], self.anchor.copy()
        return "points", [(self.pa, 1.0), (self.pb, -1.0)], np.zeros(2)


class Linear(Term):
    """A scalar affine in q: a point's angle, a coordinate or a combination of them.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    fun : callable
        ``fun(q)`` → float, the value.
    grad : array_like, shape (n,)
        Its constant gradient (also its exact discrete gradient).

    Attributes
    ----------
    fun, grad
        As given; force elements read them directly (a rotational spring's
        relative angle and its gradient).
    """

    size = 1
    linear = True

    def __init__(self, n, fun, grad):
        super().__init__(n)
        self.fun, self.grad = fun, np.asarray(grad, dtype=float)

    def value(self, q):
        return np.array([float(self.fun(q))])

    def jacobian(self, q):
        return self.grad[None, :].copy()

    def hessian(self, q, f):
        return self._zero()

    def dgrad(self, q0, q1):
        return self.grad[None, :].copy()

    def dgrad_jacobian(self, q0, q1, f):
        return self._zero()

    def compiled_form(self):
        # affine: s(q) = g · q + s(0)
        return "linear", self.grad.copy(), float(self.fun(np.zeros(self.n)))


def angle_term(n, point, sl):
    """ϑ(q), the angle of a body point (rad), as a :class:`Linear` term.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    point : BodyPoint
        A point with an angle (rigid body, beam section).
    sl : slice
        The point's body block in the local vector.

    Returns
    -------
    Linear
        Its gradient is the point's angle Jacobian at the body's q0 (constant:
        every body's angle is linear in its coordinates).

    Raises
    ------
    ValueError
        The body's own error when the point has no angle (a point mass).
    """
    if not point.has_angle:
        point.angle(point.body.q0)          # raises the body's own "has no angle" ValueError
    q0 = np.asarray(point.body.q0, dtype=float)
    grad = np.zeros(n)
    grad[sl] = to_dense(point.angle_jacobian(q0)).ravel()
    return Linear(n, lambda q: point.angle(q[sl]), grad)


def linear_combination(n, terms, coefs, const=0.0):
    """Σ c_i s_i − const of :class:`Linear` terms, as one :class:`Linear` (gradient summed once).

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    terms : sequence of Linear
    coefs : sequence of float
        c_i, one per term.
    const : float

    Returns
    -------
    Linear
    """
    terms, coefs = list(terms), [float(c) for c in coefs]
    grad = sum(c * t.grad for c, t in zip(coefs, terms))
    const = float(const)

    def fun(q):
        return sum(c * t.fun(q) for c, t in zip(coefs, terms)) - const
    return Linear(n, fun, grad)


def coordinate_term(n, index):
    """q[index], one local coordinate, as a :class:`Linear` term.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    index : int
        Position of the coordinate in the local vector.

    Returns
    -------
    Linear
    """
    grad = np.zeros(n)
    grad[index] = 1.0
    return Linear(n, lambda q: q[index], grad)


class Rotated(Term):
    """n(q) = A(ϑ(q)) n_loc: a vector fixed in the frame of a body point.

    The discrete gradient uses A(ϑ1) − A(ϑ0) = sinc(Δϑ/2) Δϑ A(ϑ_m) E, exact
    for any increment Δϑ.

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    angle : Linear
        ϑ(q), e.g. from :func:`angle_term`.
    local : array_like, shape (2,)
        n_loc, the vector at ϑ = 0.
    """

    def __init__(self, n, angle, local):
        super().__init__(n)
        self.angle, self.local = angle, np.asarray(local, dtype=float)
        self.g = angle.grad

    def value(self, q):
        return rotation(self.angle.value(q)[0]) @ self.local

    def jacobian(self, q):
        return np.outer(E_MATRIX @ self.value(q), self.g)

    def hessian(self, q, f):
        return -float(f @ self.value(q)) * np.outer(self.g, self.g)

    def _half(self, q0, q1):
        t0, t1 = self.angle.value(q0)[0], self.angle.value(q1)[0]
        half = 0.5 * (t1 - t0)
        return half, rotation(t0 + half)

    def dgrad(self, q0, q1):
        half, am = self._half(q0, q1)
        return np.outer(sinc(half) * (am @ (E_MATRIX @ self.local)), self.g)

    def compiled_form(self):
        # the angle is affine in q: ϑ = g · q + ϑ(0)
        return "rotated", self.g.copy(), float(self.angle.value(np.zeros(self.n))[0]), self.local.copy()

    def dgrad_jacobian(self, q0, q1, f):
        half, am = self._half(q0, q1)
        c = 0.5 * (dsinc(half) * float(f @ (am @ (E_MATRIX @ self.local))) - sinc(half) * float(f @ (am @ self.local)))
        return c * np.outer(self.g, self.g)


class Dot(Term):
    """u · v of two 2-vector terms, a scalar.

    The exact discrete gradient is the product rule on the mean end values,
    Δ(u·v) = ū·Δv + v̄·Δu (ū = ½ (u(q0) + u(q1))).

    Parameters
    ----------
    n : int
        Length of the local coordinate vector.
    u, v : Term
        Terms of size 2 (may be the same term: |d|² = d · d).
    """

    size = 1

    def __init__(self, n, u, v):
        super().__init__(n)
        self.u, self.v = u, v
        self.linear = (u.linear and isinstance(v, Constant)) or (v.linear and isinstance(u, Constant))

    def value(self, q):
        return np.array([float(self.u.value(q) @ self.v.value(q))])

    def jacobian(self, q):
        return (self.u.value(q) @ self.v.jacobian(q) + self.v.value(q) @ self.u.jacobian(q))[None, :]

    def hessian(self, q, f):
        uu, vv = self.u.value(q), self.v.value(q)
        ju, jv = self.u.jacobian(q), self.v.jacobian(q)
        cross = ju.T @ jv
        return f[0] * (self.v.hessian(q, uu) + self.u.hessian(q, vv) + cross + cross.T)

    def dgrad(self, q0, q1):
        ub, vb = self.u.mean(q0, q1), self.v.mean(q0, q1)
        return (ub @ self.v.dgrad(q0, q1) + vb @ self.u.dgrad(q0, q1))[None, :]

    def dgrad_jacobian(self, q0, q1, f):
        ub, vb = self.u.mean(q0, q1), self.v.mean(q0, q1)
        out = self.v.dgrad_jacobian(q0, q1, ub) + self.u.dgrad_jacobian(q0, q1, vb)
        out += 0.5 * (self.v.dgrad(q0, q1).T @ self.u.jacobian(q1) + self.u.dgrad(q0, q1).T @ self.v.jacobian(q1))
        return f[0] * out

    def compiled_form(self):
        # a constant or turning normal on a point difference (a slider on a ground line or on a body)
        for a, b in ((self.u, self.v), (self.v, self.u)):
            fa, fb = a.compiled_form(), b.compiled_form()
            if fa is None or fb is None or fb[0] != "points":
                continue
            if fa[0] == "constant" and fa[1].size == 2:
                return "projected", fa[1], fb
            if fa[0] == "rotated":
                return ("rotated projected",) + fa[1:] + (fb,)
        return None
