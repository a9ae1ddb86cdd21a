"""Implicit time integrators on one Newton–Raphson core.

Systems::

    d/dt (M(q) q̇) − ∂T/∂q + ∇V(q) + Φ_qᵀ λ = Q(q, q̇, t),     Φ(q, t) = 0

Schemes (all solve for the increment Δq = q_{n+1} − q_n, never for q_{n+1}
itself, so that v_{n+1} keeps its digits as q grows; see
``docs/energy_scheme.md``, trap 5):

``energy-momentum``
    Discrete-gradient midpoint scheme (Lee & Yun, eqs. 3, 22, 25–26)
    in Lagrangian form::

        q1 = q0 + Δq,  v1 = 2Δq/Δt − v0
        p(q1, v1) − p(q0, v0) − Δt [D_G − D_V + Q(q_m, Δq/Δt, t_m)] + D_Φᵀ μ = 0
        Φ(q1, t1) = 0

    with D_V a discrete gradient of V (stress at the mean strain), D_G one of
    G(q) = ½ v0ᵀ M(q) v1 (zero for constant mass) and D_Φ one of Φ; μ = Δt λ̄.
    Then E1 − E0 = Δq·Q − λ̄·(Φ(q1) − Φ(q0)) + v̄·r exactly (λ̄ = μ/Δt), where r is
    the Newton residual: the energy balance holds to the Newton tolerance for
    nonlinear, constrained systems.
``trapezoidal``
    Average-acceleration Newmark (β = ¼, γ = ½), equilibrium at t_{n+1},
    constraints at velocity level (index 2): Φ_q(q_{n+1}) v_{n+1} +
    Φ_t = 0, as the established multibody codes run it. Positions then
    drift off Φ = 0 by O(Δt²) (reported as the constraint residual) but the
    weak instability of the index-3 form is gone.
``generalized-alpha``
    Chung–Hulbert with spectral radius ρ∞, constraints at position level in
    the form of Arnold & Brüls (2007); the velocity-level residual
    Φ_q v + Φ_t is reported.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
import scipy.sparse as sps

from ..errors import ConvergenceError, SimulationError
from ..numerics.linear_solver import PatternCache, linear_solve
from ..numerics.newton import NewtonSettings, newton_solve, predicted_increment, roundoff_floor
from ..numerics.rotations import MAX_INCREMENT, cayley, cayley_derivative, cayley_ratio, cayley_ratio_derivative
from ..scene import add_matrices

__all__ = ["SimulationError", "ConvergenceError", "NewtonSettings", "State", "NewmarkState", "Integrator", "newton_solve", "linear_solve",
           "EnergyMomentum", "predictor_acceleration", "Newmark", "Trapezoidal", "GeneralizedAlpha", "make_integrator", "INTEGRATORS"]

_TINY = 1e-300


@dataclass
class State:
    """Integrator state at one instant: what every scheme carries (:class:`EnergyMomentum`'s state).

    Attributes
    ----------
    t : float
        Time, s.
    q, v : ndarray
        Coordinates and velocities (global vectors).
    acc : ndarray
        Acceleration q̈: consistent at the start, then the energy-momentum step's mean acceleration
        (v_{n+1} − v_n)/Δt (its Newton start) or the Newmark schemes' q̈_{n+1}.
    lam : ndarray
        Lagrange multipliers λ (for the energy scheme the mean over the last step).
    prescribed_force : ndarray
        Generalized force the prescribed coordinates' laws exert (mean over the last step).
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    acc: np.ndarray = None
    lam: np.ndarray = field(default_factory=lambda: np.zeros(0))
    prescribed_force: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass
class NewmarkState(State):
    """The state of the Newmark family (:class:`Newmark`, :class:`Trapezoidal`, :class:`GeneralizedAlpha`):
    :class:`State` and the algorithmic acceleration.

    Attributes
    ----------
    pseudo : ndarray
        Generalized-α's algorithmic acceleration a (m/s², rad/s²); q̈ itself for α_m = α_f = 0.
    """

    pseudo: np.ndarray = None


@dataclass
class StepInfo:
    """What one step reports: Newton iterations, work of external forces and drivers, residuals."""

    iterations: int
    work: float
    velocity_residual: float = 0.0


_SUB_PLANS = PatternCache()
_IX = {}


def _sub_block(mat, rows, cols):
    if rows.size == mat.shape[0] and cols.size == mat.shape[1]:
        return mat                      # rows and cols are sorted index sets: all of them
    if sps.issparse(mat):
        mat = mat.tocsr()
        if not mat.has_canonical_format:
            return mat[rows][:, cols]

        def build():
            tag = sps.csr_matrix((np.arange(1.0, mat.nnz + 1.0), mat.indices, mat.indptr), shape=mat.shape)
            sub = tag[rows][:, cols].tocsr()
            sub.sort_indices()
            return (sub.data.astype(np.int64) - 1, sub.indices.copy(), sub.indptr.copy(), sub.shape)
        take, indices, indptr, shape = _SUB_PLANS.get(mat, (rows, cols), build)
        return sps.csr_matrix((mat.data[take], indices, indptr), shape=shape)
    key = (id(rows), id(cols))
    hit = _IX.get(key)
    if hit is None or hit[0] is not rows or hit[1] is not cols:
        if len(_IX) > 16:
            _IX.clear()
        hit = _IX[key] = (rows, cols, np.ix_(rows, cols))
    return mat[hit[2]]


def _bordered(jff, d_t, c_q, dense):
    """[[J, Dᵀ], [C, 0]] in dense or sparse form."""
    m = c_q.shape[0]
    if m == 0:
        return jff
    if dense:
        jff = jff.toarray() if sps.issparse(jff) else jff
        d_t = d_t.toarray() if sps.issparse(d_t) else d_t
        c_q = c_q.toarray() if sps.issparse(c_q) else c_q
        n = jff.shape[0]
        out = np.zeros((n + m, n + m))
        out[:n, :n] = jff
        out[:n, n:] = d_t
        out[n:, :n] = c_q
        return out
    return sps.bmat([[sps.csr_matrix(jff), sps.csr_matrix(d_t)], [sps.csr_matrix(c_q), None]], format="csc")


def _inf(x):
    return float(np.abs(x).max()) if np.size(x) else 0.0


class Integrator:
    """Base class: a named scheme that advances a :class:`State` by one step."""

    name = "integrator"

    #: the dataclass of this scheme's state
    state_type = State

    def __init__(self, newton=None):
        self.newton = NewtonSettings() if newton is None else newton
        if not isinstance(self.newton, NewtonSettings):
            raise ValueError(f"newton must be NewtonSettings, got {self.newton!r}")

    # ----------------------------------------------------------- start state
    def start(self, scene, state):
        """Complete the initial state: consistent accelerations and multipliers.

        Solves M q̈ + Φ_qᵀ λ = F, Φ_q q̈ = γ for the free coordinates, the
        prescribed ones taking their laws' accelerations.
        """
        q, v, t = state.q, state.v, state.t
        free, pres = scene.free_index, scene.prescribed_index
        _, _, acc_p = scene.prescribed_state(t)
        force = -scene.potential_gradient(q)
        qv = scene.quadratic_velocity_force(q, v)
        if qv is not None:
            force = force + qv[0]
        ext = scene.external_force(q, v, t)
        if ext is not None:
            force = force + ext[0]
        mass = scene.mass_matrix(q)
        acc = np.zeros(scene.n)
        acc[pres] = acc_p
        rhs = force[free] - (_sub_block(mass, free, pres) @ acc_p if pres.size else 0.0)
        m = scene.n_constraints
        if m:
            cq = scene.constraint_jacobian(q, t)
            gamma = scene.constraint_acceleration_rhs(q, v, t)
            cq_f = _sub_block(cq, np.arange(m), free)
            g_rhs = gamma - (_sub_block(cq, np.arange(m), pres) @ acc_p if pres.size else 0.0)
            a = _bordered(_sub_block(mass, free, free), cq_f.T, cq_f, scene.dense)
            b = np.concatenate([rhs, g_rhs])
        else:
            a, b = _sub_block(mass, free, free), rhs
        try:
            x = linear_solve(a, b)
        except np.linalg.LinAlgError as exc:
            raise ValueError("the initial mass/constraint matrix is singular: a coordinate has no inertia, or "
                             "constraints are redundant") from exc
        acc[free] = x[:free.size]
        lam = x[free.size:]
        reaction = np.zeros(0)
        if pres.size:
            full = mass @ acc - force
            if m:
                full = full + (cq.T @ lam if not sps.issparse(cq) else cq.T @ lam)
            reaction = full[pres]
        return self.make_state(state.t, state.q, state.v, acc=acc, pseudo=acc.copy(), lam=lam,
                               prescribed_force=reaction)

    def make_state(self, t, q, v, **values):
        """This scheme's state (:attr:`state_type`) at time ``t`` (s) from (q, v) and the named values it
        carries; values it does not carry (``pseudo`` for energy-momentum) are left out."""
        names = {f.name for f in fields(self.state_type)}
        return self.state_type(float(t), q, v, **{k: x for k, x in values.items() if k in names})

    # ---------------------------------------------------------------- Newton
    def _newton(self, fun, x0, where, x_scale=0.0):
        """Solve fun(x) = 0 by the Newton core (:func:`skfem_flex.numerics.newton.newton_solve`) with this scheme's settings and name."""
        return newton_solve(fun, x0, self.newton, self.name, where, x_scale)

    def step(self, scene, state, dt):
        """Advance ``state`` by ``dt``; returns (new State, StepInfo)."""
        raise NotImplementedError


class EnergyMomentum(Integrator):
    """Energy-conserving discrete-gradient midpoint scheme (``"energy-momentum"``).

    See the module docstring for the equations. Prescribed coordinates take
    q1 from their law and v1 = 2Δq/Δt − v0 (so that v̄ Δt = Δq holds for
    every coordinate, which the exact energy identity needs); their residual
    rows are the impulse the law exerts, and its work v̄_P · r_P enters the
    external work.
    """

    name = "energy-momentum"

    def step(self, scene, state, dt):
        q0, v0, t0 = state.q, state.v, state.t
        t1, tm = t0 + dt, t0 + 0.5 * dt
        free, pres = scene.free_index, scene.prescribed_index
        nf, m = free.size, scene.n_constraints
        cay = getattr(scene, "cayley_index", _NO_INDEX)
        dq_base = np.zeros(scene.n)
        if pres.size:
            dq_base[pres] = scene.prescribed_state(t1)[0] - q0[pres]
        p0 = scene.momentum(q0, v0)
        p0_inf = _inf(p0)
        e_scale0 = abs(scene.kinetic_energy(q0, v0))
        rows_c = np.arange(m)
        s = self.newton
        cache = {}

        def fun(x):
            dq = dq_base.copy()
            dq[free] = x[:nf]
            mu = x[nf:]
            q1 = q0 + dq
            if cay.size:
                z, cay_terms = _cayley_rates(dq, cay, t1, dt)
            else:
                z, cay_terms = dq, None
            v1 = (2.0 / dt) * z - v0
            # one fused scene call: p1 = M(q1) v1, the discrete gradients of G and V, the tangent
            # (2/Δt) M + B − Δt ∂g_G/∂q1 − 2 ∂g_G/∂v1 + Δt ∂g_V/∂q1, and the round-off floor
            # Δt |∂g_V/∂q1| (|q0| + |q1|) of the stiff internal forces (K q cancels: |K||q| >> |K q|)
            p1, g_kin, g, jac, floor, kin1 = scene.energy_momentum_terms(q0, q1, v0, v1, dt)
            if cay_terms is not None:
                jac_mass = scene.mass_matrix(q1) * (2.0 / dt)
                force_jac = add_matrices(jac, -jac_mass)
            r = p1 - p0
            scale = max(_inf(p1), p0_inf)
            dg = dt * g
            if g_kin is not None:
                dg = dg - dt * g_kin
                scale = max(scale, dt * _inf(g_kin))
            scale = max(scale, dt * _inf(g))
            if m:
                d = scene.constraint_discrete_gradient(q0, q1, tm)
                dtmu = d.T @ mu
                dg = dg + dtmu
                scale = max(scale, _inf(dtmu))
                dmu_jac = scene.constraint_discrete_gradient_jacobian(q0, q1, mu, tm)
                if cay_terms is None:
                    jac = add_matrices(jac, dmu_jac)
                else:
                    force_jac = add_matrices(force_jac, dmu_jac)
            else:
                d = None
            if cay_terms is not None:
                # discrete gradients are conjugate to Δq; conjugate to the Cayley rates z they are
                # S·(·) with S = diag(Δψ/w) (same work S·f·z = f·Δq, now equivariant), and the
                # mass part sees ∂v1/∂Δq = (2/Δt) diag(dz/dΔq)
                ratio, dratio, dz = cay_terms
                jac = add_matrices(_scale_columns(jac_mass, dz), _scale_rows(force_jac, ratio))
                jac = add_matrices(jac, _diagonal(dg * dratio, scene.dense))
                dg = ratio * dg
                floor = ratio * floor
                d = _scale_columns(d, ratio) if d is not None else None
            r += dg
            ext = scene.external_force(q0 + 0.5 * dq, z / dt, tm) if scene.loads else None
            if ext is not None:
                r -= dt * ext[0]
                jac = add_matrices(jac, -(0.5 * dt * ext[1] + (ext[2] if cay_terms is None
                                                               else _scale_columns(ext[2], cay_terms[2]))))
                scale = max(scale, dt * _inf(ext[0]))
            if m:
                c = scene.constraint_value(q1, t1)
                cq = scene.constraint_jacobian(q1, t1)
                c_scale = max(_inf(abs(cq) @ np.abs(q1)), _inf(abs(cq)) * scene.length_scale, _TINY)
                full = _bordered(_sub_block(jac, free, free), _sub_block(d, rows_c, free).T,
                                 _sub_block(cq, rows_c, free), scene.dense)
                res = np.concatenate([r[free], c])
                err_c = _inf(c) / (s.ctol * c_scale)
            else:
                full, res, err_c = _sub_block(jac, free, free), r[free], 0.0
            vbar = z / dt
            e_scale = max(e_scale0, abs(kin1), abs(float(z @ (ratio * g if cay_terms is not None else g))), _TINY)
            r_free, vbar_free = r[free], vbar[free]
            r_inf, vr = _inf(r_free), abs(float(vbar_free @ r_free))
            err = max(r_inf / (s.rtol * max(scale, _TINY)), err_c, vr / (s.etol * e_scale))
            # within what round-off lets r and v̄·r reach (measured: ≈ 0.5 ε |floor|, ≤ 0.3 ε |v̄|·|floor|),
            # the core may accept the step once Newton stagnates (start from rest, very stiff beams)
            err = roundoff_floor(err, err_c, r_inf, _inf(floor[free]), vr, float(np.abs(vbar_free) @ floor[free]))
            cache.update(dq=dq, z=z, mu=mu, q1=q1, v1=v1, r=r, d=d, ext=ext)
            return res, full, err

        dq_guess = np.empty(nf)
        predicted_increment(np.asarray(v0, dtype=float), predictor_acceleration(state), float(dt),
                            np.asarray(free, dtype=np.int64), dq_guess)
        if cay.size:                    # the Cayley rate of the last step, continued: Δψ = 2 atan(Δt ω0/2)
            on = np.isin(free, cay)
            dq_guess[on] = 2.0 * np.arctan(0.5 * dq_guess[on])
        x0 = np.concatenate([dq_guess, state.lam * dt if state.lam.size == m else np.zeros(m)])
        # a step from rest in a stressed equilibrium (a run started from statics) has Δq ≈ 0 and a
        # residual at the round-off floor of the internal forces: updates are judged against q
        x, _, its = self._newton(fun, x0, f"t = {t1:.6g} s (dt = {dt:.3g} s)", _inf(q0[free]))
        dq, z, mu, q1, v1, r, d, ext = (cache[k] for k in ("dq", "z", "mu", "q1", "v1", "r", "d", "ext"))
        work = 0.0
        if ext is not None:
            work += float(z @ ext[0])
        if m:
            work -= float(mu @ (d @ z)) / dt         # μ = Δt λ̄: the work is −λ̄·ΔΦ
        reaction = np.zeros(0)
        if pres.size:
            reaction = r[pres] / dt
            work += float(z[pres] @ reaction)
        new = State(t1, q1, v1, acc=(v1 - v0) / dt, lam=mu / dt, prescribed_force=reaction)
        vres = 0.0
        if m:
            vres = _inf(scene.constraint_jacobian(q1, t1) @ v1 + scene.constraint_time_derivative(q1, t1))
        return new, StepInfo(its, work, vres)


_NO_INDEX = np.zeros(0, dtype=int)


def predictor_acceleration(state):
    """a0 of the energy-momentum step's Newton start (:func:`skfem_flex.numerics.newton.predicted_increment`):
    ``state.acc``, which after an energy-momentum step is the step's mean acceleration (v1 − v0)/Δt;
    zeros without one."""
    if state.acc is not None and np.size(state.acc) == np.size(state.v):
        return np.ascontiguousarray(state.acc, dtype=float)
    return np.zeros(np.size(state.v))


def _cayley_rates(dq, cay, t1, dt):
    """z = Δq with z = 2 tan(Δψ/2) on the Cayley coordinates, and (Δψ/w, d(Δψ/w)/dΔψ, dz/dΔq) as full vectors."""
    x = dq[cay]
    big = np.abs(x) >= MAX_INCREMENT
    if np.any(big):
        raise ConvergenceError(f"an angle with Cayley rate turns by {np.abs(x).max():.3g} rad in one step at "
                               f"t = {t1:.6g} s (dt = {dt:.3g} s); 2 tan(Δψ/2) needs |Δψ| < π",
                               iterations=0, residual=float("inf"))
    z = dq.copy()
    z[cay] = cayley(x)
    ratio = np.ones(dq.size)
    ratio[cay] = cayley_ratio(x)
    dratio = np.zeros(dq.size)
    dratio[cay] = cayley_ratio_derivative(x)
    dz = np.ones(dq.size)
    dz[cay] = cayley_derivative(x)
    return z, (ratio, dratio, dz)


def _scale_rows(a, s):
    """diag(s) a (dense or sparse)."""
    return sps.diags(s) @ a if sps.issparse(a) else a * s[:, None]


def _scale_columns(a, s):
    """a diag(s) (dense or sparse)."""
    return a @ sps.diags(s) if sps.issparse(a) else a * s[None, :]


def _diagonal(s, dense):
    return np.diag(s) if dense else sps.diags(s, format="csr")


class Newmark(Integrator):
    """Newmark family in generalized-α form (Chung & Hulbert 1993; Arnold & Brüls 2007).

    Parameters
    ----------
    alpha_m, alpha_f, beta, gamma : float
        Algorithmic parameters.
    constraint_level : {"position", "velocity"}
        Enforce Φ(q_{n+1}, t_{n+1}) = 0 (index 3) or Φ_q v_{n+1} + Φ_t = 0
        (index 2). The velocity-level row is multiplied by βΔt/γ, so that
        its Jacobian is Φ_q + (βΔt/γ) ∂(Φ_q v)/∂q, the same size as the
        position-level one (∂Φ_t/∂q is left out: zero for drivers).
    newton : NewtonSettings, optional
    """

    name = "newmark"
    state_type = NewmarkState

    def __init__(self, alpha_m=0.0, alpha_f=0.0, beta=0.25, gamma=0.5, newton=None, constraint_level="position"):
        super().__init__(newton)
        self.alpha_m, self.alpha_f, self.beta, self.gamma = map(float, (alpha_m, alpha_f, beta, gamma))
        if constraint_level not in ("position", "velocity"):
            raise ValueError(f"constraint_level must be 'position' or 'velocity', got {constraint_level!r}")
        self.constraint_level = constraint_level

    def step(self, scene, state, dt):
        am, af, beta, gamma = self.alpha_m, self.alpha_f, self.beta, self.gamma
        q0, v0, t0 = state.q, state.v, state.t
        if getattr(state, "pseudo", None) is None:
            raise ValueError(f"a {self.name} step needs a NewmarkState with its algorithmic acceleration (from "
                             f"start()), got {type(state).__name__}")
        a0, x0acc = state.pseudo, state.acc
        t1 = t0 + dt
        free, pres = scene.free_index, scene.prescribed_index
        nf, m = free.size, scene.n_constraints
        qp, vp, ap = scene.prescribed_state(t1)
        c_a = (1.0 - am) / ((1.0 - af) * beta * dt * dt)
        c_v = gamma / (beta * dt)
        rows_c = np.arange(m)
        by_velocity = self.constraint_level == "velocity"
        s = self.newton
        cache = {}

        def fun(x):
            dq = np.zeros(scene.n)
            dq[free] = x[:nf]
            if pres.size:
                dq[pres] = qp - q0[pres]
            mu = x[nf:]
            q1 = q0 + dq
            a1 = (dq - dt * v0 - dt * dt * (0.5 - beta) * a0) / (beta * dt * dt)
            v1 = v0 + dt * ((1.0 - gamma) * a0 + gamma * a1)
            acc1 = ((1.0 - am) * a1 + am * a0 - af * x0acc) / (1.0 - af)
            if pres.size:
                v1[pres], acc1[pres], a1[pres] = vp, ap, ap
            mass = scene.mass_matrix(q1)
            inertia = mass @ acc1
            grad = scene.potential_gradient(q1)
            r = dt * (inertia + grad)
            jac = add_matrices(mass * (dt * c_a), dt * scene.potential_hessian(q1))
            # the acceleration is a difference of O(|Δq|/(βΔt²)) terms that cancel when q̈ is small:
            # their size, not the net inertia force, sets the round-off floor of the residual
            terms = np.abs(dq) + dt * np.abs(v0) + dt * dt * abs(0.5 - beta) * np.abs(a0)
            scale = max(_inf(inertia), _inf(grad), c_a * _inf(abs(mass) @ terms))
            qv = scene.quadratic_velocity_force(q1, v1)
            if qv is not None:
                r -= dt * qv[0]
                jac = add_matrices(jac, dt * scene.momentum_jacobian(q1, acc1))
                jac = add_matrices(jac, -dt * (qv[1] + c_v * qv[2]))
                scale = max(scale, _inf(qv[0]))
            ext = scene.external_force(q1, v1, t1) if scene.loads else None
            if ext is not None:
                r -= dt * ext[0]
                jac = add_matrices(jac, -dt * (ext[1] + c_v * ext[2]))
                scale = max(scale, _inf(ext[0]))
            scale *= dt
            if m:
                cq = scene.constraint_jacobian(q1, t1)
                ctmu = cq.T @ mu
                r += ctmu
                scale = max(scale, _inf(ctmu))
                jac = add_matrices(jac, scene.constraint_hessian_product(q1, mu, t1))
                c_scale = max(_inf(abs(cq) @ np.abs(q1)), _inf(abs(cq)) * scene.length_scale, _TINY)
                if by_velocity:
                    # (βΔt/γ)(Φ_q v1 + Φ_t): a length, like Φ, so the same scale and tolerance apply
                    phit = scene.constraint_time_derivative(q1, t1)
                    c = (cq @ v1 + phit) / c_v
                    c_scale = max(c_scale, _inf(abs(cq) @ np.abs(v1)) / c_v, _inf(phit) / c_v)
                    cq_c = add_matrices(cq, scene.constraint_velocity_jacobian(q1, v1, t1) / c_v)
                else:
                    c, cq_c = scene.constraint_value(q1, t1), cq
                cq_f = _sub_block(cq_c, rows_c, free)
                full = _bordered(_sub_block(jac, free, free), _sub_block(cq, rows_c, free).T, cq_f, scene.dense)
                res = np.concatenate([r[free], c])
                err_c = _inf(c) / (s.ctol * c_scale)
            else:
                full, res, err_c, cq = _sub_block(jac, free, free), r[free], 0.0, None
            err = max(_inf(r[free]) / (s.rtol * max(scale, _TINY)), err_c)
            cache.update(dq=dq, mu=mu, q1=q1, v1=v1, a1=a1, acc1=acc1, r=r, ext=ext, cq=cq)
            return res, full, err

        lam0 = state.lam if state.lam.size == m else np.zeros(m)
        x0 = np.concatenate([dt * v0[free] + 0.5 * dt * dt * x0acc[free], dt * lam0])
        # a step from rest in a stressed equilibrium (a run started from statics) has Δq ≈ 0 and a
        # residual at the round-off floor of the internal forces: updates are judged against q
        x, _, its = self._newton(fun, x0, f"t = {t1:.6g} s (dt = {dt:.3g} s)", _inf(q0[free]))
        dq, mu, q1, v1, a1, acc1, r, ext, cq = (cache[k] for k in
                                                ("dq", "mu", "q1", "v1", "a1", "acc1", "r", "ext", "cq"))
        lam1 = mu / dt
        work = 0.0
        if ext is not None:
            ext0 = scene.external_force(q0, v0, t0)[0]
            work += float(dq @ (0.5 * (ext0 + ext[0])))
        reaction = np.zeros(0)
        if pres.size:
            reaction = r[pres] / dt
            prev = state.prescribed_force if state.prescribed_force.size == pres.size else reaction
            work += float(dq[pres] @ (0.5 * (prev + reaction)))
        vres = 0.0
        if m:
            phit1 = scene.constraint_time_derivative(q1, t1)
            vres = _inf(cq @ v1 + phit1)
            if any(c.rheonomic for c in scene.constraints):
                phit0 = scene.constraint_time_derivative(q0, t0)
                lam_prev = state.lam if state.lam.size == m else lam1
                work += 0.5 * dt * float(lam_prev @ phit0 + lam1 @ phit1)
        new = NewmarkState(t1, q1, v1, acc=acc1, pseudo=a1, lam=lam1, prescribed_force=reaction)
        return new, StepInfo(its, work, vres)


class Trapezoidal(Newmark):
    """Average-acceleration Newmark (β = ¼, γ = ½) with velocity-level constraints, ``"trapezoidal"``.

    Index 2, as the established multibody codes run the trapezoidal rule:
    Φ_q(q_{n+1}) v_{n+1} + Φ_t(t_{n+1}) = 0. The position-level (index-3)
    form is ``Newmark(constraint_level="position")``; it drives the
    multipliers into a growing zigzag on a swinging pendulum.
    """

    name = "trapezoidal"

    def __init__(self, newton=None):
        super().__init__(0.0, 0.0, 0.25, 0.5, newton, constraint_level="velocity")


class GeneralizedAlpha(Newmark):
    """Chung–Hulbert generalized-α with spectral radius ρ∞ at infinite frequency.

    α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), γ = ½ − α_m + α_f,
    β = ¼ (γ + ½)².

    Parameters
    ----------
    rho_inf : float
        ρ∞ in [0, 1]; 1 keeps every frequency, 0 annihilates the highest.
    """

    name = "generalized-alpha"

    def __init__(self, rho_inf=0.9, newton=None):
        rho = float(rho_inf)
        if not (np.isfinite(rho) and 0.0 <= rho <= 1.0):
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf!r}")
        am = (2.0 * rho - 1.0) / (rho + 1.0)
        af = rho / (rho + 1.0)
        gamma = 0.5 - am + af
        super().__init__(am, af, 0.25 * (gamma + 0.5) ** 2, gamma, newton)
        self.rho_inf = rho


