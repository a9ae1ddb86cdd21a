r"""The strain measures of the geometrically exact beam on its strain points, and their energy.

:class:`StrainPoints` holds, for an :class:`~skfem_flex.bodies.exact.body.ExactBeam`, the reduced
Gauss rule of its mesh (shape functions, derivatives and weights at the strain points) and evaluates
there, vectorised over the elements, the strains, the strain energy, its gradient and Hessian and
the energy-conserving (equivariant) discrete gradient; it also holds the fixed scatter pattern of the
element matrices. :class:`ElementInversionError` is what it raises when an element folds inside out.

The body's coordinates are the global displacement u = r − X(s) of the axis from the straight
reference placement X(s) and the section rotation ψ = φ − α from the reference angle α. With
' = d/ds along the reference arc length s (the mesh coordinate) and t = (cos φ, sin φ),
n = (−sin φ, cos φ) the section's tangent and normal, the strain measures are

.. math::

    ε = t · r' − 1 = x' \cos φ + y' \sin φ − 1, \qquad
    γ = n · r' = −x' \sin φ + y' \cos φ, \qquad
    κ = φ',

zero in the straight, stress-free reference configuration (placed anywhere,
at any angle), and invariant under rigid motions. Strain and kinetic energy

.. math::

    V = ½ \int EA ε² + kGA γ² + EI κ² \, ds, \qquad
    T = ½ \int ρA (\dot x² + \dot y²) + ρI \dot φ² \, ds,

so the mass matrix is the constant consistent mass of the linear beam
(u_x, u_y, ψ play the roles of u, w, θ), assembled once by scikit-fem. The
strains are sampled on the reduced Gauss rule (one point per P1 element, two
per P2 element), which keeps slender beams free of shear and membrane
locking; for P1 the curvature is constant per element and exact.

Energy-conserving discrete gradient
-----------------------------------
Lee & Yun, eqs. (3b), (17)–(22): the section forces are taken at the
mean strain, f_m = C (e_0 + e_1)/2, and the strain increment is written
exactly through the incremental rotation. In the plane the incremental
rotation is one angle Δφ with Rodrigues/Cayley parameter w = W(Δφ) =
2 tan(Δφ/2) (:mod:`skfem_flex.numerics.rotations`); with \bar t = (t_0 + t_1)/2 and
\bar r' = (r_0' + r_1')/2,

.. math::

    t_1 − t_0 = w \, E \bar t, \qquad
    ε_1 − ε_0 = \bar t · Δr' + w_p \, (E \bar t · \bar r'), \qquad
    γ_1 − γ_0 = E \bar t · Δr' − w_p \, (\bar t · \bar r')

exactly at every strain point p (Simo, Tarnow & Doblaré 1995: \bar Λᵀ(Δr' −
w E \bar r')). The point's Cayley parameter w_p = W(Δφ_p), Δφ_p = Σ N_a Δφ_a,
and the curvature increment Δκ_p = Σ N_a' Δφ_a are written *exactly and
linearly* in the nodal parameters w_a = W(Δφ_a) by divided differences of W
about the element's first node a = 0 (W[x, y] = (W(x) − W(y))/(x − y) =
sinc((x − y)/2)/(cos(x/2) cos(y/2)), smooth at x = y):

.. math::

    w_p = w_0 + W[Δφ_0, Δφ_p] \sum_{a ≥ 1} \frac{N_a}{W[Δφ_0, Δφ_a]} (w_a − w_0),
    \qquad
    Δκ_p = \sum_{a ≥ 1} \frac{N_a'}{W[Δφ_0, Δφ_a]} (w_a − w_0).

The coefficients of w_a sum to 1 in w_p and to 0 in Δκ_p. The discrete
gradient D_w V = Σ_p W_p f_mᵀ ∂Δe_p/∂(Δr, w) is then (i) exact,
D_w V · (Δr, w) = V_1 − V_0, and (ii) *equivariant*: orthogonal to the
infinitesimal rotation ξ = (E \bar r_a, 1) at the mean configuration, because
a step (Δr_a, w_a) = c ξ leaves every strain unchanged (Δr' = c E \bar r'
and w_p = c turn r' and t alike). Only r' enters, so its force resultant
vanishes too.

The energy-momentum integrator takes w_a/Δt as the mean angular velocity of
the sections (the body declares its ψ coordinates as ``cayley_coordinates``)
and this discrete gradient for the force; with the constant mass matrix both
momenta then change only by external impulses, and energy by external work,
to the Newton tolerance (flying beam: 1e-14). The body hands the gradient
out conjugate to Δq (ψ rows times w/Δψ), so it is a valid exact discrete
gradient for any caller; :meth:`StrainPoints.discrete_gradient`
differentiates it by complex steps.

With the plain mid-point rate Δφ/Δt (``rotation_rate="mid-point"``)
exact energy and exact angular momentum exclude each other: the step along
ξ(q_m) turns nodes by 2 atan(c/2) but sections by c and changes V. Then the
angular momentum changes per step by ΔL = −Δt D V · ξ(q_m) = O(Δt³), an
O(Δt²) drift (flying beam: 5e-4 relative at Δt = 0.1, 6e-6 at Δt = 0.01).

References
----------
J. C. Simo, L. Vu-Quoc, "On the dynamics of flexible beams under large
overall motions — the plane case", J. Appl. Mech. 53 (1986) 849–863.
J. C. Simo, N. Tarnow, M. Doblaré, "Non-linear dynamics of three-dimensional
rods: exact energy and momentum conserving algorithms", IJNME 38 (1995).
Lee & Yun, "The dynamics analysis for nonlinear flexible mechanisms using finite
elements and algebraic quaternions" (mean velocity, stress at the mean strain).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import Basis, ElementLineP1, ElementLineP2

from ...errors import ConvergenceError
from ...fem.beam import ElementQuadrature, gauss_line
from ...numerics.rotations import MAX_INCREMENT, cayley_divided_difference, cayley_ratio

__all__ = ["StrainPoints", "ElementInversionError"]

#: imaginary step of the complex-step tangent (any tiny value: no subtraction, no truncation error)
COMPLEX_STEP = 1e-30


class ElementInversionError(ConvergenceError, ValueError):
    """A configuration in which an element of an :class:`~skfem_flex.bodies.exact.body.ExactBeam` folds
    inside out (1 + ε ≤ 0).

    A :class:`~skfem_flex.schemes.integrators.ConvergenceError` (and a ``ValueError``):
    raised during a time step, ``simulate`` first retries the step in halves
    (a Newton iterate of a too-large step may fold transiently) and finally
    reports the time, the step and this message, which names the element.
    """


class StrainPoints:
    """The strain points of an exact beam and the strain energy evaluated on them (module docstring).

    Parameters
    ----------
    beam : TimoshenkoBeam
        Mesh, section and element order of the body.
    angle : float
        Reference angle α of the axis, rad.
    dense : bool
        Whether matrices are handed out dense (else CSR in a fixed pattern).
    name : str
        The body's name, for error messages.

    Attributes
    ----------
    ed : ndarray (n_elements, 3k)
        Element DOFs, node-major (x, y, ψ).
    N, dN : ndarray (n_elements, n_points, k)
        Scalar shape functions and their s-derivatives (1/m) at the strain points.
    W : ndarray (n_elements, n_points)
        Quadrature weights, m.
    element_lo, element_hi : ndarray (n_elements,)
        Reference coordinates s (m) of the elements' ends.
    """

    def __init__(self, beam, angle, dense, name):
        self.name = name
        self.angle = float(angle)
        self.direction = np.array([np.cos(self.angle), np.sin(self.angle)])
        sec = beam.section
        self.EA, self.kGA, self.EI = sec.EA, sec.kGA, sec.EI
        n = self.n_dofs = int(beam.n_dofs)
        self.dense = bool(dense)
        #: the ψ coordinate of every node along the beam
        self.psi_dofs = np.asarray(beam.node_dofs)[:, 2]

        # element kernels: strains on the reduced rule (order points per element)
        scalar = ElementLineP1() if beam.order == 1 else ElementLineP2()
        quad = ElementQuadrature.from_basis(Basis(beam.mesh, scalar, quadrature=gauss_line(beam.order)))
        self.ed = np.asarray(beam.element_dofs)                # (n_el, 3k) node-major (x, y, φ)
        self.n_elements, nloc = self.ed.shape
        self.k = nloc // 3
        self.N = np.ascontiguousarray(np.transpose(quad.N, (1, 2, 0)))      # (n_el, n_p, k)
        self.dN = np.ascontiguousarray(np.transpose(quad.dNdx, (1, 2, 0)))
        self.W = np.asarray(quad.dx)                                        # (n_el, n_p), m
        self.s_points = np.asarray(quad.x)
        self._ex = self.ed[:, 0::3]
        self._ey = self.ed[:, 1::3]
        self._ep = self.ed[:, 2::3]
        el_s = beam.mesh.p[0, beam.mesh.t]
        self.element_lo, self.element_hi = el_s.min(axis=0), el_s.max(axis=0)

        # scatter patterns into a fixed structure
        rows = np.broadcast_to(self.ed[:, :, None], (self.n_elements, nloc, nloc)).ravel()
        cols = np.broadcast_to(self.ed[:, None, :], (self.n_elements, nloc, nloc)).ravel()
        keys = rows.astype(np.int64) * n + cols
        if self.dense:
            self._flat = keys
        else:
            uniq, inv = np.unique(keys, return_inverse=True)
            self._inv = inv
            self._csr_indices = (uniq % n).astype(np.int32)
            self._csr_indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
            self._nnz = uniq.size
        self._cache_q = None
        self._cache_kin = None

    # ------------------------------------------------------------- kinematics
    def kinematics(self, q, check=True):
        """Strain-point values r', φ, φ', t, n and the strains ε, γ, κ (a dict of (n_el, n_p) arrays).

        Raises
        ------
        ElementInversionError
            With ``check``, if an element folds inside out (or the strains are not finite).
        """
        q = np.asarray(q, dtype=float)
        U, V, P = q[self._ex], q[self._ey], q[self._ep]
        ux = np.einsum("ek,epk->ep", U, self.dN)
        uy = np.einsum("ek,epk->ep", V, self.dN)
        psi = np.einsum("ek,epk->ep", P, self.N)
        kap = np.einsum("ek,epk->ep", P, self.dN)
        phi = self.angle + psi
        c, s = np.cos(phi), np.sin(phi)
        # ε = t·r' − 1 and γ = n·r' with r' = e_α + u', written so that no O(1) terms cancel
        sh = np.sin(0.5 * psi)
        eps = -2.0 * sh * sh + c * ux + s * uy
        gam = -np.sin(psi) + (-s * ux + c * uy)
        kin = dict(rx=self.direction[0] + ux, ry=self.direction[1] + uy, psi=psi, c=c, s=s, stretch=1.0 + eps,
                   eps=eps, gam=gam, kap=kap)
        if check:
            self._check(kin)
        return kin

    def _check(self, kin):
        st = kin["stretch"]
        if not np.all(np.isfinite(st)):
            raise ElementInversionError(f"{self.name}: non-finite strain (the configuration escaped)")
        bad = np.nonzero(st <= 0.0)
        if bad[0].size:
            e = int(bad[0][0])
            raise ElementInversionError(
                f"{self.name}: element {e} (s in [{self.element_lo[e]:.6g}, {self.element_hi[e]:.6g}] m) folds "
                f"inside out: stretch 1 + ε = {st[bad][0]:.3g} <= 0 ({bad[0].size} strain point(s) reversed)")

    def _kin_cached(self, q):
        if self._cache_q is not None and np.array_equal(self._cache_q, q):
            return self._cache_kin
        kin = self.kinematics(q)
        self._cache_q, self._cache_kin = np.array(q, dtype=float), kin
        return kin

    def strains(self, q):
        """(ε, γ, κ) at the strain points, each of shape (n_elements, n_points)."""
        kin = self.kinematics(q, check=False)
        return kin["eps"], kin["gam"], kin["kap"]

    # ----------------------------------------------------- element assembly
    def _vec(self, crx, cry, cphi, cphip):
        """Element vectors of a linear form c_r · δr' + c_φ δφ + c_φ' δφ', shape (n_el, n_p, 3k)."""
        ne, npt, k = self.N.shape
        out = np.empty((ne, npt, k, 3))
        out[..., 0] = crx[..., None] * self.dN
        out[..., 1] = cry[..., None] * self.dN
        out[..., 2] = cphi[..., None] * self.N + cphip * self.dN
        return out.reshape(ne, npt, 3 * k)

    def _second(self, out, crphi_x, crphi_y, cphir_x, cphir_y, cphiphi):
        """Add Σ_p of the bilinear form δr'·c_rφ Δφ + δφ c_φr·Δr' + δφ c_φφ Δφ (weights included)."""
        N, dN = self.N, self.dN
        out[:, :, 0, :, 2] += np.einsum("ep,epa,epb->eab", crphi_x, dN, N)
        out[:, :, 1, :, 2] += np.einsum("ep,epa,epb->eab", crphi_y, dN, N)
        out[:, :, 2, :, 0] += np.einsum("ep,epa,epb->eab", cphir_x, N, dN)
        out[:, :, 2, :, 1] += np.einsum("ep,epa,epb->eab", cphir_y, N, dN)
        out[:, :, 2, :, 2] += np.einsum("ep,epa,epb->eab", cphiphi, N, N)

    def _scatter_vector(self, g_el):
        return np.bincount(self.ed.ravel(), weights=g_el.ravel(), minlength=self.n_dofs)

    def _scatter_matrix(self, k_el):
        n = self.n_dofs
        if self.dense:
            return np.bincount(self._flat, weights=k_el.ravel(), minlength=n * n).reshape(n, n)
        data = np.bincount(self._inv, weights=k_el.ravel(), minlength=self._nnz)
        return sps.csr_matrix((data, self._csr_indices, self._csr_indptr), shape=(n, n))

    def _grads(self, kin):
        """∇ε, ∇γ, ∇κ as element vectors at the strain points."""
        zero = np.zeros_like(kin["c"])
        b_eps = self._vec(kin["c"], kin["s"], kin["gam"], 0.0)
        b_gam = self._vec(-kin["s"], kin["c"], -kin["stretch"], 0.0)
        b_kap = self._vec(zero, zero, zero, 1.0)
        return b_eps, b_gam, b_kap

    # ------------------------------------------------------------- potential
    def energy(self, q):
        """V = ½ ∫ EA ε² + kGA γ² + EI κ² ds, J."""
        kin = self._kin_cached(q)
        dens = self.EA * kin["eps"] ** 2 + self.kGA * kin["gam"] ** 2 + self.EI * kin["kap"] ** 2
        return 0.5 * float(np.sum(self.W * dens))

    def gradient(self, q):
        """∇V (N, N m) at q."""
        kin = self._kin_cached(q)
        b_eps, b_gam, b_kap = self._grads(kin)
        W = self.W
        g_el = np.einsum("ep,epi->ei", W * self.EA * kin["eps"], b_eps)
        g_el += np.einsum("ep,epi->ei", W * self.kGA * kin["gam"], b_gam)
        g_el += np.einsum("ep,epi->ei", W * self.EI * kin["kap"], b_kap)
        return self._scatter_vector(g_el)

    def hessian(self, q):
        """∇²V at q (dense or CSR, as ``dense``)."""
        kin = self._kin_cached(q)
        b_eps, b_gam, b_kap = self._grads(kin)
        W = self.W
        k_el = np.einsum("ep,epi,epj->eij", W * self.EA, b_eps, b_eps)
        k_el += np.einsum("ep,epi,epj->eij", W * self.kGA, b_gam, b_gam)
        k_el += np.einsum("ep,epi,epj->eij", W * self.EI, b_kap, b_kap)
        ne, k = self.n_elements, self.k
        k_el = k_el.reshape(ne, k, 3, k, 3)
        wn, wq = W * self.EA * kin["eps"], W * self.kGA * kin["gam"]
        c, s = kin["c"], kin["s"]
        # ∇²ε: δr'·n δφ twice, −(1 + ε) δφ²;  ∇²γ: −δr'·t δφ twice, −γ δφ²
        self._second(k_el, wn * -s - wq * c, wn * c - wq * s, wn * -s - wq * c, wn * c - wq * s,
                     -wn * kin["stretch"] - wq * kin["gam"])
        return self._scatter_matrix(k_el.reshape(ne, 3 * k, 3 * k))

    def _discrete_gradient_elements(self, ql0, ql1):
        """Element vectors of the discrete gradient, (n_el, batch, 3k), in Δq-space.

        ``ql0`` (n_el, 3k) and ``ql1`` (n_el, batch, 3k) are element coordinates
        (node-major x, y, ψ); ``ql1`` may be complex (complex-step tangent).
        See the module docstring for the equations.
        """
        N, dN, W = self.N, self.dN, self.W                   # (e, p, k), (e, p, k), (e, p)
        ql0 = ql0[:, None, :]

        def ends(ql):
            U, V, P = ql[..., 0::3], ql[..., 1::3], ql[..., 2::3]
            ux = np.einsum("ebk,epk->ebp", U, dN)
            uy = np.einsum("ebk,epk->ebp", V, dN)
            psi = np.einsum("ebk,epk->ebp", P, N)
            kap = np.einsum("ebk,epk->ebp", P, dN)
            phi = self.angle + psi
            c, s = np.cos(phi), np.sin(phi)
            sh = np.sin(0.5 * psi)
            eps = -2.0 * sh * sh + c * ux + s * uy
            gam = -np.sin(psi) + (-s * ux + c * uy)
            return ux, uy, c, s, eps, gam, kap, P

        ux0, uy0, c0, s0, eps0, gam0, kap0, P0 = ends(ql0)
        ux1, uy1, c1, s1, eps1, gam1, kap1, P1 = ends(ql1)
        wb = W[:, None, :]
        n_bar = wb * self.EA * 0.5 * (eps0 + eps1)
        q_bar = wb * self.kGA * 0.5 * (gam0 + gam1)
        m_bar = wb * self.EI * 0.5 * (kap0 + kap1)
        rbx = self.direction[0] + 0.5 * (ux0 + ux1)              # r̄'
        rby = self.direction[1] + 0.5 * (uy0 + uy1)
        tbx, tby = 0.5 * (c0 + c1), 0.5 * (s0 + s1)              # t̄ = mean section tangent at the point
        a = -tby * rbx + tbx * rby                               # r̄' · E t̄
        b = tbx * rbx + tby * rby                                # r̄' · t̄

        # nodal Cayley rates w_a = W(Δψ_a) → point rate w_p and curvature increment, exactly and linearly,
        # through divided differences about the element's first node (coefficients sum to 1 and to 0)
        X = P1 - P0                                              # (e, b, k)
        Xp = np.einsum("ebk,epk->ebp", X, N)
        dd_p = cayley_divided_difference(X[..., :1], Xp)         # (e, b, p)
        dd_a = cayley_divided_difference(X[..., :1], X[..., 1:])  # (e, b, k−1)
        beta = dd_p[..., None] * N[:, None, :, 1:] / dd_a[:, :, None, :]
        c_w = np.concatenate([1.0 - beta.sum(axis=-1, keepdims=True), beta], axis=-1)      # (e, b, p, k)
        k_w = dN[:, None, :, 1:] / dd_a[:, :, None, :]
        k_w = np.concatenate([-k_w.sum(axis=-1, keepdims=True), k_w], axis=-1)

        fx = np.einsum("ebp,epk->ebk", n_bar * tbx - q_bar * tby, dN)
        fy = np.einsum("ebp,epk->ebk", n_bar * tby + q_bar * tbx, dN)
        fw = (np.einsum("ebp,ebpk->ebk", n_bar * a - q_bar * b, c_w)
              + np.einsum("ebp,ebpk->ebk", m_bar, k_w))
        out = np.empty(ql1.shape, dtype=np.result_type(ql1, float))
        out[..., 0::3] = fx
        out[..., 1::3] = fy
        out[..., 2::3] = fw / cayley_ratio(X)                   # conjugate to w → conjugate to Δψ
        return out

    def discrete_gradient(self, q0, q1):
        """Equivariant discrete gradient: stress at the mean strain, strain increments in Cayley rates.

        Returns (g, ∂g/∂q1) with g · (q1 − q0) = V(q1) − V(q0) to round-off;
        its ψ rows are those of the Cayley-rate gradient times w/Δψ (module
        docstring), so that the integrator's scaling by Δψ/w recovers it.
        The tangent is the complex-step derivative of the element vectors
        (exact to round-off; the coefficients of the divided differences make
        a closed form long and error-prone).

        Raises
        ------
        ElementInversionError
            If q1 folds an element.
        ConvergenceError
            If a nodal rotation increment abs(Δψ) reaches π (no Cayley parameter).
        """
        self._kin_cached(q0)
        self.kinematics(q1)                                    # folded elements are reported here
        q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
        dpsi = np.abs(q1[self.psi_dofs] - q0[self.psi_dofs])
        if dpsi.size and dpsi.max() >= MAX_INCREMENT:
            i = int(np.argmax(dpsi))
            raise ConvergenceError(f"{self.name}: the section at node {i} turns by {dpsi[i]:.3g} rad in one step; "
                                   f"the Cayley parameter 2 tan(Δψ/2) needs |Δψ| < π (take a smaller step)")
        ql0, ql1 = q0[self.ed], q1[self.ed]
        nloc = ql1.shape[1]
        h = COMPLEX_STEP
        probe = ql1[:, None, :] + (1j * h) * np.eye(nloc)[None]
        g = self._discrete_gradient_elements(ql0, probe)        # (e, j, i): perturbation j, row i
        g_el = g[:, 0, :].real
        k_el = np.transpose(g.imag, (0, 2, 1)) / h
        return self._scatter_vector(g_el), self._scatter_matrix(k_el)
