"""The face every body shows the scene.

A body owns a block of generalized coordinates q (length ``n_dofs``) with
velocities v. The scene concatenates the blocks; integrators only ever talk
to the scene, so a body knows nothing of integrators (docs/ARCHITECTURE.md, the body contract).

A body supplies

* kinetic energy T(q, v) = ½ vᵀ M(q) v and momentum p = M(q) v;
  constant-mass bodies set ``constant_mass = True`` and only implement
  :meth:`Body.mass_matrix` (the scene then builds M once and skips the rest);
* potential energy V(q) (strain energy; gravity comes through
  :meth:`Body.gravity_potential`), its gradient and Hessian;
* discrete gradients for the energy-conserving scheme: of V between q0 and
  q1, and of G(q) = ½ v0ᵀ M(q) v1 (zero for constant M), each with its
  derivative with respect to the end state;
* linear and angular momentum (planar, about the global origin) where they
  make sense, and geometry for output.

Array conventions: vectors are 1-D float arrays of the body's own length;
matrices are dense ``ndarray`` or ``scipy.sparse`` (the scene accepts both).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Body", "BodyGeometry", "BodyPoint", "check_finite_vector", "check_finite_number", "to_dense"]


def check_finite_vector(name, value, size=None):
    """Return ``value`` as a finite 1-D float array or raise ``ValueError``.

    Parameters
    ----------
    name : str
        Name used in the error message.
    value : array_like
        The candidate vector.
    size : int, optional
        Required length.
    """
    arr = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if size is not None and arr.size != size:
        raise ValueError(f"{name} must have {size} entries, got {arr.size}: {value!r}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return arr


def check_finite_number(name, value):
    """Return ``value`` as a finite float or raise ``ValueError`` (also for a bool or a non-number).

    Parameters
    ----------
    name : str
        Name used in the error message.
    value : object
        The candidate number.
    """
    try:
        val = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if isinstance(value, bool) or not np.isfinite(val):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    return val


#: systems with at most this many coordinates use dense matrices; larger ones use
#: ``scipy.sparse`` so that no n × n array is ever allocated for them (memory linear in the mesh)
DENSE_LIMIT = 150
#: most coordinates compiled code holds in a dense n × n matrix (2.9 MB): a body with a dense tangent
#: (an unreduced ModalBody) packs compiled kernel data up to this size, and the compiled loop
#: (skfem_flex.compiled.pack) stores a Newton matrix that has no plan as a band with a small dense
#: border dense up to this size; above DENSE_LIMIT it stores every other one as the values of its
#: sparsity pattern, at any size. 
COMPILED_SIZE_LIMIT = 600


def zero_matrix(n, m=None):
    """An all-zero (n, m) matrix: dense ndarray for small systems (≤ :data:`DENSE_LIMIT`
    coordinates), an empty CSR matrix otherwise."""
    m = n if m is None else m
    if max(n, m) <= DENSE_LIMIT:
        return np.zeros((n, m))
    import scipy.sparse as sps
    return sps.csr_matrix((n, m))


def place_block(n, index, block, sign=1.0, out=None):
    """``out`` (default a :func:`zero_matrix` (n, n)) plus ``sign · block`` at rows and columns ``index``.

    Dense for small systems; for large ones the block goes in as sparse entries,
    so the cost is that of the block, never n²."""
    if out is None:
        out = zero_matrix(n)
    if isinstance(out, np.ndarray):
        out[index, index] += sign * to_dense(block)
        return out
    import scipy.sparse as sps
    idx = np.arange(n)[index]
    c = sps.coo_matrix(block)
    return out + sps.csr_matrix((sign * c.data, (idx[c.row], idx[c.col])), shape=(n, n))


def keeps_methods(obj, cls, names):
    """True if ``obj``'s class inherits the methods ``names`` from ``cls`` unchanged (a compiled form
    describes ``cls``'s equations; a subclass that redefines one of them must run in Python)."""
    kind = type(obj)
    return all(getattr(kind, name) is getattr(cls, name) for name in names)


