"""Scene: bodies, constraints, forces and prescribed motion on one coordinate layout.

The scene concatenates the bodies' coordinate blocks into global vectors
q and v and assembles the terms the integrators ask for. It only touches
what it holds: no multipliers without constraints, no M(q) work when every
body has constant mass, no external-force work without loads.
Matrices are dense ``ndarray`` for small scenes and ``scipy.sparse.csr_matrix``
for large ones (``Scene.dense``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from .elements.constraints.quadratic import Rigidity, UnitQuaternion
from .elements.forces import Gravity
from .elements.motion import Prescribed

__all__ = ["Scene", "DENSE_LIMIT", "add_matrices"]

#: scenes with at most this many coordinates use dense matrices (measured crossover of the time loop:
#: dense LAPACK wins below ~100 coordinates, banded/sparse LU above ~150; examples/benchmark.py);
#: the same small-system threshold the bodies' and constraints' zero blocks follow
from .bodies.base import DENSE_LIMIT, Body  # noqa: E402


def add_matrices(a, b):
    """a + b for dense/sparse mixtures (None counts as zero)."""
    if b is None:
        return a
    if a is None:
        return b
    if sps.issparse(a) and not sps.issparse(b):
        return a.toarray() + b
    return a + b


class _Accumulator:
    """Sum of blocks placed at index sets, dense or sparse."""

    def __init__(self, shape, dense):
        self.shape, self.dense = shape, dense
        if dense:
            self.a = np.zeros(shape)
        else:
            self.rows, self.cols, self.vals = [], [], []
            self.extra = []
            self.whole = None           # sum of blocks that cover the whole system (no scatter)

    def add(self, block, rows, cols, ix=None):
        """Add ``block`` at (rows, cols); ``None`` is a zero block; ``ix`` a precomputed ``np.ix_``."""
        if block is None:
            return
        if self.dense:
            if sps.issparse(block):
                block = block.toarray()
            self.a[np.ix_(rows, cols) if ix is None else ix] += block
            return
        if sps.issparse(block):
            c = block.tocoo()
            self.rows.append(rows[c.row])
            self.cols.append(cols[c.col])
            self.vals.append(c.data)
        else:
            block = np.asarray(block)
            r, c = np.nonzero(block)
            self.rows.append(rows[r])
            self.cols.append(cols[c])
            self.vals.append(block[r, c])

    def add_whole(self, block):
        """Add a block that covers the whole matrix (identity index sets)."""
        if self.dense:
            self.a += block.toarray() if sps.issparse(block) else block
        elif self.whole is None:
            self.whole = sps.csr_matrix(block)
        else:
            self.whole = self.whole + sps.csr_matrix(block)

    def result(self):
        if self.dense:
            return self.a
        if not self.vals:
            return self.whole if self.whole is not None else sps.csr_matrix(self.shape)
        out = sps.csr_matrix((np.concatenate(self.vals), (np.concatenate(self.rows), np.concatenate(self.cols))),
                             shape=self.shape)
        return out if self.whole is None else out + self.whole


class Scene:
    """A planar or spatial multibody system (every body moves in the same ``dimension``: 2 or 3).

    Parameters
    ----------
    bodies : sequence of Body
        Every body once; its coordinates form one block of q in this order.
    constraints : sequence of Constraint, optional
    forces : sequence of ForceElement, optional
        Gravity, springs, loads. ``Gravity(bodies=None)`` acts on all bodies.
    prescribed : sequence of Prescribed, optional
        Coordinates that follow a motion law; they are not unknowns.
    probes : dict of str to callable, optional
        ``probe(scene, t, q, v)`` returning a float or a small array, recorded
        at every output step of a simulation.
    name : str
    parameters : dict, optional
        The parameters the scene was built with (for summaries).

    Raises
    ------
    ValueError
        On a body listed twice, an element that refers to a body outside the
        scene, a coordinate prescribed twice, or a non-callable probe.
    """

    def __init__(self, bodies, constraints=(), forces=(), prescribed=(), probes=None, name="scene",
                 parameters=None):
        if isinstance(bodies, (str, bytes)) or not hasattr(bodies, "__iter__"):
            raise TypeError(f"bodies must be a sequence of skfem_flex bodies, got {type(bodies).__name__}")
        self.bodies = tuple(bodies)
        for b in self.bodies:
            if not isinstance(b, Body):
                raise TypeError(f"bodies must be skfem_flex bodies (FloatingBeam, ExactBeam, RigidBody, PointMass, "
                                f"...), got {type(b).__name__} {b!r:.40}")
        if not self.bodies:
            raise ValueError("a scene needs at least one body")
        ids = [id(b) for b in self.bodies]
        if len(set(ids)) != len(ids):
            raise ValueError("a body is listed twice in the scene")
        dims = {getattr(b, "dimension", 2) for b in self.bodies}
        if len(dims) != 1:
            raise ValueError("a scene's bodies must all be planar or all spatial, got "
                             + ", ".join(f"{b.name!r} ({getattr(b, 'dimension', 2)}D)" for b in self.bodies))
        #: 2 (planar) or 3 (spatial)
        self.dimension = dims.pop()
        self.name = name
        self.parameters = dict(parameters or {})
        self._offset = {}
        start = 0
        for b in self.bodies:
            self._offset[id(b)] = start
            start += b.n_dofs
        self.n = start
        self.dense = self.n <= DENSE_LIMIT

        self.forces = tuple(f.on(self.bodies) if isinstance(f, Gravity) and f.bodies is None else f
                            for f in forces)
        self.prescribed = tuple(prescribed)
        pres = []
        for p in self.prescribed:
            if not isinstance(p, Prescribed):
                raise ValueError(f"prescribed entries must be Prescribed, got {p!r}")
            pres.append(self.index(p.body, p.coordinate))
        if len(set(pres)) != len(pres):
            raise ValueError("a coordinate is prescribed twice")
        self.prescribed_index = np.array(pres, dtype=int)
        self.free_index = np.setdiff1d(np.arange(self.n), self.prescribed_index)
        # spatial rigid bodies and the nodes of spatial beams are held rigid by their directors'
        # constraints (less what prescribed directors hold), bodies turned by quaternions at |e| = 1, added first
        start = dict(zip(pres, self.prescribed_state(0.0)[0]))
        self.constraints = tuple(r for b in self.bodies for r in Rigidity.of_body(b, {
            i - self._offset[id(b)]: x for i, x in start.items() if 0 <= i - self._offset[id(b)] < b.n_dofs})) + tuple(
            UnitQuaternion(b, o) for b in self.bodies for o in getattr(b, "unit_quaternions", ())) + tuple(constraints)
        self._force_idx = [self._indices(f.bodies, f"force {getattr(f, 'name', f)!r}") for f in self.forces]
        layout, row = [], 0
        for c in self.constraints:
            idx = self._indices(c.bodies, f"constraint {c.name!r}")
            rows = np.arange(row, row + c.n_equations)
            # read-only: constraint_layout hands these very arrays out, and the dense row assembly keys
            # its cached index meshes by their identity, so no caller may change them in place
            idx.flags.writeable = rows.flags.writeable = False
            layout.append((idx, rows))
            row += c.n_equations
        self._constraint_layout = tuple(layout)
        self.n_constraints = row


        self.probes = dict(probes or {})
        for k, fn in self.probes.items():
            if not callable(fn):
                raise ValueError(f"probe {k!r} is not callable")

        self._body_idx = [np.arange(self._offset[id(b)], self._offset[id(b)] + b.n_dofs) for b in self.bodies]
        self._ix = {}
        self.variable_mass_bodies = [(b, i) for b, i in zip(self.bodies, self._body_idx) if not b.constant_mass]
        acc = _Accumulator((self.n, self.n), self.dense)
        for b, i in zip(self.bodies, self._body_idx):
            if b.constant_mass:
                self._add(acc, b.mass_matrix(b.q0), i)
        self._constant_mass = acc.result()
        cay = []
        for b, i in zip(self.bodies, self._body_idx):
            local = np.asarray(getattr(b, "cayley_coordinates", ()), dtype=int)
            if local.size:
                if not b.constant_mass:
                    raise ValueError(f"body {b.name!r} declares Cayley coordinates but has a variable mass "
                                     f"matrix; only constant-mass bodies may")
                cay.append(i[local])
        #: global indices of the Cayley-rate angles (empty: the energy scheme's plain mid-point rates)
        self.cayley_index = np.sort(np.concatenate(cay)) if cay else np.zeros(0, dtype=int)
        self.potential_bodies = [(b, i) for b, i in zip(self.bodies, self._body_idx) if b.has_potential]
        self.conservative_forces = [(f, i) for f, i in zip(self.forces, self._force_idx) if f.conservative]
        self.loads = [(f, i) for f, i in zip(self.forces, self._force_idx) if not f.conservative]
        self._fused = None

    # ---------------------------------------------------------------- layout
    @property
    def constraint_layout(self):
        """Where each constraint reads and writes: its coordinate indices and its multiplier rows.

        Returns
        -------
        tuple of (ndarray, ndarray)
            One pair ``(indices, rows)`` per constraint, in the order of
            ``scene.constraints`` (and of :attr:`reaction_names`): ``indices``
            are the global coordinates of the constraint's bodies in the order
            it reads them (``q[indices]`` is its local vector), ``rows`` the
            positions of its equations in Φ and of its multipliers in λ
            (``lam[rows]``). The arrays are read-only.

        Examples
        --------
        The reaction of every constraint from the multipliers λ::

            for c, (idx, rows) in zip(scene.constraints, scene.constraint_layout):
                c.reaction(q[idx], lam[rows])
        """
        return self._constraint_layout

    def _indices(self, bodies, what):
        out = []
        for b in bodies:
            if id(b) not in self._offset:
                raise ValueError(f"{what} refers to body {getattr(b, 'name', b)!r}, which is not in the scene")
            o = self._offset[id(b)]
            out.append(np.arange(o, o + b.n_dofs))
        return np.concatenate(out) if out else np.zeros(0, dtype=int)

    def slice(self, body):
        """The slice of ``body``'s coordinates in the global vectors."""
        if id(body) not in self._offset:
            raise ValueError(f"body {getattr(body, 'name', body)!r} is not in the scene")
        o = self._offset[id(body)]
        return slice(o, o + body.n_dofs)

    def index(self, body, coordinate):
        """Global index of a body's coordinate (name or local index)."""
        return self.slice(body).start + body.coordinate_index(coordinate)

    def coordinates(self, body, x):
        """The block of the global vector ``x`` that belongs to ``body``."""
        return x[self.slice(body)]

    def initial_state(self):
        """(q0, v0) as global vectors, with prescribed coordinates set by their laws at t = 0."""
        q = np.concatenate([b.q0 for b in self.bodies]).astype(float)
        v = np.concatenate([b.v0 for b in self.bodies]).astype(float)
        qp, vp, _ = self.prescribed_state(0.0)
        q[self.prescribed_index] = qp
        v[self.prescribed_index] = vp
        return q, v

    def prescribed_state(self, t):
        """Values, rates and accelerations of the prescribed coordinates at t."""
        if not self.prescribed:
            z = np.zeros(0)
            return z, z, z
        vals = np.array([p.law(t) for p in self.prescribed], dtype=float)
        return vals[:, 0], vals[:, 1], vals[:, 2]

    def _zeros(self):
        return _Accumulator((self.n, self.n), self.dense)

    def _add(self, acc, block, idx):
        """acc += block at (idx, idx), with the index mesh built once per index set."""
        key = id(idx)
        if key not in self._ix:
            # an index set that is exactly 0, 1, …, n−1 (a single-body scene) needs no scatter;
            # one covering every body in another order does
            identity = idx.size == self.n and bool(np.array_equal(idx, np.arange(self.n)))
            self._ix[key] = None if identity else np.ix_(idx, idx)
        ix = self._ix[key]
        if ix is None and block is not None and acc.shape == (self.n, self.n):
            acc.add_whole(block)
            return
        acc.add(block, idx, idx, ix)

    # --------------------------------------------------------------- kinetic
    def kinetic_energy(self, q, v):
        """T = ½ vᵀ M(q) v, J."""
        t = 0.5 * float(v @ (self._constant_mass @ v))
        for b, i in self.variable_mass_bodies:
            t += b.kinetic_energy(q[i], v[i])
        return t

    def mass_matrix(self, q):
        """M(q)."""
        if not self.variable_mass_bodies:
            return self._constant_mass
        acc = self._zeros()
        for b, i in self.variable_mass_bodies:
            self._add(acc, b.mass_matrix(q[i]), i)
        return self._constant_mass + acc.result()

    def momentum(self, q, v):
        """p = M(q) v."""
        p = self._constant_mass @ v
        for b, i in self.variable_mass_bodies:
            p[i] += b.momentum(q[i], v[i])
        return p

    def momentum_jacobian(self, q, v):
        """B(q, v) = ∂(M(q) v)/∂q, or None when all masses are constant."""
        if not self.variable_mass_bodies:
            return None
        acc = self._zeros()
        for b, i in self.variable_mass_bodies:
            self._add(acc, b.momentum_jacobian(q[i], v[i]), i)
        return acc.result()

    def quadratic_velocity_force(self, q, v):
        """(Q_v, ∂Q_v/∂q, ∂Q_v/∂v) with Q_v = ∂T/∂q − Ṁ v, or None when all masses are constant."""
        if not self.variable_mass_bodies:
            return None
        f = np.zeros(self.n)
        fq, fv = self._zeros(), self._zeros()
        for b, i in self.variable_mass_bodies:
            fb, fbq, fbv = b.quadratic_velocity_force(q[i], v[i])
            f[i] += fb
            self._add(fq, fbq, i)
            self._add(fv, fbv, i)
        return f, fq.result(), fv.result()

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        """Discrete gradient of G(q) = ½ v0ᵀ M(q) v1: (g, ∂g/∂q1, ∂g/∂v1), or None."""
        if not self.variable_mass_bodies:
            return None
        g = np.zeros(self.n)
        gq, gv = self._zeros(), self._zeros()
        for b, i in self.variable_mass_bodies:
            gb, gbq, gbv = b.kinetic_discrete_gradient(q0[i], q1[i], v0[i], v1[i])
            g[i] += gb
            self._add(gq, gbq, i)
            self._add(gv, gbv, i)
        return g, gq.result(), gv.result()

    def energy_momentum_terms(self, q0, q1, v0, v1, dt):
        """What one Newton evaluation of the energy-momentum scheme needs from the scene.

        Returns
        -------
        p1 : ndarray (n,)
            M(q1) v1.
        g_kin : ndarray (n,) or None
            Discrete gradient of G(q) = ½ v0ᵀ M(q) v1 (None when all masses are constant).
        g_pot : ndarray (n,)
            Discrete gradient of V (bodies and conservative force elements).
        jac : matrix (n, n)
            (2/Δt) M(q1) + B(q1, v1) − Δt ∂g_kin/∂q1 − 2 ∂g_kin/∂v1 + Δt ∂g_pot/∂q1.
        floor : ndarray (n,)
            Δt |∂g_pot/∂q1| (|q0| + |q1|), the round-off floor of the internal forces.
        kinetic : float
            T(q1, v1).

        Bodies that implement the optional fused ``energy_momentum_terms(q0, q1, v0, v1, dt)``
        (e.g. :class:`~skfem_flex.bodies.FloatingBeam`) are evaluated in one call; otherwise
        (or with conservative force elements) the terms come from the separate contract methods.
        """
        if self._fused is None:
            self._fused = (bool(self.variable_mass_bodies) and all(
                hasattr(b, "energy_momentum_terms") for b, _ in self.variable_mass_bodies + self.potential_bodies)
                and {id(b) for b, _ in self.potential_bodies} <= {id(b) for b, _ in self.variable_mass_bodies})
        if not self._fused:
            p1 = self.momentum(q1, v1)
            jac = add_matrices(self.mass_matrix(q1) * (2.0 / dt), None)
            g_kin = None
            if self.variable_mass_bodies:
                jac = add_matrices(jac, self.momentum_jacobian(q1, v1))
                g_kin, g_q, g_v = self.kinetic_discrete_gradient(q0, q1, v0, v1)
                jac = add_matrices(jac, -(dt * g_q + 2.0 * g_v))
            g_pot, h = self.potential_discrete_gradient(q0, q1)
            jac = add_matrices(jac, dt * h)
            floor = dt * (abs(h) @ (np.abs(q0) + np.abs(q1)))
            return p1, g_kin, g_pot, jac, floor, self.kinetic_energy(q1, v1)
        if len(self.bodies) == 1 and not self.conservative_forces:
            b = self.bodies[0]
            p1, g_kin, g_pot, jac, floor = b.energy_momentum_terms(q0, q1, v0, v1, dt)
            return p1, g_kin, g_pot, jac, floor, 0.5 * float(v1 @ p1)
        p1 = self._constant_mass @ v1
        g_kin, g_pot, floor = np.zeros(self.n), np.zeros(self.n), np.zeros(self.n)
        acc = self._zeros()
        for b, i in self.variable_mass_bodies:
            pb, gkb, gpb, jb, fb = b.energy_momentum_terms(q0[i], q1[i], v0[i], v1[i], dt)
            p1[i] += pb
            g_kin[i] += gkb
            g_pot[i] += gpb
            floor[i] += fb
            self._add(acc, jb, i)
        for f, i in self.conservative_forces:          # gravity, springs: their own discrete gradients
            gf, hf = f.potential_discrete_gradient(q0[i], q1[i])
            g_pot[i] += gf
            if hf is not None:
                hf = hf * dt
                self._add(acc, hf, i)
                floor[i] += abs(hf) @ (np.abs(q0[i]) + np.abs(q1[i]))
        jac = add_matrices(self._constant_mass * (2.0 / dt), acc.result())
        return p1, g_kin, g_pot, jac, floor, 0.5 * float(v1 @ p1)

    # ------------------------------------------------------------- potential
    def potential_energy(self, q):
        """V(q): strain energy of bodies plus conservative force elements, J."""
        e = 0.0
        for b, i in self.potential_bodies:
            e += b.potential_energy(q[i])
        for f, i in self.conservative_forces:
            e += f.potential_energy(q[i])
        return e

    def potential_gradient(self, q):
        """∇V(q)."""
        g = np.zeros(self.n)
        for b, i in self.potential_bodies:
            g[i] += b.potential_gradient(q[i])
        for f, i in self.conservative_forces:
            g[i] += f.potential_gradient(q[i])
        return g

    def potential_hessian(self, q):
        """∇²V(q)."""
        acc = self._zeros()
        for b, i in self.potential_bodies:
            self._add(acc, b.potential_hessian(q[i]), i)
        for f, i in self.conservative_forces:
            self._add(acc, f.potential_hessian(q[i]), i)
        return acc.result()

    def potential_discrete_gradient(self, q0, q1):
        """(g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0)."""
        g = np.zeros(self.n)
        acc = self._zeros()
        for b, i in self.potential_bodies:
            gb, hb = b.potential_discrete_gradient(q0[i], q1[i])
            g[i] += gb
            self._add(acc, hb, i)
        for f, i in self.conservative_forces:
            gb, hb = f.potential_discrete_gradient(q0[i], q1[i])
            g[i] += gb
            self._add(acc, hb, i)
        return g, acc.result()

    # ------------------------------------------------------------------ loads
    def external_force(self, q, v, t):
        """(Q, ∂Q/∂q, ∂Q/∂v) of the non-conservative loads, or None without loads."""
        if not self.loads:
            return None
        f = np.zeros(self.n)
        fq, fv = self._zeros(), self._zeros()
        for e, i in self.loads:
            fe, feq, fev = e.generalized_force(q[i], v[i], t)
            f[i] += fe
            if feq is not None:
                self._add(fq, feq, i)
            if fev is not None:
                self._add(fv, fev, i)
        return f, fq.result(), fv.result()

    # ------------------------------------------------------------ constraints
    def constraint_value(self, q, t):
        """Φ(q, t), shape (n_constraints,)."""
        phi = np.zeros(self.n_constraints)
        for c, (i, r) in zip(self.constraints, self.constraint_layout):
            phi[r] = c.value(q[i], t)
        return phi

    def _assemble_rows(self, blocks):
        if self.dense:
            out = np.zeros((self.n_constraints, self.n))
            for blk, i, r in blocks:
                key = (id(r), id(i))                   # the scene's own index arrays: built once
                if key not in self._ix:
                    self._ix[key] = np.ix_(r, i)
                out[self._ix[key]] += blk
            return out
        acc = _Accumulator((self.n_constraints, self.n), False)
        for blk, i, r in blocks:
            acc.add(blk, r, i)
        return acc.result()

    def constraint_jacobian(self, q, t):
        """Φ_q(q, t), shape (n_constraints, n)."""
        return self._assemble_rows([(c.jacobian(q[i], t), i, r)
                                    for c, (i, r) in zip(self.constraints, self.constraint_layout)])

    def constraint_time_derivative(self, q, t):
        """Φ_t(q, t)."""
        out = np.zeros(self.n_constraints)
        for c, (i, r) in zip(self.constraints, self.constraint_layout):
            if c.rheonomic:
                out[r] = c.time_derivative(q[i], t)
        return out

    def constraint_acceleration_rhs(self, q, v, t):
        """γ with Φ_q q̈ = γ."""
        out = np.zeros(self.n_constraints)
        for c, (i, r) in zip(self.constraints, self.constraint_layout):
            out[r] = c.acceleration_rhs(q[i], v[i], t)
        return out

    def constraint_velocity_jacobian(self, q, v, t):
        """∂(Φ_q v)/∂q at fixed v, shape (n_constraints, n)."""
        return self._assemble_rows([(c.velocity_jacobian(q[i], v[i], t), i, r)
                                    for c, (i, r) in zip(self.constraints, self.constraint_layout)])

    def constraint_hessian_product(self, q, mu, t):
        """∂(Φ_qᵀ μ)/∂q, shape (n, n)."""
        acc = self._zeros()
        for c, (i, r) in zip(self.constraints, self.constraint_layout):
            self._add(acc, c.hessian_product(q[i], mu[r], t), i)
        return acc.result()

    def constraint_discrete_gradient(self, q0, q1, t):
        """D with D (q1 − q0) = Φ(q1, t) − Φ(q0, t)."""
        return self._assemble_rows([(c.discrete_gradient(q0[i], q1[i], t), i, r)
                                    for c, (i, r) in zip(self.constraints, self.constraint_layout)])

    def constraint_discrete_gradient_jacobian(self, q0, q1, mu, t):
        """∂(Dᵀ μ)/∂q1."""
        acc = self._zeros()
        for c, (i, r) in zip(self.constraints, self.constraint_layout):
            self._add(acc, c.discrete_gradient_jacobian(q0[i], q1[i], mu[r], t), i)
        return acc.result()

    @property
    def reaction_names(self):
        """Unique names of the constraints in multiplier order (repeated names get #2, #3, ...)."""
        out, seen = [], {}
        for c in self.constraints:
            seen[c.name] = seen.get(c.name, 0) + 1
            out.append(c.name if seen[c.name] == 1 else f"{c.name}#{seen[c.name]}")
        return tuple(out)

    def constraint_reactions(self, q, lam):
        """{unique constraint name: reaction} at q with multipliers λ (``Constraint.reaction``)."""
        lam = np.asarray(lam, dtype=float)
        if lam.size != self.n_constraints:
            raise ValueError(f"lam must have {self.n_constraints} entries, got {lam.size}")
        return {name: np.atleast_1d(np.asarray(c.reaction(q[i], lam[r]), dtype=float))
                for name, c, (i, r) in zip(self.reaction_names, self.constraints, self.constraint_layout)}

    # ---------------------------------------------------------------- momenta
    def linear_momentum(self, q, v):
        """Total linear momentum (dimension,), or None if a body does not provide it."""
        total = np.zeros(self.dimension)
        for b, i in zip(self.bodies, self._body_idx):
            p = b.linear_momentum(q[i], v[i])
            if p is None:
                return None
            total += p
        return total

    def angular_momentum(self, q, v):
        """Total angular momentum about the origin (a float in the plane, (3,) in space), or None if a body does
        not provide it."""
        total = 0.0 if self.dimension == 2 else np.zeros(3)
        for b, i in zip(self.bodies, self._body_idx):
            h = b.angular_momentum(q[i], v[i])
            if h is None:
                return None
            total += h
        return total

    def evaluate_probes(self, t, q, v):
        """{name: value} of every probe."""
        return {k: np.asarray(fn(self, t, q, v), dtype=float) for k, fn in self.probes.items()}

    @property
    def length_scale(self):
        """Characteristic size of the scene, m: the diagonal of the bounding box of all bodies at q0.

        A floor for scale-relative tolerances of position constraints: a joint
        at the global origin whose coordinates are zero has |Φ_q| |q| = 0, so
        |Φ_q| · length_scale gives its residual a meaningful scale. Computed
        once from the bodies' output geometry (1 m if that is degenerate).
        """
        if getattr(self, "_length_scale", None) is None:
            pts = []
            for b in self.bodies:
                try:
                    pts.append(np.asarray(b.geometry(np.asarray(b.q0, float), np.asarray(b.v0, float)).points,
                                          dtype=float).reshape(-1, self.dimension))
                except (NotImplementedError, AttributeError, ValueError):
                    continue
            size = 0.0
            if pts:
                allp = np.vstack(pts)
                if allp.size and np.all(np.isfinite(allp)):
                    size = float(np.linalg.norm(allp.max(axis=0) - allp.min(axis=0)))
            self._length_scale = size if size > 0.0 else 1.0
        return self._length_scale
