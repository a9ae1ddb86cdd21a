r"""The floating frame of reference (FFR) algebra shared by every floating-frame body.

A floating-frame body has reference coordinates q_r = (R_x, R_y, θ) and elastic coordinates
q_f whose displacement field is linear in q_f: a material point with body-frame position X
(and, for beams, a cross-section angle) is at

.. math::

    r(X) = R + A(θ)\,(X + S(X)\,q_f).

Its kinetic energy T = ½ q̇ᵀ M(q) q̇ is then fixed by a handful of inertia invariants, all
integrals over the undeformed body computed once (the ρ of a beam is ρA, and beams add the
rotary inertia ρI of the cross-section, which only enters J_r, n_φ and M_I):

=========  ==========================  ==========================================
symbol     integral                    meaning
=========  ==========================  ==========================================
m          ∫ρ                          mass
S_0        ∫ρ X                        first moment of the undeformed body
I_0        ∫ρ |X|² + J_r               polar moment about the frame origin
S̄          ∫ρ S                        first moment per elastic coordinate
c          ∫ρ Sᵀ X                     centrifugal load per unit ω²
k_0n       ∫ρ Sᵀ E X + n_φ             rotation–elastic coupling
M_A        ∫ρ Sᵀ S                     translational elastic mass
H          ∫ρ Sᵀ E S                   skew (Coriolis) coupling
M_ff       M_A + M_I                   elastic mass
=========  ==========================  ==========================================

(E the 90° rotation.) With s̄ = S_0 + S̄ q_f, c_m = c + M_A q_f, a = k_0n + H q_f and
J = I_0 + 2 cᵀq_f + q_fᵀ M_A q_f::

    M = [[m I,   A E s̄,  A S̄ ],
         [  ·,     J,     aᵀ  ],
         [  ·,     ·,    M_ff ]]

M is a polynomial of degree ≤ 2 in q_f and carries θ only through A(θ), so the discrete
gradient of G(q) = ½ v₀ᵀ M(q) v₁ between two states has the exact closed form of
:meth:`FloatingFrame.kinetic_discrete_gradient` (identities A(θ₁) − A(θ₀) =
sinc(Δθ/2) A(θ_m) E Δθ and (A(θ₀) + A(θ₁))/2 = cos(Δθ/2) A(θ_m)). The same holds for
gravity and for every material point (:class:`FramePoint`), whose position is linear in q_f.

:class:`FloatingFrame` holds this algebra once; :class:`~skfem_flex.bodies.FloatingBeam`
(nodal beam coordinates) and :class:`~skfem_flex.bodies.modal.body.ModalBody` (any linear field
u = Φ η: reduced beams, plane-stress bodies) are its subclasses and only supply the
invariants, a strain energy and geometry. Derivation: docs/flexible_bodies.md.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from .base import Body, BodyPoint
from .floating.kernel import sinc_half
from .rigid import E_MATRIX as E2, rotation as _rot

__all__ = ["FloatingFrame", "FramePoint", "InertiaInvariants"]

#: the inertia invariants of a floating-frame body (table in the module docstring), as
#: :attr:`FloatingFrame.invariants` hands them out
InertiaInvariants = namedtuple("InertiaInvariants", "mass S0 I0 Sbar c k0n MA H Mff")
#: intermediates of the kinetic discrete gradient shared by the contract method and the fused time-loop call
_KineticTerms = namedtuple("_KineticTerms", "g sig dsig kap dkap ca sa smx smy cmm w0 w1 b0x b0y b1x b1y "
                                            "c0x c0y c1x c1y Hf0 Hf1 X SbEwb SbTwb")


def _cross(a, b):
    return float(a[0] * b[1] - a[1] * b[0])


class FloatingFrame(Body):
    """Kinetic energy, gravity and material points of a floating-frame body from its invariants.

    Subclasses call :meth:`set_invariants` once (and set ``elastic_blocks``, the dict of dense
    elastic blocks "MA", "H", "Mff", "K" that :meth:`compose_matrix` sums) and then have ``mass_matrix``,
    ``momentum_jacobian``, ``quadratic_velocity_force``, ``kinetic_discrete_gradient``,
    gravity and momenta. Coordinates are (R_x, R_y, θ, q_f). Matrices are dense unless the
    subclass overrides :meth:`compose_matrix` (FloatingBeam does, for sparse bodies).
    """

    constant_mass = False
    sparse = False

    def set_invariants(self, mass, S0, I0, Sbar, c, k0n, MA, H, Mff):
        """Store the inertia invariants (table in the module docstring) and the products built from them.

        ``MA``, ``H``, ``Mff`` are dense arrays, or scipy.sparse when ``self.sparse``."""
        import scipy.sparse as sps
        nf = self.n_elastic
        self.mass_total = float(mass)
        self._S0 = np.asarray(S0, dtype=float).copy()
        self._I0 = float(I0)
        self._Sbar = np.asarray(Sbar, dtype=float).reshape(2, nf)
        self._c = np.asarray(c, dtype=float).copy()
        self._k0n = np.asarray(k0n, dtype=float).copy()
        self._MA, self._H, self._Mff = MA, H, Mff
        self._SbarT = self._Sbar.T.copy()
        self._SbEt = self._SbarT @ E2.T                  # S̄ᵀEᵀ, (nf, 2)
        stack = sps.vstack if self.sparse else np.vstack
        self._Pq = stack([self._Sbar, self._MA, self._H])  # q_f -> (S̄ q_f, M_A q_f, H q_f)
        self._Pf = stack([self._Sbar, self._H])            # f -> (S̄ f, H f)
        if self.sparse:
            self._Pq, self._Pf = self._Pq.tocsr(), self._Pf.tocsr()
        self._top_template = np.zeros((3, 3 + nf))
        self._top_template[:2, :2] = self.mass_total * np.eye(2)
        self._cache_key, self._cache_val = None, None

    @property
    def invariants(self):
        """The inertia invariants m, S_0, I_0, S̄, c, k_0n, M_A, H, M_ff (table in the module docstring) as an
        :class:`InertiaInvariants`; M_A, H, M_ff dense or scipy.sparse as the body stores them."""
        return InertiaInvariants(self.mass_total, self._S0, self._I0, self._Sbar, self._c, self._k0n, self._MA,
                                 self._H, self._Mff)

    def compose_matrix(self, top, left, terms=(), extra=None, loc=None):
        """Dense n × n matrix from its reference rows ``top`` (3, n), the block ``left`` (nf, 3)
        below them and an elastic block Σ coef · X[key] for ``terms`` = [(coef, key)], key in
        ``self.elastic_blocks``, plus a dense ``extra`` (nf, nf). ``top``/``left`` None mean zero."""
        n = self.n_dofs
        out = np.zeros((n, n))
        if top is not None:
            out[:3] = top
        if left is not None:
            out[3:, :3] = left
        ff = out[3:, 3:]
        for coef, key in terms:
            ff += coef * self.elastic_blocks[key]
        if extra is not None:
            ff += extra
        return out

    # ================================================================ kinetic
    def _parts(self, q):
        """(A, q_f, s̄, c_m = c + M_A q_f, a = k0 + n_φ + H q_f, J) at q; one-entry cache (Newton
        evaluates M, p, B at the same q several times per iteration)."""
        key = q.tobytes()
        if key == self._cache_key:
            return self._cache_val
        A = _rot(q[2])
        qf = np.array(q[3:], dtype=float)
        y = self._Pq @ qf
        nf = self.n_elastic
        sbar = self._S0 + y[:2]
        cm = self._c + y[2:2 + nf]
        a = self._k0n + y[2 + nf:]
        J = self._I0 + float(qf @ (self._c + cm))
        self._cache_key, self._cache_val = key, (A, qf, sbar, cm, a, J)
        return self._cache_val

    def mass_matrix(self, q):
        """M(q) (eq. 16), kg, kg m, kg m²."""
        A, qf, sbar, cm, a, J = self._parts(q)
        AEs = A @ (E2 @ sbar)
        ASb = A @ self._Sbar
        top = self._top_template.copy()
        top[:2, 2] = AEs
        top[:2, 3:] = ASb
        top[2, :2] = AEs
        top[2, 2] = J
        top[2, 3:] = a
        left = np.empty((self.n_elastic, 3))
        left[:, :2] = ASb.T
        left[:, 2] = a
        return self.compose_matrix(top, left, [(1.0, "Mff")])

    def momentum_jacobian(self, q, v):
        """B(q, v) = ∂(M(q) v)/∂q."""
        A, qf, sbar, cm, a, J = self._parts(q)
        V, om, f = v[:2], float(v[2]), v[3:]
        n = self.n_dofs
        b = A.T @ V
        AE = A @ E2
        Sf = self._Sbar @ f
        SbEb = self._SbEt @ b
        top = np.zeros((3, n))
        top[:2, 2] = -om * (A @ sbar) + AE @ Sf
        top[:2, 3:] = om * (AE @ self._Sbar)
        top[2, 2] = -float(b @ sbar)
        top[2, 3:] = SbEb + 2.0 * om * cm - self._H @ f
        left = np.zeros((self.n_elastic, 3))
        left[:, 2] = SbEb
        return self.compose_matrix(top, left, [(om, "H")])

    def quadratic_velocity_force(self, q, v):
        """Q_v = ∂T/∂q − Ṁ v (eq. 26) with ∂Q_v/∂q and ∂Q_v/∂v."""
        A, qf, sbar, cm, a, J = self._parts(q)
        om, f = float(v[2]), v[3:]
        n = self.n_dofs
        AE = A @ E2
        Sf = self._Sbar @ f
        Hf = self._H @ f
        g = np.empty(n)
        inner = om * om * sbar - 2.0 * om * (E2 @ Sf)
        g[:2] = A @ inner
        g[2] = -2.0 * om * float(cm @ f)
        g[3:] = om * om * cm - 2.0 * om * Hf
        tq = np.zeros((3, n))
        tq[:2, 2] = AE @ inner
        tq[:2, 3:] = om * om * (A @ self._Sbar)
        tq[2, 3:] = -2.0 * om * (self._MA @ f)
        gq = self.compose_matrix(tq, None, [(om * om, "MA")])
        tv = np.zeros((3, n))
        tv[:2, 2] = A @ (2.0 * om * sbar - 2.0 * (E2 @ Sf))
        tv[:2, 3:] = -2.0 * om * (AE @ self._Sbar)
        tv[2, 2] = -2.0 * float(cm @ f)
        tv[2, 3:] = -2.0 * om * cm
        lv = np.zeros((self.n_elastic, 3))
        lv[:, 2] = 2.0 * om * cm - 2.0 * Hf
        gv = self.compose_matrix(tv, lv, [(-2.0 * om, "H")])
        return g, gq, gv

    def _kinetic_terms(self, q0, q1, v0, v1, yf0, yf1):
        """Value and intermediates of the kinetic discrete gradient (formulas in kinetic_discrete_gradient).

        ``yf_i`` = P_f f_i = (S̄ f_i, H f_i) for the elastic velocities f_i of v_i.
        """
        nf = self.n_elastic
        d = float(q1[2] - q0[2])
        tm = 0.5 * float(q0[2] + q1[2])
        ca, sa = math.cos(tm), math.sin(tm)
        sig, dsig = sinc_half(d)
        kap, dkap = math.cos(0.5 * d), -0.5 * math.sin(0.5 * d)
        y = self._Pq @ (0.5 * (q0[3:] + q1[3:]))
        smx, smy = self._S0[0] + y[0], self._S0[1] + y[1]
        cmm = self._c + y[2:2 + nf]
        w0, w1 = float(v0[2]), float(v1[2])
        b0x, b0y = ca * v0[0] + sa * v0[1], -sa * v0[0] + ca * v0[1]
        b1x, b1y = ca * v1[0] + sa * v1[1], -sa * v1[0] + ca * v1[1]
        Hf0, Hf1 = yf0[2:], yf1[2:]
        c0x, c0y = -w0 * smy + yf0[0], w0 * smx + yf0[1]     # c_i = ω_i E s̄_m + S̄ f_i
        c1x, c1y = -w1 * smy + yf1[0], w1 * smx + yf1[1]
        X = (-b0x * c1y + b0y * c1x) + (-b1x * c0y + b1y * c0x)  # b0·E c1 + b1·E c0
        wb = np.array([w1 * b0x + w0 * b1x, w1 * b0y + w0 * b1y])
        SbEwb = self._SbEt @ wb
        SbTwb = self._SbarT @ wb
        g = np.zeros(self.n_dofs)
        g[2] = 0.5 * sig * X
        g[3:] = 0.5 * kap * SbEwb + (w0 * w1) * cmm - 0.5 * (w0 * Hf1 + w1 * Hf0)
        return _KineticTerms(g, sig, dsig, kap, dkap, ca, sa, smx, smy, cmm, w0, w1, b0x, b0y, b1x, b1y,
                             c0x, c0y, c1x, c1y, Hf0, Hf1, X, SbEwb, SbTwb)

    def kinetic_discrete_gradient(self, q0, q1, v0, v1):
        """Exact discrete gradient of G(q) = ½ v0ᵀ M(q) v1 with its derivatives (docs/flexible_bodies.md §1).

        With b_i = A(θ_m)ᵀ Ṙ_i, s̄_m = s̄(q_f,m), c_i = ω_i E s̄_m + S̄ f_i, σ = sinc(Δθ/2), κ = cos(Δθ/2)::

            g_R = 0,   g_θ = ½ σ (b_0·E c_1 + b_1·E c_0)
            g_f = ½ κ S̄ᵀEᵀ(ω_1 b_0 + ω_0 b_1) + ω_0 ω_1 (c + M_A q_f,m) − ½ H (ω_0 f_1 + ω_1 f_0)

        The derivatives include those of σ and κ (exact tangent).
        """
        n, nf = self.n_dofs, self.n_elastic
        yf = self._Pf @ np.stack([v0[3:], v1[3:]], axis=1)   # (2 + nf, 2): S̄ f_i, H f_i
        (g, sig, dsig, kap, dkap, ca, sa, smx, smy, cmm, w0, w1, b0x, b0y, b1x, b1y,
         c0x, c0y, c1x, c1y, Hf0, Hf1, X, SbEwb, SbTwb) = self._kinetic_terms(q0, q1, v0, v1, yf[:, 0], yf[:, 1])
        tq = np.zeros((3, n))
        tq[2, 2] = 0.5 * dsig * X - 0.25 * sig * (b0x * c1x + b0y * c1y + b1x * c0x + b1y * c0y)
        tq[2, 3:] = -0.25 * sig * SbTwb
        lq = np.zeros((nf, 3))
        lq[:, 2] = 0.5 * dkap * SbEwb - 0.25 * kap * SbTwb
        gq = self.compose_matrix(tq, lq, [(0.5 * w0 * w1, "MA")])
        SbEb0 = self._SbEt @ np.array([b0x, b0y])
        tv = np.zeros((3, n))
        e0x, e0y = -c0y, c0x                                       # E c_0, then A_m E c_0
        tv[2, 0] = 0.5 * sig * (ca * e0x - sa * e0y)
        tv[2, 1] = 0.5 * sig * (sa * e0x + ca * e0y)
        tv[2, 2] = -0.5 * sig * (b0x * smx + b0y * smy)
        tv[2, 3:] = 0.5 * sig * SbEb0
        lv = np.zeros((nf, 3))
        lv[:, :2] = (0.5 * kap * w0) * (self._SbEt @ np.array([[ca, sa], [-sa, ca]]))
        lv[:, 2] = 0.5 * kap * SbEb0 + w0 * cmm - 0.5 * Hf0
        gv = self.compose_matrix(tv, lv, [(-0.5 * w0, "H")])
        return g, gq, gv


    # ================================================================ frame-linear maps
    def _lin_parts(self, q, y0, Y):
        A = _rot(q[2])
        return A, y0 + Y @ q[3:]

    def _map_hessian(self, q, f, y0, Y):
        """∂/∂q of (∂r/∂q)ᵀ f for r = R + A(θ)(y0 + Y q_f)."""
        A, s = self._lin_parts(q, y0, Y)
        top = np.zeros((3, self.n_dofs))
        top[2, 2] = -float(f @ (A @ s))
        row = (f @ (A @ E2)) @ Y
        top[2, 3:] = row
        left = np.zeros((self.n_elastic, 3))
        left[:, 2] = row
        return self.compose_matrix(top, left)

    def _map_dg(self, q0, q1, y0, Y, mR=1.0):
        """D (2, n) with D (q1 − q0) = r(q1) − r(q0), r = mR R + A(θ)(y0 + Y q_f)."""
        d = q1[2] - q0[2]
        Am = _rot(0.5 * (q0[2] + q1[2]))
        sig, _ = sinc_half(d)
        sm = y0 + Y @ (0.5 * (q0[3:] + q1[3:]))
        D = np.empty((2, self.n_dofs))
        D[:, :2] = mR * np.eye(2)
        D[:, 2] = sig * (Am @ (E2 @ sm))
        D[:, 3:] = math.cos(0.5 * d) * (Am @ Y)
        return D

    def _map_dg_jacobian(self, q0, q1, f, y0, Y):
        """∂(Dᵀ f)/∂q1 for :meth:`_map_dg`."""
        d = q1[2] - q0[2]
        Am = _rot(0.5 * (q0[2] + q1[2]))
        sig, dsig = sinc_half(d)
        kap = math.cos(0.5 * d)
        sm = y0 + Y @ (0.5 * (q0[3:] + q1[3:]))
        fA = f @ Am
        top = np.zeros((3, self.n_dofs))
        top[2, 2] = dsig * float(fA @ (E2 @ sm)) - 0.5 * sig * float(fA @ sm)
        top[2, 3:] = 0.5 * sig * ((fA @ E2) @ Y)
        left = np.zeros((self.n_elastic, 3))
        left[:, 2] = -0.5 * math.sin(0.5 * d) * (Y.T @ fA) + 0.5 * kap * (Y.T @ (E2.T @ fA))
        return self.compose_matrix(top, left)

    # ================================================================ gravity
    def mass_moment(self):
        """Not linear in q (the frame turns): gravity goes through :meth:`gravity_potential`."""
        raise NotImplementedError("FloatingBeam positions are not linear in q; use gravity_potential")

    def mass_moment_map(self):
        """(m, S₀, S̄) with ∫ r dm = m R + A(θ)(S₀ + S̄ q_f): kg, kg m (2,), kg (2, n_elastic).

        The first moment of mass as the compiled mechanism loop reads it (gravity)."""
        return self.mass_total, self._S0.copy(), self._Sbar.copy()

    def gravity_potential(self, q, g):
        """V = −g · ∫ρA r dx = −g · (m R + A s̄), with gradient and Hessian."""
        g = np.asarray(g, dtype=float)
        A, s = self._lin_parts(q, self._S0, self._Sbar)
        V = -float(g @ (self.mass_total * q[:2] + A @ s))
        grad = np.empty(self.n_dofs)
        grad[:2] = -self.mass_total * g
        grad[2] = -float(g @ (A @ (E2 @ s)))
        grad[3:] = -(self._Sbar.T @ (A.T @ g))
        return V, grad, self._map_hessian(q, -g, self._S0, self._Sbar)

    def gravity_discrete_gradient(self, q0, q1, g):
        """Exact discrete gradient of the gravity potential (sinc/cos identities), with ∂/∂q1."""
        g = np.asarray(g, dtype=float)
        D = self._map_dg(q0, q1, self._S0, self._Sbar, self.mass_total)
        return -(g @ D), self._map_dg_jacobian(q0, q1, -g, self._S0, self._Sbar)

    # ================================================================ momenta
    def linear_momentum(self, q, v):
        """∫ρ ṙ dV = p_R, kg m/s."""
        return self.momentum(q, v)[:2].copy()

    def angular_momentum(self, q, v):
        """∫ρ r × ṙ dV (+ rotary inertia) about the origin = R × p_R + p_θ, kg m²/s."""
        p = self.momentum(q, v)
        return _cross(q[:2], p[:2]) + float(p[2])


    # ================================================================ fused evaluation
    def compiled_kernel_data(self):
        """The packed arrays (:class:`~skfem_flex.bodies.floating.kernel.FloatingKernelData`) on which the
        compiled floating-frame kernels evaluate this body, or None if it has none (subclasses provide them).

        What the floating-frame family (:mod:`skfem_flex.compiled.families.floating_frame`) asks a body for; the kernels' reference is the numpy
        contract methods of the body."""
        return None

    def energy_momentum_terms(self, q0, q1, v0, v1, dt):
        """Everything one Newton evaluation of the energy-momentum scheme needs, in one call.

        The optional fused form of the body contract (the scene uses it when present): the same
        numbers as :meth:`mass_matrix`, :meth:`momentum_jacobian`, :meth:`kinetic_discrete_gradient`
        and :meth:`potential_discrete_gradient`, each evaluated once (FloatingBeam overrides it with
        its compiled kernel).

        Returns
        -------
        p1, g_kin, g_pot, jac, floor
            M(q1) v1; the discrete gradients of G = ½ v0ᵀ M v1 and of V;
            (2/Δt) M(q1) + B(q1, v1) − Δt ∂g_kin/∂q1 − 2 ∂g_kin/∂v1 + Δt ∂g_pot/∂q1;
            Δt |∂g_pot/∂q1| (|q0| + |q1|), the round-off floor of the internal forces.
        """
        M1 = self.mass_matrix(q1)
        gk, gq, gv = self.kinetic_discrete_gradient(q0, q1, v0, v1)
        gp, hp = self.potential_discrete_gradient(q0, q1)
        jac = (2.0 / dt) * M1 + self.momentum_jacobian(q1, v1) - dt * gq - 2.0 * gv + dt * hp
        floor = dt * (abs(hp) @ (np.abs(q0) + np.abs(q1)))
        return M1 @ v1, gk, gp, jac, floor

class FramePoint(BodyPoint):
    """A material point of a floating-frame body: r = R + A(θ)(y0 + S q_f), angle θ + N_φ q_f.

    Parameters
    ----------
    body : FloatingFrame
    y0 : array_like (2,)
        Undeformed position in the body frame, m.
    S : ndarray (2, n_elastic)
        Elastic displacement of the point per elastic coordinate.
    Nphi : ndarray (n_elastic,), optional
        Rotation of the point per elastic coordinate (rad); None: the point has no angle.
    """

    def __init__(self, body, y0, S, Nphi=None):
        self.body = body
        self.y0 = np.array(y0, dtype=float)
        self.S = np.asarray(S, dtype=float)
        self.has_angle = Nphi is not None
        self.Nphi = np.zeros(body.n_elastic) if Nphi is None else np.asarray(Nphi, dtype=float)
        grad = np.zeros(body.n_dofs)
        grad[2] = 1.0
        grad[3:] = self.Nphi
        self._angle_grad = grad

    def position(self, q):
        return q[:2] + _rot(q[2]) @ (self.y0 + self.S @ q[3:])

    def compiled_map(self):
        return "frame", 1.0, self.y0, self.S

    def position_jacobian(self, q):
        A = _rot(q[2])
        s = self.y0 + self.S @ q[3:]
        J = np.empty((2, self.body.n_dofs))
        J[:, :2] = np.eye(2)
        J[:, 2] = A @ (E2 @ s)
        J[:, 3:] = A @ self.S
        return J

    def position_hessian_product(self, q, f):
        return self.body._map_hessian(q, np.asarray(f, dtype=float), self.y0, self.S)

    def position_discrete_gradient(self, q0, q1):
        return self.body._map_dg(q0, q1, self.y0, self.S)

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        return self.body._map_dg_jacobian(q0, q1, np.asarray(f, dtype=float), self.y0, self.S)

    def angle(self, q):
        if not self.has_angle:
            return super().angle(q)
        return float(q[2] + self.Nphi @ q[3:])

    def angle_jacobian(self, q):
        if not self.has_angle:
            return super().angle_jacobian(q)
        return self._angle_grad.copy()