def to_dense(a):
    """``a`` as a dense ndarray (bodies may return scipy.sparse blocks)."""
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


@dataclass
class BodyGeometry:
    """Geometry of one body at one instant, in the global frame, for output.

    Attributes
    ----------
    points : ndarray, shape (n_points, 2)
        Point coordinates in m.
    cells : list of (str, ndarray)
        meshio cell blocks, e.g. ``[("line", conn)]`` or ``[("vertex", ...)]``.
    point_data : dict of str to ndarray
        Arrays with first dimension n_points.
    cell_data : dict of str to list of ndarray
        One array per cell block.
    """

    points: np.ndarray
    cells: list
    point_data: dict = field(default_factory=dict)
    cell_data: dict = field(default_factory=dict)


class BodyPoint:
    """A material point of a body, for joints, point loads and probes.

    Made by ``body.point(locator)`` (the locator is body-specific: the axial
    coordinate x for beams, body-frame coordinates for a rigid body, nothing
    for a point mass). All methods take the body's own coordinate block q.
    Positions are in the global frame (m); the angle is that of the body
    frame or beam cross-section at the point (rad), which every body here
    makes linear in q.

    Subclasses implement the position methods; the angle methods default to
    "no angle" (a point mass).
    """

    body = None
    #: True when the angle of the point is defined (rigid bodies, beams)
    has_angle = False

    def _not_provided(self, method):
        owner = getattr(self.body, "name", None)
        return NotImplementedError(f"{type(self).__name__} (a point of body {owner!r}) does not implement {method}, "
                                   f"which every body point used by a joint, load or probe must provide "
                                   f"(docs/user_elements.md)")

    def position(self, q):
        """r(q), shape (2,)."""
        raise self._not_provided("position(q)")

    def position_jacobian(self, q):
        """∂r/∂q, shape (2, n)."""
        raise self._not_provided("position_jacobian(q)")

    def position_hessian_product(self, q, f):
        """∂(r_qᵀ f)/∂q for a fixed vector f (2,), shape (n, n)."""
        raise self._not_provided("position_hessian_product(q, f)")

    def position_discrete_gradient(self, q0, q1):
        """D (2, n) with D (q1 − q0) = r(q1) − r(q0) exactly."""
        raise self._not_provided("position_discrete_gradient(q0, q1)")

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        """∂(Dᵀ f)/∂q1, shape (n, n)."""
        raise self._not_provided("position_discrete_gradient_jacobian(q0, q1, f)")

    def velocity(self, q, v):
        """ṙ = r_q v."""
        return self.position_jacobian(q) @ v

    def compiled_map(self):
        """The position map in the form the compiled mechanism loop evaluates
        (the element families of :mod:`skfem_flex.compiled.families`): ``("linear", G, c)`` for r = G q + c,
        ``("frame", m_R, y0, Y)`` for r = m_R R + A(θ)(y0 + Y q_f) with R = q[0:2], θ = q[2],
        q_f = q[3:]; None (the default) if it is neither (the scene then runs on the Python path)."""
        return None

    def angle(self, q):
        """Angle of the frame attached at the point, rad."""
        raise ValueError(f"a point of body {self.body.name!r} has no angle (a point mass cannot be welded "
                         f"or carry a moment)")

    def angle_jacobian(self, q):
        """∂ϑ/∂q, shape (n,) (constant: ϑ is linear in q)."""
        raise ValueError(f"a point of body {self.body.name!r} has no angle")


