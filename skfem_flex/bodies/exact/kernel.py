r"""Compiled (Numba) strain energy and energy-conserving discrete gradient of an
:class:`~skfem_flex.bodies.exact.body.ExactBeam`.

Same equations as the numpy methods :meth:`ExactBeam.potential_energy
<skfem_flex.bodies.exact.body.ExactBeam.potential_energy>` and :meth:`ExactBeam.potential_discrete_gradient
<skfem_flex.bodies.exact.body.ExactBeam.potential_discrete_gradient>` (module docstring of :mod:`.strain`:
stress at the mean strain, strain increments written exactly through the Cayley parameters
w_a = 2 tan(Δψ_a/2) and their divided differences), in one loop over elements and strain points
on the arrays that :func:`pack` collects once (``ExactBeam.compiled_strain_data()``):

* ``ed`` (n_el, 3k): the element DOF map, node-major (u_x, u_y, ψ) per local node;
* ``N``, ``dN`` (n_el, n_p, k) and ``W`` (n_el, n_p): scalar shape functions, their s-derivatives
  and the weights (m) at the reduced-rule strain points;
* EA, kGA, EI, the reference direction (cos α, sin α) and angle α, MAX_INCREMENT;
* ``psi``: the ψ coordinate of every node;
* the CSR pattern ``pat_ptr``, ``pat_idx`` (int64) of the body matrix (the union of the element
  blocks, for dense and sparse bodies alike: a dense caller scatters it as for a sparse body) and
  ``map_el`` (n_el, 3k, 3k), the position in the pattern's data of every entry of every element block.

For callers: g is conjugate to Δq, exactly as the numpy method (g · Δq = V₁ − V₀); on the ψ rows it is
the Cayley-rate gradient f_w times w/Δψ. The energy-momentum step with Cayley coordinates
(``EnergyMomentum.step``, ``_cayley_rates``) multiplies the ψ rows of g, of the force tangent and of the
floor by Δψ/w = ``cayley_ratio(Δψ)`` and adds diag(Δt g · d(Δψ/w)/dΔψ): applied to this g and
∂g/∂q1 that recovers f_w and ∂f_w/∂q1 (to round-off), so the kernel output enters that scaling as the
numpy body's does. The floor is Δt-free (the caller multiplies by Δt).

The tangent ∂g/∂q1 is analytic (derived below, held to the numpy complex-step tangent to
round-off by ``tests/test_exact_kernel.py``). With the point values (u_x', u_y', ψ, κ) at the
end state 1, n̄ = ½ W EA (ε₀ + ε₁), q̄ = ½ W kGA (γ₀ + γ₁), m̄ = ½ W EI (κ₀ + κ₁),
t̄ = ½(t₀ + t₁), r̄' = e_α + ½(u₀' + u₁'), a = r̄'·E t̄, b = r̄'·t̄, the element vector is

.. math::

    g_{x,a} = Σ_p N'_{pa} (n̄ t̄_x − q̄ t̄_y), \quad g_{y,a} = Σ_p N'_{pa} (n̄ t̄_y + q̄ t̄_x), \quad
    f_{w,a} = Σ_p (n̄ a − q̄ b) c_{w,pa} + m̄ k_{w,pa}, \quad g_{ψ,a} = f_{w,a} \, W[Δψ_a, 0]

(W[x, 0] = w/Δψ, the inverse of ``rotations.cayley_ratio``); its derivatives with respect to the
point values use ∂ε₁/∂(u_x', u_y', ψ) = (c, s, γ₁), ∂γ₁/∂(…) = (−s, c, −(1 + ε₁)), ∂t̄/∂ψ₁ = ½ n₁,
and those of the coefficients c_w, k_w of the divided differences W[x, y] (module docstring of
``strain.py``) use ∂W[x, y]/∂x = (½ sinc'(h) + ½ sinc(h) tan(x/2)) / (cos(x/2) cos(y/2)),
h = (x − y)/2 (and symmetrically in y), all free of cancellation.

Failure is reported, not raised (a compiled time loop hands the step back to Python, whose
methods raise the proper error): the discrete gradient returns :data:`TURN` if a nodal increment
|Δψ| reaches ``rotations.MAX_INCREMENT`` (or is not finite) and :data:`FOLDED` if q0 or q1 folds an
element (stretch 1 + ε ≤ 0 or not finite at a strain point, as ``StrainPoints.kinematics``). The increments
are checked first (the divided differences need |Δψ| < π), so a state both turned too far and folded
reports TURN where the numpy method raises ElementInversionError; :func:`potential_energy` checks
nothing (:func:`state_status` does).

Kernels are compiled with ``cache=True``: the first call on a machine compiles them, later
processes load them from numba's cache.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np

from ...numerics.rotations import MAX_INCREMENT, dsinc, sinc

__all__ = ["ExactKernelData", "pack", "OK", "TURN", "FOLDED", "potential_energy", "state_status",
           "potential_discrete_gradient", "discrete_gradient_terms"]

#: status of the kernels: success
OK = 0
#: a nodal rotation increment |Δψ| ≥ MAX_INCREMENT (or not finite): no Cayley parameter
TURN = 1
#: an element folds (1 + ε ≤ 0 or not finite at a strain point) in q0 or q1
FOLDED = 2

#: the arrays an :class:`~skfem_flex.bodies.exact.body.ExactBeam` hands its kernels (built once by :func:`pack`)
ExactKernelData = namedtuple("ExactKernelData", [
    "n", "ed", "N", "dN", "W", "EA", "kGA", "EI", "dx", "dy", "angle", "max_increment",
    "psi", "pat_ptr", "pat_idx", "map_el"])


def pack(body):
    """Build :class:`ExactKernelData` from an :class:`~skfem_flex.bodies.exact.body.ExactBeam` (any rotation rate).

    The tangent pattern is the union of the element blocks (sorted CSR, int64), for dense and
    sparse bodies alike; ``map_el[e, i, j]`` is the position of the entry (ed[e, i], ed[e, j]).
    """
    n = int(body.n_dofs)
    ed = np.ascontiguousarray(body.ed, dtype=np.int64)
    ne, nloc = ed.shape
    rows = np.broadcast_to(ed[:, :, None], (ne, nloc, nloc)).ravel()
    cols = np.broadcast_to(ed[:, None, :], (ne, nloc, nloc)).ravel()
    keys = rows * n + cols
    uniq, inv = np.unique(keys, return_inverse=True)
    pat_idx = np.ascontiguousarray(uniq % n, dtype=np.int64)
    pat_ptr = np.ascontiguousarray(np.searchsorted(uniq // n, np.arange(n + 1)), dtype=np.int64)
    map_el = np.ascontiguousarray(inv.reshape(ne, nloc, nloc), dtype=np.int64)
    f64 = lambda a: np.ascontiguousarray(a, dtype=float)        # noqa: E731
    sp = body.strain_points
    return ExactKernelData(
        n, ed, f64(sp.N), f64(sp.dN), f64(sp.W), float(body.EA), float(body.kGA), float(body.EI),
        float(body.direction[0]), float(body.direction[1]), float(body.angle), float(MAX_INCREMENT),
        np.ascontiguousarray(body.node_dofs[:, 2], dtype=np.int64), pat_ptr, pat_idx, map_el)


@numba.njit(cache=True)
def _end(kd, q, e, p):
    """(u_x', u_y', ψ, κ, cos φ, sin φ, ε, γ) at strain point p of element e for the state q.

    ε = −2 sin²(ψ/2) + c u_x' + s u_y', γ = −sin ψ + (−s u_x' + c u_y'), φ = α + ψ (no O(1) terms
    cancel, as ``StrainPoints.kinematics``)."""
    ed, N, dN = kd.ed, kd.N, kd.dN
    ux, uy, psi, kap = 0.0, 0.0, 0.0, 0.0
    for a in range(N.shape[2]):
        d, f = dN[e, p, a], N[e, p, a]
        ux += d * q[ed[e, 3 * a]]
        uy += d * q[ed[e, 3 * a + 1]]
        pa = q[ed[e, 3 * a + 2]]
        psi += f * pa
        kap += d * pa
    sh, ch = math.sin(0.5 * psi), math.cos(0.5 * psi)
    sp = 2.0 * sh * ch                                  # sin ψ
    cp = 1.0 - 2.0 * sh * sh                            # cos ψ
    c = kd.dx * cp - kd.dy * sp                         # cos(α + ψ)
    s = kd.dy * cp + kd.dx * sp                         # sin(α + ψ)
    eps = -2.0 * sh * sh + c * ux + s * uy
    gam = -sp + (-s * ux + c * uy)
    return ux, uy, psi, kap, c, s, eps, gam


@numba.njit(cache=True)
def _bad_stretch(eps):
    st = 1.0 + eps
    return not (st > 0.0 and st < np.inf)


@numba.njit(cache=True)
def potential_energy(kd, q):
    """V = ½ Σ W (EA ε² + kGA γ² + EI κ²), J (no fold check: see :func:`state_status`)."""
    ne, npt = kd.W.shape
    v = 0.0
    for e in range(ne):
        for p in range(npt):
            _, _, _, kap, _, _, eps, gam = _end(kd, q, e, p)
            v += kd.W[e, p] * (kd.EA * eps * eps + kd.kGA * gam * gam + kd.EI * kap * kap)
    return 0.5 * v


@numba.njit(cache=True)
def state_status(kd, q):
    """:data:`FOLDED` if q folds an element (stretch 1 + ε ≤ 0 or not finite at a strain point), else :data:`OK`."""
    ne, npt = kd.W.shape
    for e in range(ne):
        for p in range(npt):
            eps = _end(kd, q, e, p)[6]
            if _bad_stretch(eps):
                return FOLDED
    return OK


@numba.njit(cache=True)
def _dd(x, y, cx, tx, cy, ty):
    """W[x, y] = (W(x) − W(y))/(x − y) = sinc(h)/(cos(x/2) cos(y/2)), h = (x − y)/2, and its partial
    derivatives in x and y; cx = cos(x/2), tx = tan(x/2), likewise cy, ty (shared by the callers)."""
    h = 0.5 * (x - y)
    sn, ds = sinc(h), dsinc(h)
    inv = 1.0 / (cx * cy)
    return sn * inv, 0.5 * (ds + sn * tx) * inv, 0.5 * (sn * ty - ds) * inv


@numba.njit(cache=True)
def potential_discrete_gradient(kd, q0, q1, g, data, floor):
    """Discrete gradient of the strain energy, its tangent and its round-off floor, in place.

    Parameters
    ----------
    kd : ExactKernelData
    q0, q1 : ndarray (n,)
        Body coordinates at the step's ends.
    g : ndarray (n,), out
        The discrete gradient, conjugate to Δq = q1 − q0 (ψ rows: the Cayley-rate gradient
        times w/Δψ), g · Δq = V(q1) − V(q0) to round-off; as ``ExactBeam.potential_discrete_gradient``.
    data : ndarray (nnz,), out
        ∂g/∂q1 as the data of the CSR pattern (``kd.pat_ptr``, ``kd.pat_idx``).
    floor : ndarray (n,), out
        |∂g/∂q1| (|q0| + |q1|) (row sums over the assembled pattern; the caller multiplies by Δt).

    Returns
    -------
    int
        :data:`OK`; :data:`TURN` (some |Δψ_a| ≥ MAX_INCREMENT or not finite) or :data:`FOLDED` (q0 or
        q1 folds an element), in which case the outputs are incomplete and the caller re-runs the
        step in Python (whose methods raise the proper error).
    """
    ed, N, dN, W = kd.ed, kd.N, kd.dN, kd.W
    ne, npt, k = N.shape
    nloc = 3 * k
    EA, kGA, EI = kd.EA, kd.kGA, kd.EI
    # nodal increments first (|Δψ| < MAX_INCREMENT: the divided differences below need |Δψ| < π):
    # cos(Δψ/2), tan(Δψ/2), w/Δψ = W[Δψ, 0] and its derivative, once per node, by ψ DOF index
    nodal = np.empty((4, kd.n))
    for a in range(kd.psi.size):
        i = kd.psi[a]
        x = q1[i] - q0[i]
        if not abs(x) < kd.max_increment:
            return TURN
        c = math.cos(0.5 * x)
        t = math.sin(0.5 * x) / c
        nodal[0, i], nodal[1, i] = c, t
        nodal[2, i], nodal[3, i], _ = _dd(x, 0.0, c, t, 1.0, 0.0)
    g[:] = 0.0
    data[:] = 0.0
    # per-element scratch (k ≤ 3): one allocation per call (with ``nodal``: two)
    work = np.empty(nloc * nloc + 16 * k + 3 * k * k)
    kel = work[:nloc * nloc].reshape(nloc, nloc)
    o = nloc * nloc
    X, cx, tx = work[o:o + k], work[o + k:o + 2 * k], work[o + 2 * k:o + 3 * k]
    rinv, drinv = work[o + 3 * k:o + 4 * k], work[o + 4 * k:o + 5 * k]
    D, Dx, Dy = work[o + 5 * k:o + 6 * k], work[o + 6 * k:o + 7 * k], work[o + 7 * k:o + 8 * k]
    fw, dDp, cw, kw = work[o + 8 * k:o + 9 * k], work[o + 9 * k:o + 10 * k], work[o + 10 * k:o + 11 * k], \
        work[o + 11 * k:o + 12 * k]
    gx, gy = work[o + 12 * k:o + 13 * k], work[o + 13 * k:o + 14 * k]
    o2 = o + 16 * k
    dcw = work[o2:o2 + k * k].reshape(k, k)             # ∂c_w[a]/∂X_b at the point
    dkw = work[o2 + k * k:o2 + 2 * k * k].reshape(k, k)  # ∂k_w[a]/∂X_b
    for e in range(ne):
        # ------------------------------------------------ nodal increments and their divided differences
        for a in range(k):
            i = ed[e, 3 * a + 2]
            X[a] = q1[i] - q0[i]
            cx[a], tx[a], rinv[a], drinv[a] = nodal[0, i], nodal[1, i], nodal[2, i], nodal[3, i]
        D[0], Dx[0], Dy[0] = 1.0, 0.0, 0.0
        for a in range(1, k):
            D[a], Dx[a], Dy[a] = _dd(X[0], X[a], cx[0], tx[0], cx[a], tx[a])
        kel[:, :] = 0.0
        for a in range(k):
            fw[a], gx[a], gy[a] = 0.0, 0.0, 0.0
        for p in range(npt):
            ux0, uy0, psi0, kap0, c0, s0, eps0, gam0 = _end(kd, q0, e, p)
            ux1, uy1, psi1, kap1, c1, s1, eps1, gam1 = _end(kd, q1, e, p)
            if _bad_stretch(eps0) or _bad_stretch(eps1):
                return FOLDED
            hw = 0.5 * W[e, p]
            nb = hw * EA * (eps0 + eps1)
            qb = hw * kGA * (gam0 + gam1)
            mb = hw * EI * (kap0 + kap1)
            rbx = kd.dx + 0.5 * (ux0 + ux1)
            rby = kd.dy + 0.5 * (uy0 + uy1)
            tbx, tby = 0.5 * (c0 + c1), 0.5 * (s0 + s1)
            av = -tby * rbx + tbx * rby                 # r̄'·E t̄
            bv = tbx * rbx + tby * rby                  # r̄'·t̄
            ax = nb * tbx - qb * tby
            ay = nb * tby + qb * tbx
            fv = nb * av - qb * bv
            # partial derivatives in the point values (u_x', u_y', ψ) at end 1 (κ₁: m̄ only)
            n_u, n_v, n_s = hw * EA * c1, hw * EA * s1, hw * EA * gam1
            q_u, q_v, q_s = -hw * kGA * s1, hw * kGA * c1, -hw * kGA * (1.0 + eps1)
            m_k = hw * EI
            tx_s, ty_s = -0.5 * s1, 0.5 * c1
            a_u, a_v, a_s = -0.5 * tby, 0.5 * tbx, -0.5 * (c1 * rbx + s1 * rby)
            b_u, b_v, b_s = 0.5 * tbx, 0.5 * tby, 0.5 * (-s1 * rbx + c1 * rby)
            ax_u = n_u * tbx - q_u * tby
            ax_v = n_v * tbx - q_v * tby
            ax_s = n_s * tbx - q_s * tby + nb * tx_s - qb * ty_s
            ay_u = n_u * tby + q_u * tbx
            ay_v = n_v * tby + q_v * tbx
            ay_s = n_s * tby + q_s * tbx + nb * ty_s + qb * tx_s
            f_u = n_u * av + nb * a_u - q_u * bv - qb * b_u
            f_v = n_v * av + nb * a_v - q_v * bv - qb * b_v
            f_s = n_s * av + nb * a_s - q_s * bv - qb * b_s
            # coefficients of the nodal Cayley parameters in w_p (c_w) and Δκ_p (k_w), and their X-derivatives
            xp = 0.0
            for b in range(k):
                xp += N[e, p, b] * X[b]
            cp = math.cos(0.5 * xp)
            Dp, Dp_x, Dp_y = _dd(X[0], xp, cx[0], tx[0], cp, math.sin(0.5 * xp) / cp)
            for b in range(k):
                dDp[b] = Dp_y * N[e, p, b]
            dDp[0] += Dp_x
            cw[0], kw[0] = 1.0, 0.0
            for b in range(k):
                dcw[0, b], dkw[0, b] = 0.0, 0.0
            for a in range(1, k):
                na, da = N[e, p, a], dN[e, p, a]
                ia = 1.0 / D[a]
                beta = Dp * na * ia
                cw[a] = beta
                cw[0] -= beta
                kw[a] = da * ia
                kw[0] -= kw[a]
                for b in range(k):
                    dda = (Dx[a] if b == 0 else 0.0) + (Dy[a] if b == a else 0.0)    # ∂D_a/∂X_b
                    dc = na * (dDp[b] - Dp * dda * ia) * ia
                    dk = -da * dda * ia * ia
                    dcw[a, b] = dc
                    dkw[a, b] = dk
                    dcw[0, b] -= dc
                    dkw[0, b] -= dk
            # element vector and tangent (rows x_a, y_a; ψ rows still conjugate to w)
            for a in range(k):
                da = dN[e, p, a]
                gx[a] += da * ax
                gy[a] += da * ay
                fw[a] += cw[a] * fv + kw[a] * mb
                rx, ry, rw = 3 * a, 3 * a + 1, 3 * a + 2
                for b in range(k):
                    db, nbb = dN[e, p, b], N[e, p, b]
                    cx_, cy_, cs_ = 3 * b, 3 * b + 1, 3 * b + 2
                    kel[rx, cx_] += da * ax_u * db
                    kel[rx, cy_] += da * ax_v * db
                    kel[rx, cs_] += da * ax_s * nbb
                    kel[ry, cx_] += da * ay_u * db
                    kel[ry, cy_] += da * ay_v * db
                    kel[ry, cs_] += da * ay_s * nbb
                    kel[rw, cx_] += cw[a] * f_u * db
                    kel[rw, cy_] += cw[a] * f_v * db
                    kel[rw, cs_] += cw[a] * f_s * nbb + kw[a] * m_k * db + fv * dcw[a, b] + mb * dkw[a, b]
        # ------------------------------------------------ ψ rows: conjugate to w → conjugate to Δψ, scatter
        for a in range(k):
            rw = 3 * a + 2
            for j in range(nloc):
                kel[rw, j] *= rinv[a]
            kel[rw, rw] += fw[a] * drinv[a]
            g[ed[e, 3 * a]] += gx[a]
            g[ed[e, 3 * a + 1]] += gy[a]
            g[ed[e, rw]] += fw[a] * rinv[a]
        mp = kd.map_el
        for i in range(nloc):
            for j in range(nloc):
                data[mp[e, i, j]] += kel[i, j]
    ptr, idx = kd.pat_ptr, kd.pat_idx
    for i in range(kd.n):
        s = 0.0
        for t in range(ptr[i], ptr[i + 1]):
            j = idx[t]
            s += abs(data[t]) * (abs(q0[j]) + abs(q1[j]))
        floor[i] = s
    return OK


@numba.njit(cache=True)
def discrete_gradient_terms(kd, q0, q1):
    """Allocating form of :func:`potential_discrete_gradient`: (status, g, data, floor)."""
    g = np.empty(kd.n)
    data = np.empty(kd.pat_idx.size)
    floor = np.empty(kd.n)
    status = potential_discrete_gradient(kd, q0, q1, g, data, floor)
    return status, g, data, floor
