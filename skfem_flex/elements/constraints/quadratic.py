r"""Constraints quadratic in q: the rigidity of spatial bodies and every spatial joint.

Each equation k is a polynomial of degree two in the constraint's local coordinates q,

.. math::  Φ_k(q, t) = \tfrac12\, q^T H_k\, q + b_k \cdot q + c_k - s_k(t),

with a symmetric H_k and an optional motion law s_k(t). Then Φ_q = H q + b, the Hessian product is
Σ μ_k H_k, and the mid-point Jacobian D = H (q₀ + q₁)/2 + b is an *exact* discrete gradient:
D (q₁ − q₀) = Φ(q₁) − Φ(q₀) for any step. The energy–momentum scheme therefore lets no spatial joint do
work. Between affine vectors (rigid bodies, beam nodes, a floating frame's own points) every equation is
invariant under a common rotation of all position vectors (dot products and differences of points and
directors), and its mid-point gradient conserves the angular momentum too.

At a floating-frame body's material point (quadratic in q) an equation may gain products of two quadratic
invariants, Φ_k + Σ_m a_m s_m (:mod:`.product_rows`, with the product rule's exact discrete gradient): a
material direction against a moving one, a difference of points dotted with a direction. The coincidence of
such a point with another, r_a − r_b = 0, stays quadratic but is not an invariant: its mid-point gradient
keeps the energy and the linear momentum, the angular momentum to O(Δt²).

Equations are built from *affine vectors* u(q) = A q + a (:class:`Affine`: a body point, a body-fixed
direction, a ground point or direction): ``u.equals(w)`` gives three linear equations,
``u.dot(w, value)`` the quadratic u·w − value.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ...bodies.base import DENSE_LIMIT, check_finite_vector
from ..motion import MotionLaw
from ..point_terms import PointLayout
from .base import Constraint
from .product_rows import PolynomialRows, ProductRows, product_dot

__all__ = ["Affine", "QuadraticConstraint", "Rigidity", "UnitQuaternion", "spatial_reaction", "unit_vector", "perpendiculars", "stack",
           "hinge_directions"]


def unit_vector(name, vec):
    """``vec`` (3,) scaled to unit length, or ``ValueError`` for a zero or non-finite one."""
    vec = check_finite_vector(name, vec, 3)
    nrm = float(np.linalg.norm(vec))
    if nrm < 1e-300:
        raise ValueError(f"{name} must not have zero length, got {vec!r}")
    return vec / nrm


def hinge_directions(body_a, body_b, axis):
    """The directions a hinge angle about ``axis`` is read from, over the bodies' coordinates.

    Returns (layout, u, n₁, n₂): the :class:`~..point_terms.PointLayout` of body a (and b), u the direction
    of the turning body (b, or a against the ground when ``body_b`` is None) that lies along n₁ at the start,
    and n₁, n₂ perpendicular to the axis, fixed in body a (or in space), as :class:`Affine` vectors; the
    angle is atan2(u·n₂, u·n₁). ``ValueError`` for a body without directors or an axis of zero length.
    """
    for nm, b in (("body_a", body_a), ("body_b", body_b)):
        if b is not None and not hasattr(b, "axis"):
            raise ValueError(f"{nm} must be a spatial rigid body (with directors), got {b!r}")
    n1, n2 = perpendiculars(unit_vector("axis", axis))
    layout = PointLayout.of_bodies([body_a] if body_b is None else [body_a, body_b])
    n = layout.n

    def direction(k, vec):
        body = layout.bodies[k]
        return Affine.of(body.axis(body.body_direction(vec)), layout.slices[k], n)

    if body_b is None:
        return layout, direction(0, n1), Affine.constant(n1, n), Affine.constant(n2, n)
    return layout, direction(1, n1), direction(0, n1), direction(0, n2)


def perpendiculars(e):
    """Two unit vectors that make (e, n₁, n₂) a right-handed orthonormal triad (e a unit vector)."""
    k = int(np.argmin(np.abs(e)))
    n1 = np.cross(e, np.eye(3)[k])
    n1 /= np.linalg.norm(n1)
    return n1, np.cross(e, n1)


class Affine:
    """u(q) = A q + a, a 3-vector affine in the local coordinates (A (3, n), a (3,)); with ``H`` (3, n, n) the
    quadratic u_c(q) = ½ qᵀ H_c q + A_c·q + a_c (a point of a floating-frame body, x + D(X₀ + S y))."""

    def __init__(self, A, a, H=None, factors=None):
        self.A = np.asarray(A, dtype=float)
        self.a = np.asarray(a, dtype=float).reshape(3)
        self.H = None if H is None else np.asarray(H, dtype=float)
        #: the factored form (A₀, a₀, ((β_j, γ_j, W_j), ...)) of a quadratic vector, u = A₀q + a₀ + Σ (β_j·q + γ_j) W_j q
        #: (:func:`~.product_rows.product_dot`), or None
        self.factors = factors

    def _factored(self):
        """(A₀, a₀, terms): an affine vector is its own (A, a, ()); a quadratic one without factors gives None."""
        return (self.A, self.a, ()) if self.H is None else self.factors

    @classmethod
    def constant(cls, vec, n):
        """A ground point or a fixed direction in space."""
        return cls(np.zeros((3, n)), vec)

    @classmethod
    def of(cls, body_affine, where, n):
        """A body point's or axis' (A_b, a_b) (``.affine()``, body-local) placed at ``where`` of n columns; a
        point whose position is quadratic in q gives (H_b, A_b, a_b) by ``.quadratic()`` instead."""
        quadratic = getattr(body_affine, "quadratic", None)
        if quadratic is None:
            H_b = None
            A_b, a_b = body_affine.affine()
        else:
            H_b, A_b, a_b = quadratic()
        A = np.zeros((3, n))
        A[:, where] = A_b
        if H_b is None:
            return cls(A, a_b)
        H = np.zeros((3, n, n))
        H[:, where, where] = H_b
        factored = getattr(body_affine, "factored", None)
        factors = None
        if factored is not None:
            A0_b, a0_b, terms_b = factored()
            A0 = np.zeros((3, n))
            A0[:, where] = A0_b
            terms = []
            for beta_b, gamma, W_b in terms_b:
                beta, W = np.zeros(n), np.zeros((3, n))
                beta[where], W[:, where] = beta_b, W_b
                terms.append((beta, float(gamma), W))
            factors = (A0, np.asarray(a0_b, dtype=float), tuple(terms))
        return cls(A, a_b, H, factors)

    def _second(self, n):
        return np.zeros((3, n, n)) if self.H is None else self.H

    def __sub__(self, other):
        H = None if self.H is None and other.H is None else self._second(self.A.shape[1]) - other._second(
            other.A.shape[1])
        fu, fw = self._factored(), other._factored()
        factors = None
        if H is not None and fu is not None and fw is not None:
            factors = (fu[0] - fw[0], fu[1] - fw[1], fu[2] + tuple((beta, gamma, -W) for beta, gamma, W in fw[2]))
        return Affine(self.A - other.A, self.a - other.a, H, factors)

    def value(self, q):
        out = self.A @ q + self.a
        return out if self.H is None else out + 0.5 * np.einsum("cij,i,j->c", self.H, q, q)

    def equals(self, other):
        """Three equations u − w = 0 (linear, or quadratic for quadratic points): (H, b, c) stacks."""
        d = self - other
        return d._second(d.A.shape[1]).copy(), d.A.copy(), d.a.copy()

    def _constant(self):
        return self.H is None and not self.A.any()

    def dot(self, other, value=0.0):
        """One equation u·w − value = 0 as :class:`~.product_rows.PolynomialRows` (H, b, c, products) with one
        row: quadratic when both u and w are affine, or one is quadratic and the other constant (a direction of
        a floating-frame body's material point against a direction fixed in space); a sum of products of two
        quadratic invariants when a quadratic vector meets a moving one (:mod:`.product_rows`)."""
        if self.H is not None or other.H is not None:
            quad, fixed = (self, other) if other._constant() else (other, self) if self._constant() else (None, None)
            if quad is None:
                fu, fw = self._factored(), other._factored()
                if fu is None or fw is None:
                    raise ValueError("a dot product of a quadratic vector with a moving one needs the vectors' "
                                     "factored form (a floating-frame body's ElasticPoint gives it): this one has none")
                return product_dot(fu, fw, value)
            H = np.einsum("c,cij->ij", fixed.a, quad.H)
            return PolynomialRows(H[None], (fixed.a @ quad.A)[None], np.array([quad.a @ fixed.a - float(value)]))
        H = self.A.T @ other.A + other.A.T @ self.A
        b = self.a @ other.A + other.a @ self.A
        return PolynomialRows(H[None], b[None], np.array([self.a @ other.a - float(value)]))


def stack(parts):
    """Concatenate (H, b, c) or :class:`~.product_rows.PolynomialRows` parts into one
    :class:`~.product_rows.PolynomialRows` (the product terms' rows renumbered)."""
    products, row = [], 0
    for p in parts:
        products += [t._replace(row=t.row + row) for t in (p.products if isinstance(p, PolynomialRows) else ())]
        row += len(p[2])
    return PolynomialRows(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
                          np.concatenate([p[2] for p in parts]), tuple(products))


def _law(law, name):
    if law is None or isinstance(law, MotionLaw):
        return law
    raise ValueError(f"{name} must be a MotionLaw (x(t), ẋ(t), ẍ(t)) or None, got {law!r}")


class QuadraticConstraint(Constraint):
    """Equations Φ_k = ½ qᵀ H_k q + b_k·q + c_k − s_k(t), plus Σ_m a_m(q) s_m(q) on rows with product terms
    (module docstring).

    Parameters
    ----------
    bodies : sequence of Body
        The bodies whose concatenated coordinate blocks are the local q.
    H : array_like (m, n, n)
        Symmetric second derivatives (made symmetric here).
    b : array_like (m, n)
    c : array_like (m,)
    laws : sequence of MotionLaw or None, optional
        s_k(t) per equation (None: no time term).
    name : str
    columns : array_like of int, optional
        The local coordinates the equations touch (default: all of them); H is then (m, k, k) and b (m, k)
        over these k columns only, which keeps the equations of one node of a long beam small.
    products : sequence of ProductTerm, optional
        Terms a_m(q) s_m(q) added to their rows, over all n local coordinates (:mod:`.product_rows`: axes at
        floating-frame material points against moving bodies). The equations are then not quadratic: their
        discrete gradient is the product rule's, and the product-rows family packs them.
    """

    quadratic = True
    #: the product terms (:class:`~.product_rows.ProductRows` over the columns), or None
    products = None

    def __init__(self, bodies, H, b, c, laws=None, name="quadratic constraint", columns=None, products=()):
        self.layout = PointLayout.of_bodies(bodies)
        self.bodies = self.layout.bodies
        H = np.asarray(H, dtype=float)
        self.H = 0.5 * (H + np.transpose(H, (0, 2, 1)))
        self.b = np.asarray(b, dtype=float)
        self.c = np.asarray(c, dtype=float).ravel()
        m, k = self.b.shape
        n = self.layout.n
        self.products = None
        if products:
            if columns is not None or self.H.shape != (m, n, n):
                raise ValueError(f"quadratic constraint {name!r}: product terms need H over all {n} coordinates")
            self.products = ProductRows(products, m, n)
            self.quadratic = False
        if columns is None and self.H.shape == (m, n, n):
            # only the coordinates the equations touch (a joint at one node of a long beam touches 12 of them)
            touched = np.any(self.H != 0.0, axis=(0, 1)) | np.any(self.b != 0.0, axis=0)
            if self.products is not None:
                touched |= self.products.columns()
            touched = np.flatnonzero(touched)
            if touched.size < n:
                self.H, self.b = self.H[:, touched][:, :, touched], self.b[:, touched]
                if self.products is not None:
                    self.products = self.products.restricted(touched)
                columns, k = touched, touched.size
        self.columns = np.arange(n) if columns is None else np.asarray(columns, dtype=np.int64).ravel()
        if (self.H.shape != (m, k, k) or self.c.shape != (m,) or self.columns.size != k
                or (self.columns.size and (self.columns.min() < 0 or self.columns.max() >= n))):
            raise ValueError(f"quadratic constraint {name!r}: H {self.H.shape}, b {self.b.shape}, c {self.c.shape} "
                             f"do not match {m} equations on {k} of the {n} coordinates")
        self._full = bool(np.array_equal(self.columns, np.arange(n)))
        if not (np.all(np.isfinite(self.H)) and np.all(np.isfinite(self.b)) and np.all(np.isfinite(self.c))):
            raise ValueError(f"quadratic constraint {name!r} has non-finite coefficients")
        self.laws = [None] * m if laws is None else [_law(law, f"{name}: laws[{k}]") for k, law in enumerate(laws)]
        if len(self.laws) != m:
            raise ValueError(f"quadratic constraint {name!r}: {len(self.laws)} laws for {m} equations")
        self.rheonomic = any(law is not None for law in self.laws)
        self.n_equations = m
        self.name = name

    def _law_values(self, t, k):
        return np.array([0.0 if law is None else float(law(t)[k]) for law in self.laws])

    def _wide(self, rows):
        """(m, k) rows over the columns placed into (m, n)."""
        if self._full:
            return rows
        out = np.zeros(rows.shape[:-1] + (self.layout.n,))
        out[..., self.columns] = rows
        return out

    def value(self, q, t):
        q = np.asarray(q, dtype=float)[self.columns]
        out = 0.5 * np.einsum("kij,i,j->k", self.H, q, q) + self.b @ q + self.c - (
            self._law_values(t, 0) if self.rheonomic else 0.0)
        return out if self.products is None else out + self.products.value(q)

    def jacobian(self, q, t):
        q = np.asarray(q, dtype=float)[self.columns]
        rows = self.H @ q + self.b
        return self._wide(rows if self.products is None else rows + self.products.jacobian(q))

    def hessian_product(self, q, mu, t):
        mu = np.asarray(mu, dtype=float)
        local = np.tensordot(mu, self.H, axes=1)
        if self.products is not None:
            local = local + self.products.hessian_product(np.asarray(q, dtype=float)[self.columns], mu)
        return self._square(local)

    def _square(self, local):
        """A (k, k) matrix over the columns placed into (n, n) (dense, or sparse for a long beam)."""
        if self._full:
            return local
        n = self.layout.n
        if n <= DENSE_LIMIT:
            out = np.zeros((n, n))
            out[np.ix_(self.columns, self.columns)] = local
            return out
        k = self.columns.size
        rows = np.repeat(self.columns, k)
        return sps.csr_matrix((local.ravel(), (rows, np.tile(self.columns, k))), shape=(n, n))

    def velocity_jacobian(self, q, v, t):
        v = np.asarray(v, dtype=float)[self.columns]
        rows = self.H @ v
        if self.products is not None:
            rows = rows + self.products.velocity_jacobian(np.asarray(q, dtype=float)[self.columns], v)
        return self._wide(rows)

    def time_derivative(self, q, t):
        return -self._law_values(t, 1) if self.rheonomic else np.zeros(self.n_equations)

    def time_terms(self, q, v, t):
        return -self._law_values(t, 2) if self.rheonomic else np.zeros(self.n_equations)

    def discrete_gradient(self, q0, q1, t):
        q0, q1 = np.asarray(q0, dtype=float)[self.columns], np.asarray(q1, dtype=float)[self.columns]
        rows = self.H @ (0.5 * (q0 + q1)) + self.b
        return self._wide(rows if self.products is None else rows + self.products.discrete_gradient(q0, q1))

    def discrete_gradient_jacobian(self, q0, q1, mu, t):
        mu = np.asarray(mu, dtype=float)
        local = 0.5 * np.tensordot(mu, self.H, axes=1)
        if self.products is not None:
            local = local + self.products.discrete_gradient_jacobian(np.asarray(q0, dtype=float)[self.columns],
                                                                     np.asarray(q1, dtype=float)[self.columns], mu)
        return self._square(local)

    def without_equations(self, rows):
        """A copy without the equations ``rows`` (indices), e.g. redundant ones
        (:func:`~skfem_flex.scene_initial.drop_redundant_constraints`); same name and reaction."""
        import copy

        keep = np.setdiff1d(np.arange(self.n_equations), np.asarray(rows, dtype=int))
        new = copy.copy(self)
        new.H, new.b, new.c = self.H[keep], self.b[keep], self.c[keep]
        new.laws = [self.laws[k] for k in keep]
        if self.products is not None:
            new.products = self.products.without_rows(keep)
            if not new.products.terms:          # every product row dropped: quadratic again
                new.products, new.quadratic = None, True
        new.rheonomic = any(law is not None for law in new.laws)
        new.n_equations = int(keep.size)
        return new

    def compiled_form(self):
        """``("quadratic", H, b, c, laws, columns)``: the quadratic-rows family packs it; with product terms
        ``("product", H, b, c, laws, columns, products)`` for the product-rows family."""
        if type(self).value is not QuadraticConstraint.value:
            return None
        if self.products is not None:
            return "product", self.H, self.b, self.c, tuple(self.laws), self.columns, self.products
        return "quadratic", self.H, self.b, self.c, tuple(self.laws), self.columns


def _cross(a, b):
    """Row-wise a × b of (N, 3) arrays (np.cross is slow on small arrays: it moves axes per call)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def spatial_reaction(constraint, body, where, point, q, lam):
    """Force (3,) N and moment (3,) N m that ``constraint`` exerts on ``body`` (its block at ``where`` of the
    local q), from f = −Φ_qᵀλ on the body's coordinates: F = Σ f_x over its position vectors x (the centre
    of mass, or a beam's nodes) and the moment about ``point`` (a body point at r),
    M = Σ d × f_d over its directors + Σ (x − r) × f_x (``body.vector_layout()``). A body turning about a
    pivot has no x: the pivot takes the force, F is reported 0 and M is the moment about the pivot.

    ``q`` (N, n) and ``lam`` (N, m) give (N, 6), one row per state; ``q`` (n,) and ``lam`` (m,) give (6,).
    """
    q, lam = np.asarray(q, dtype=float), np.asarray(lam, dtype=float)
    one = q.ndim == 1
    q, lam = np.atleast_2d(q), np.atleast_2d(lam)
    qc = q[:, constraint.columns]
    local = np.einsum("kij,Nj->Nki", constraint.H, qc) + constraint.b
    if getattr(constraint, "products", None) is not None:
        local = local + constraint.products.jacobians(qc)
    jac = constraint._wide(local)
    f = -np.einsum("Nk,Nki->Ni", lam, jac)[:, where]
    qb = q[:, where]
    positions, directors = body.vector_layout()
    M = np.zeros((q.shape[0], 3))
    F = np.zeros((q.shape[0], 3))
    for o in directors:
        M += _cross(qb[:, o:o + 3], f[:, o:o + 3])
    r = qb @ point.G.T + point.a if hasattr(point, "G") else np.array([point.position(row) for row in qb])
    for o in positions:
        F += f[:, o:o + 3]
        M += _cross(qb[:, o:o + 3] - r, f[:, o:o + 3])
    out = np.concatenate([F, M], axis=1)
    return out[0] if one else out


class Rigidity(QuadraticConstraint):
    """The six rigidity equations of a triad of directors: ½(d_i·d_i − 1) = 0, d_i·d_j = 0 (i < j).

    The scene adds one for every triad a body names in ``director_triads`` (the local offsets of d₁, d₂,
    d₃): a spatial rigid body has one, a spatial beam one per node. The equations touch only the triad's
    nine coordinates.
    """

    reaction_labels = ("N11", "N22", "N33", "N12", "N13", "N23")

    def __init__(self, body, triad=None, name=None):
        offs = tuple(int(o) for o in (body.directors if triad is None else triad))
        columns = np.concatenate([np.arange(o, o + 3) for o in offs])
        H, c = np.zeros((6, 9, 9)), np.zeros(6)
        pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
        for k, (i, j) in enumerate(pairs):
            for a in range(3):
                H[k, 3 * i + a, 3 * j + a] += 1.0
                H[k, 3 * j + a, 3 * i + a] += 1.0
            if i == j:
                H[k] *= 0.5
                c[k] = -0.5
        super().__init__([body], H, np.zeros((6, 9)), c, name=name or f"{body.name}: rigidity",
                         columns=columns)
        self.pairs, self.triad = pairs, offs

    @classmethod
    def of_body(cls, body, prescribed=None):
        """The rigidity of each of ``body``'s director triads (``director_triads``), without the equations whose
        six coordinates are all prescribed (``prescribed``: {local index: value at t = 0} of the body's
        coordinates that follow motion laws).

        A frame driven by its laws (:func:`~skfem_flex.elements.motion.driven_frame`) is kept orthonormal by
        them: its equations would be rows without an unknown, which no multiplier can enforce and which make
        the Newton matrix singular. The laws must hold them at the start (checked here) and at every time
        (the caller's promise; ``driven_frame``'s laws do).

        Raises
        ------
        ValueError
            If the prescribed coordinates of a triad do not satisfy its equations at the body's initial state.
        """
        start = {int(k): float(x) for k, x in (prescribed or {}).items()}
        out = []
        triads = tuple(getattr(body, "director_triads", ()))
        for k, triad in enumerate(triads):
            name = f"{body.name}: rigidity" + (f" of node {k}" if len(triads) > 1 else "")
            r = cls(body, triad, name=name)
            held = [e for e, (i, j) in enumerate(r.pairs)
                    if all(o + a in start for o in (r.triad[i], r.triad[j]) for a in range(3))]
            d = np.array([start.get(int(col), body.q0[col]) for col in r.columns])
            bad = [e for e in held if abs(0.5 * d @ r.H[e] @ d + r.c[e]) > 1e-9]
            if bad:
                raise ValueError(f"the prescribed directors of {name!r} are not orthonormal at the start: equation(s) "
                                 f"{bad} of (d1·d1, d2·d2, d3·d3, d1·d2, d1·d3, d2·d3) miss by more than 1e-9")
            if len(held) < 6:
                out.append(r.without_equations(held) if held else r)
        return out


class UnitQuaternion(QuadraticConstraint):
    """The one equation ½(e·e − 1) = 0 of a body's Euler parameters e at local offset ``offset``.

    The scene adds one for every offset a body names in ``unit_quaternions``
    (:class:`~skfem_flex.bodies.quaternion.QuaternionRigidBody`). A turn of the body or of space multiplies
    e by a unit quaternion, an orthogonal map of R⁴ that keeps this equation: its mid-point gradient
    conserves every angular momentum component the other forces leave free.
    """

    reaction_labels = ("N",)

    def __init__(self, body, offset, name=None):
        o = int(offset)
        super().__init__([body], np.eye(4)[None], np.zeros((1, 4)), [-0.5], name=name or f"{body.name}: unit quaternion",
                         columns=np.arange(o, o + 4))