class Body:
    """Base class of all bodies.

    Subclasses set ``n_dofs``, ``q0``, ``v0``, ``coordinate_names`` and
    ``name`` and override the methods that apply to them. The defaults
    describe a body with constant mass, no strain energy and positions that
    are linear in q (so that gravity is linear too).
    """

    #: number of generalized coordinates
    n_dofs: int = 0
    #: 2 for planar bodies, 3 for spatial ones (positions, momenta and gravity have this many components)
    dimension: int = 2
    #: True when M does not depend on q (the scene then skips all M(q) work)
    constant_mass: bool = True
    #: True when potential_energy is not identically zero
    has_potential: bool = False
    #: local indices of angles whose mean rate in the energy-momentum scheme is the Cayley rate
    #: 2 tan(Δφ/2)/Δt instead of Δφ/Δt (:mod:`skfem_flex.numerics.rotations`); a body that declares them
    #: writes its potential discrete gradient so that, with its rows on these coordinates scaled
    #: by Δφ/w, it is conjugate to those rates. Constant-mass bodies only.
    cayley_coordinates: tuple = ()
    #: the form name of the compiled family that packs ``compiled_strain_data()`` (a body that provides it)
    strain_family: str = None
    name: str = "body"

    def _not_provided(self, method, why):
        """The NotImplementedError a contract method raises when a subclass that needs it left it out."""
        return NotImplementedError(f"body {self.name!r} ({type(self).__name__}) does not implement {method}, "
                                   f"which {why} (the body contract: docs/user_elements.md)")

    def _check_potential(self, method):
        """Strain-energy defaults are zero only for bodies without strain energy: a body that sets
        ``has_potential = True`` and leaves one out would silently lose its internal forces."""
        if self.has_potential:
            raise self._not_provided(method, "a body with has_potential = True must provide")

    # ----------------------------------------------------------------- state
    @property
    def coordinate_names(self):
        """Names of the coordinates, used by drivers and error messages."""
        return tuple(f"q{i}" for i in range(self.n_dofs))

    def coordinate_index(self, name_or_index):
        """Local index of a coordinate given by name or integer.

        Raises
        ------
        ValueError
            If the name is unknown or the index out of range.
        """
        if isinstance(name_or_index, (int, np.integer)):
            i = int(name_or_index)
            if not 0 <= i < self.n_dofs:
                raise ValueError(f"coordinate index {i} is outside 0..{self.n_dofs - 1} of body {self.name!r}")
            return i
        names = self.coordinate_names
        if name_or_index not in names:
            raise ValueError(f"body {self.name!r} has no coordinate {name_or_index!r}; it has {list(names)[:12]}")
        return names.index(name_or_index)

    # --------------------------------------------------------------- kinetic
    def mass_matrix(self, q):
        """M(q), kg (and kg m² for angles)."""
        raise self._not_provided("mass_matrix(q)", "every body must provide")

    def kinetic_energy(self, q, v):
        """T = ½ vᵀ M(q) v, J."""
        return 0.5 * float(v @ (self.mass_matrix(q) @ v))

    def momentum(self, q, v):
        """Generalized momentum p = M(q) v."""
        return self.mass_matrix(q) @ v

    def momentum_jacobian(self, q, v):
        """B(q, v) = ∂(M(q) v)/∂q (zero for constant mass)."""
        raise self._not_provided("momentum_jacobian(q, v)", "a body with constant_mass = False must provide "
                                 "(the trapezoidal and generalized-alpha schemes need it)")

    def quadratic_velocity_force(self, q, v):
        """Q_v = ∂T/∂q − Ṁ v with its derivatives (f, ∂f/∂q, ∂f/∂v).

        Only bodies with ``constant_mass = False`` provide it.
        """
        raise self._not_provided("quadratic_velocity_force(q, v)", "a body with constant_mass = False must provide "
                                 "(every scheme's start and the trapezoidal and generalized-alpha steps need it)")

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        """Discrete gradient of G(q) = ½ v0ᵀ M(q) v1 between q0 and q1.

        Returns (g, ∂g/∂q1, ∂g/∂v1) with g · (q1 − q0) = G(q1) − G(q0).
        Only bodies with ``constant_mass = False`` provide it.
        """
        raise self._not_provided("kinetic_discrete_gradient(q0, q1, v0, v1)", "a body with constant_mass = False "
                                 "must provide (the energy-momentum scheme needs it)")

    # ------------------------------------------------------------- potential
    def potential_energy(self, q):
        """Internal (strain) energy V(q), J (zero unless ``has_potential``)."""
        self._check_potential("potential_energy(q)")
        return 0.0

    def potential_gradient(self, q):
        """∇V(q)."""
        self._check_potential("potential_gradient(q)")
        return np.zeros(self.n_dofs)

    def potential_hessian(self, q):
        """∇²V(q)."""
        self._check_potential("potential_hessian(q)")
        return zero_matrix(self.n_dofs)

    def potential_discrete_gradient(self, q0, q1):
        """(g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0) exactly."""
        self._check_potential("potential_discrete_gradient(q0, q1)")
        return np.zeros(self.n_dofs), zero_matrix(self.n_dofs)

    # --------------------------------------------------------------- gravity
    def mass_moment(self):
        """(Γ, c) with ∫ r dm = Γ q + c for bodies whose positions are linear in q.

        Γ has shape (2, n_dofs) in kg, c shape (2,) in kg m. Bodies whose positions are not linear
        in q raise ``NotImplementedError`` and override :meth:`gravity_potential` and
        :meth:`gravity_discrete_gradient` instead.
        """
        raise self._not_provided("mass_moment()", "gravity needs from a body whose positions are linear in q "
                                 "(otherwise override gravity_potential(q, g) and "
                                 "gravity_discrete_gradient(q0, q1, g))")

    def gravity_potential(self, q, g):
        """Potential of the uniform field g (m/s²): V = −g · ∫ r dm.

        Returns (V, ∇V, ∇²V).
        """
        gam, c = self._linear_mass_moment("gravity_potential(q, g)")
        g = np.asarray(g, dtype=float)
        grad = -(g @ gam)
        return float(grad @ q - g @ c), grad, zero_matrix(self.n_dofs)

    def gravity_discrete_gradient(self, q0, q1, g):
        """Discrete gradient of the gravity potential: (g, ∂g/∂q1).

        The default is the constant gradient of a body linear in q (:meth:`mass_moment`); a body
        that overrides :meth:`gravity_potential` because it is not linear must override this too.
        """
        gam, _ = self._linear_mass_moment("gravity_discrete_gradient(q0, q1, g)")
        return -(np.asarray(g, dtype=float) @ gam), zero_matrix(self.n_dofs)

    def _linear_mass_moment(self, method):
        """(Γ, c) of :meth:`mass_moment`, or a NotImplementedError saying what gravity needs instead."""
        try:
            return self.mass_moment()
        except NotImplementedError as exc:
            own = "" if type(self).mass_moment is Body.mass_moment else f" (it says: {exc})"
            raise NotImplementedError(
                f"body {self.name!r} ({type(self).__name__}) provides neither mass_moment() (bodies whose positions "
                f"are linear in q){own} nor its own {method} (bodies that are not); gravity needs one of them "
                f"(the body contract: docs/user_elements.md)") from None

    # -------------------------------------------------------------- momenta
    def linear_momentum(self, q, v):
        """Total linear momentum (kg m/s), shape (dimension,), or None if not provided."""
        return None

    def angular_momentum(self, q, v):
        """Angular momentum about the global origin (kg m²/s): a float (planar), shape (3,) (spatial), or None."""
        return None

    # ---------------------------------------------------------- body points
    def point(self, locator=None):
        """A :class:`BodyPoint` at ``locator``; ``ValueError`` if it lies outside the body."""
        raise self._not_provided("point(locator)", "joints, point loads and probes need")

    # --------------------------------------------------------------- output
    def geometry(self, q, v):
        """A :class:`BodyGeometry` of the current configuration."""
        raise self._not_provided("geometry(q, v)", "output sinks (VTK series) need")


class StrainPointsPotential:
    """Mixin of a body whose strain energy lives in its ``strain_points`` (an object with ``energy(q)``,
    ``gradient(q)`` and ``hessian(q)``): the exact beams, planar and spatial."""

    def potential_energy(self, q):
        """V(q), J: ``strain_points.energy``."""
        return self.strain_points.energy(q)

    def potential_gradient(self, q):
        """∇V(q): ``strain_points.gradient``."""
        return self.strain_points.gradient(q)

    def potential_hessian(self, q):
        """∇²V(q): ``strain_points.hessian``."""
        return self.strain_points.hessian(q)