INTEGRATORS = {
    "energy-momentum": EnergyMomentum,
    "trapezoidal": Trapezoidal,
    "generalized-alpha": GeneralizedAlpha,
}


def make_integrator(integrator, rho_inf=None, newton=None):
    """An :class:`Integrator` from a name or an instance.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones) or ρ∞ given
        to a scheme that has none.
    """
    if isinstance(integrator, Integrator):
        # a scheme object carries its own parameters; a second, ignored copy would be a silent error
        for name, value in (("rho_inf", rho_inf), ("newton", newton)):
            if value is not None:
                raise ValueError(f"{name}={value!r} given with the scheme object {type(integrator).__name__}; "
                                 f"set it on the object instead (e.g. GeneralizedAlpha(rho_inf=0.8, newton=...))")
        return integrator
    if not isinstance(integrator, str) or integrator not in INTEGRATORS:
        raise ValueError(f"unknown integrator {integrator!r}; choose one of {sorted(INTEGRATORS)}")
    if integrator == "generalized-alpha":
        return GeneralizedAlpha(0.9 if rho_inf is None else rho_inf, newton=newton)
    if rho_inf is not None:
        raise ValueError(f"rho_inf applies to generalized-alpha only, not to {integrator!r}")
    return INTEGRATORS[integrator](newton=newton)
