r"""Compiled (Numba) arithmetic of the floating-frame bodies (:class:`~skfem_flex.bodies.floating.body.FloatingBeam`,
:class:`~skfem_flex.bodies.modal.body.ModalBody`).

The energy-momentum scheme asks a floating-frame body, at every Newton evaluation, for

.. math::

    p_1 = M(q_1) v_1,\quad g_{kin},\quad g_{pot},\quad
    J = \tfrac{2}{\Delta t} M(q_1) + B(q_1, v_1) - \Delta t\,\partial_{q_1} g_{kin}
        - 2\,\partial_{v_1} g_{kin} + \Delta t\,\partial_{q_1} g_{pot},\quad
    \text{floor} = \Delta t\,|\partial_{q_1} g_{pot}|\,(|q_0| + |q_1|)

(formulas in :meth:`FloatingFrame.kinetic_discrete_gradient <skfem_flex.bodies.ffr.FloatingFrame>`,
the bodies' ``potential_discrete_gradient`` and the module docstrings of ``ffr.py`` and
``floating.py``). The numpy implementation spends most of its time in the Python overhead
of many small array operations; the kernels here do the same arithmetic in loops over
plain arrays that the body precomputes once (:func:`pack`, handed out by the body's
``compiled_kernel_data()``):

* the constant elastic blocks M_A, H, M_ff = M_A + M_I and K as CSR arrays,
* the inertia invariants m, S_0, I_0, S̄, c, k_0n (table in ``ffr.py``),
* the strain energy beyond ½ q_fᵀ K q_f: for a FloatingBeam with Green–Lagrange strain the
  quadrature arrays of the axial kernel (dN/dx per element and point, EA dx per point, the
  local-to-elastic DOF map, −1 = eliminated by the reference condition); for a ModalBody with
  Green–Lagrange strain the cubic and quartic tensors K3, K4 of its quartic energy, folded by
  their symmetries (:func:`.modal_kernel.pack_quartic`); empty arrays where they do not apply,
* the CSR pattern of the body matrix (the full n × n pattern for dense bodies, the fixed
  sparse pattern for large ones) and the positions in it of every term.

The kinetic terms depend only on the invariants, so one kernel serves every floating-frame body.

The tangent is written as the data array of that pattern, so one kernel serves both the
dense (reshaped to n × n) and the sparse (``csr_matrix``) return types.

Kernels are compiled with ``cache=True``: the first call on a machine compiles them (a few
seconds), later processes load them from numba's cache.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
import numba

from ...numerics.rotations import dsinc, sinc
from ..modal.kernel import quartic_discrete_gradient, quartic_energy

__all__ = ["FloatingKernelData", "pack", "energy_momentum_terms", "newmark_terms", "momentum", "potential_energy",
           "sinc_half", "csr_parts"]

#: the arrays a floating-frame body hands its kernels (built once by :func:`pack`)
FloatingKernelData = namedtuple("FloatingKernelData", [
    "n", "nf", "green", "mass", "s0x", "s0y", "i0",
    "sbar", "c", "k0n",
    "ma_ptr", "ma_idx", "ma_dat", "h_ptr", "h_idx", "h_dat",
    "mff_ptr", "mff_idx", "mff_dat", "k_ptr", "k_idx", "k_dat",
    "pat_ptr", "pat_idx", "map_top", "map_left", "map_ma", "map_h", "map_mff", "map_k",
    "dn", "loc", "wq", "map_loc",
    "quartic", "k3p", "k3q", "k3a", "k3b", "k4a", "k4s", "k4w", "map_ee"])


def csr_parts(mat):
    """(indptr, indices, data) of a canonical CSR copy of ``mat`` (int64 indices)."""
    import scipy.sparse as sps
    x = sps.csr_matrix(mat, copy=True)
    x.sum_duplicates()
    x.sort_indices()
    return x.indptr.astype(np.int64), x.indices.astype(np.int64), x.data.astype(float)


def pack(n, nf, green, mass, s0, i0, sbar, c, k0n, blocks, pattern, maps, dn=None, loc=None, wq=None, map_loc=None,
         quartic=None):
    """Build :class:`FloatingKernelData` from a floating-frame body's precomputed operators.

    Parameters
    ----------
    n, nf : int
        Body coordinates (3 + nf) and elastic coordinates.
    green : bool
        Green–Lagrange axial strain of a FloatingBeam (``dn, loc, wq, map_loc``; False: none, or
        linear strain, whose axial part is in K).
    mass, s0, i0 : float, (2,), float
        m = ∫ρA (kg), S_0 = ∫ρA x_0 (kg m), I_00 + J_r (kg m²).
    sbar, c, k0n : (2, nf), (nf,), (nf,)
        S̄ = ∫ρA S, c = ∫ρA Sᵀx_0, k_0 + n_φ.
    blocks : dict
        ``"MA", "H", "Mff", "K"``: the constant elastic blocks (dense or sparse, nf × nf).
    pattern : (indptr, indices)
        CSR pattern of the n × n body matrix.
    maps : dict
        Positions in the pattern data: ``"top"`` (3 n, rows 0–2 row-major), ``"left"``
        (nf × 3 row-major, rows 3…, columns 0–2), for each block key the positions of
        the entries of its canonical CSR form (:func:`csr_parts`), and with ``quartic``
        ``"ee"`` (nf × nf row-major: the whole elastic block).
    dn : (n_el, n_qp, n_l), optional
        dN/dx of the local shape functions at the axial quadrature points, 1/m.
    loc : (n_el, 2 n_l) int, optional
        Elastic index of the local (u, w) DOFs, −1 where the reference condition eliminates it.
    wq : (n_el n_qp,), optional
        EA dx per quadrature point, N m.
    map_loc : (n_el, 2 n_l, 2 n_l) int, optional
        Position in the pattern data of each entry of the element axial tangent (−1: dropped).
    quartic : tuple of seven arrays, optional
        The cubic and quartic tensors of a :class:`~skfem_flex.bodies.modal.stiffening.QuarticEnergy` on the
        elastic coordinates, as :func:`.modal_kernel.pack_quartic` arranges them.
    """
    parts = {k: csr_parts(blocks[k]) for k in ("MA", "H", "Mff", "K")}
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)      # noqa: E731
    f64 = lambda a: np.ascontiguousarray(a, dtype=float)         # noqa: E731
    if green and dn is None:
        raise ValueError("pack: green=True needs the axial quadrature arrays dn, loc, wq, map_loc")
    if dn is None:                  # empty arrays of the same types: one compiled kernel serves every body
        dn, loc, wq, map_loc = (np.zeros((0, 0, 0)), np.zeros((0, 0), np.int64), np.zeros(0),
                                np.zeros((0, 0, 0), np.int64))
    if quartic is None:
        quartic_mats, map_ee = (np.zeros((0, 0)),) * 7, np.zeros(0, np.int64)
    else:
        quartic_mats, map_ee = tuple(quartic), maps["ee"]
        ns, nw = nf * (nf + 1) // 2, nf * (nf - 1) // 2
        shapes = [(nf, ns)] * 2 + [(nf * nf, nf)] * 2 + [(ns, ns)] * 2 + [(nw, nw)]
        if [np.shape(a) for a in quartic_mats] != shapes or np.size(map_ee) != nf * nf:
            raise ValueError(f"pack: quartic matrices of shapes {[np.shape(a) for a in quartic_mats]} (and "
                             f"{np.size(map_ee)} block positions) do not fit {nf} elastic coordinates")
    return FloatingKernelData(
        int(n), int(nf), bool(green), float(mass), float(s0[0]), float(s0[1]), float(i0),
        f64(sbar), f64(c), f64(k0n),
        *parts["MA"], *parts["H"], *parts["Mff"], *parts["K"],
        i64(pattern[0]), i64(pattern[1]), i64(maps["top"]), i64(maps["left"]),
        i64(maps["MA"]), i64(maps["H"]), i64(maps["Mff"]), i64(maps["K"]),
        f64(dn), i64(loc), f64(wq), i64(map_loc),
        quartic is not None, *(f64(a) for a in quartic_mats), i64(map_ee))


@numba.njit(cache=True)
def _matvec(ptr, idx, dat, x, off):
    """y = X x[off:] for the CSR matrix (ptr, idx, dat)."""
    m = ptr.size - 1
    y = np.empty(m)
    for i in range(m):
        s = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            s += dat[k] * x[off + idx[k]]
        y[i] = s
    return y


@numba.njit(cache=True)
def sinc_half(d):
    """σ = sinc(d/2) and dσ/dd = ½ dsinc(d/2) (:mod:`skfem_flex.numerics.rotations`); also used by the numpy
    methods of floating-frame bodies."""
    h = 0.5 * d
    return sinc(h), 0.5 * dsinc(h)


@numba.njit(cache=True)
def momentum(kd, q, v):
    """p = M(q) v (eq. 16 of Liu & Yun; see FloatingBeam.momentum), kg m/s and kg m²/s."""
    nf = kd.nf
    sbar = kd.sbar
    C, S = math.cos(q[2]), math.sin(q[2])
    sqx, sqy, sfx, sfy = 0.0, 0.0, 0.0, 0.0
    for i in range(nf):
        sqx += sbar[0, i] * q[3 + i]
        sqy += sbar[1, i] * q[3 + i]
        sfx += sbar[0, i] * v[3 + i]
        sfy += sbar[1, i] * v[3 + i]
    sx, sy = kd.s0x + sqx, kd.s0y + sqy
    maq = _matvec(kd.ma_ptr, kd.ma_idx, kd.ma_dat, q, 3)
    hq = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, q, 3)
    mff = _matvec(kd.mff_ptr, kd.mff_idx, kd.mff_dat, v, 3)
    J = kd.i0
    af = 0.0
    for i in range(nf):
        J += q[3 + i] * (kd.c[i] + (kd.c[i] + maq[i]))
        af += (kd.k0n[i] + hq[i]) * v[3 + i]
    w = v[2]
    aesx, aesy = C * (-sy) - S * sx, S * (-sy) + C * sx          # A E s̄
    bx, by = C * v[0] + S * v[1], -S * v[0] + C * v[1]            # Aᵀ Ṙ
    p = np.empty(kd.n)
    p[0] = kd.mass * v[0] + w * aesx + (C * sfx - S * sfy)
    p[1] = kd.mass * v[1] + w * aesy + (S * sfx + C * sfy)
    p[2] = (aesx * v[0] + aesy * v[1]) + J * w + af
    for i in range(nf):
        p[3 + i] = (sbar[0, i] * bx + sbar[1, i] * by) + w * (kd.k0n[i] + hq[i]) + mff[i]
    return p


@numba.njit(cache=True)
def _axial_strains(kd, q):
    """(u', w', ε) at the axial quadrature points (flattened element-major) of the body state q."""
    dn, loc = kd.dn, kd.loc
    nel, nqp, nl = dn.shape
    up = np.zeros(nel * nqp)
    wp = np.zeros(nel * nqp)
    for e in range(nel):
        for k in range(nqp):
            su, sw = 0.0, 0.0
            for l in range(nl):
                iu, iw = loc[e, l], loc[e, nl + l]
                if iu >= 0:
                    su += dn[e, k, l] * q[3 + iu]
                if iw >= 0:
                    sw += dn[e, k, l] * q[3 + iw]
            up[e * nqp + k] = su
            wp[e * nqp + k] = sw
    eps = up + 0.5 * (up * up + wp * wp)
    return up, wp, eps


@numba.njit(cache=True)
def potential_energy(kd, q):
    """Strain energy V = ½ q_fᵀ K q_f + ½ Σ EA dx ε² (beam's Green–Lagrange part, only if ``kd.green``)
    + the cubic and quartic terms of a modal body's quartic energy (only if ``kd.quartic``), J."""
    kq = _matvec(kd.k_ptr, kd.k_idx, kd.k_dat, q, 3)
    e = 0.0
    for i in range(kd.nf):
        e += q[3 + i] * kq[i]
    e *= 0.5
    if kd.green:
        _, _, eps = _axial_strains(kd, q)
        s = 0.0
        for k in range(eps.size):
            s += kd.wq[k] * eps[k] * eps[k]
        e += 0.5 * s
    if kd.quartic:
        e += quartic_energy(kd.k3p, kd.k4a, q, 3)
    return e


@numba.njit(cache=True)
def energy_momentum_terms(kd, q0, q1, v0, v1, dt):
    """Compiled twin of :meth:`FloatingFrame.energy_momentum_terms` (same equations; FloatingBeam's
    method is this kernel, a ModalBody's numpy method is its reference).

    Returns
    -------
    p1, g_kin, g_pot : ndarray (n,)
    data : ndarray (nnz,)
        The tangent J as the data array of the body's CSR pattern (``kd.pat_ptr``, ``kd.pat_idx``).
    floor : ndarray (n,)
        Δt |∂g_pot/∂q1| (|q0| + |q1|).
    """
    n, nf = kd.n, kd.nf
    sbar = kd.sbar
    c2 = 2.0 / dt
    # ---------------------------------------------------------------- products with the elastic state
    qfm = np.empty(nf)
    for i in range(nf):
        qfm[i] = 0.5 * (q0[3 + i] + q1[3 + i])
    sq1x, sq1y, sqmx, sqmy = 0.0, 0.0, 0.0, 0.0
    sf0x, sf0y, sf1x, sf1y = 0.0, 0.0, 0.0, 0.0
    for i in range(nf):
        sq1x += sbar[0, i] * q1[3 + i]
        sq1y += sbar[1, i] * q1[3 + i]
        sqmx += sbar[0, i] * qfm[i]
        sqmy += sbar[1, i] * qfm[i]
        sf0x += sbar[0, i] * v0[3 + i]
        sf0y += sbar[1, i] * v0[3 + i]
        sf1x += sbar[0, i] * v1[3 + i]
        sf1y += sbar[1, i] * v1[3 + i]
    maq1 = _matvec(kd.ma_ptr, kd.ma_idx, kd.ma_dat, q1, 3)
    maqm = _matvec(kd.ma_ptr, kd.ma_idx, kd.ma_dat, qfm, 0)
    hq1 = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, q1, 3)
    hf0 = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, v0, 3)
    hf1 = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, v1, 3)
    mff1 = _matvec(kd.mff_ptr, kd.mff_idx, kd.mff_dat, v1, 3)
    kqm = _matvec(kd.k_ptr, kd.k_idx, kd.k_dat, qfm, 0)
    # at q1: s̄ = S_0 + S̄ q_f, c_m = c + M_A q_f, a = k_0 + n_φ + H q_f, J = I_0 + q_f·(c + c_m)
    sx, sy = kd.s0x + sq1x, kd.s0y + sq1y
    J = kd.i0
    for i in range(nf):
        J += q1[3 + i] * (kd.c[i] + (kd.c[i] + maq1[i]))
    # at the midpoint: s̄_m = S_0 + S̄ q_f,m, c + M_A q_f,m
    smx, smy = kd.s0x + sqmx, kd.s0y + sqmy
    # ---------------------------------------------------------------- kinetic discrete gradient
    d = q1[2] - q0[2]
    tm = 0.5 * (q0[2] + q1[2])
    ca, sa = math.cos(tm), math.sin(tm)
    sig, dsig = sinc_half(d)
    kap, dkap = math.cos(0.5 * d), -0.5 * math.sin(0.5 * d)
    w0, w1 = v0[2], v1[2]
    b0x, b0y = ca * v0[0] + sa * v0[1], -sa * v0[0] + ca * v0[1]
    b1x, b1y = ca * v1[0] + sa * v1[1], -sa * v1[0] + ca * v1[1]
    c0x, c0y = -w0 * smy + sf0x, w0 * smx + sf0y          # c_i = ω_i E s̄_m + S̄ f_i
    c1x, c1y = -w1 * smy + sf1x, w1 * smx + sf1y
    X = (-b0x * c1y + b0y * c1x) + (-b1x * c0y + b1y * c0x)
    wbx, wby = w1 * b0x + w0 * b1x, w1 * b0y + w0 * b1y
    gk = np.zeros(n)
    gk[2] = 0.5 * sig * X
    for i in range(nf):
        sbe_wb = -sbar[1, i] * wbx + sbar[0, i] * wby         # (S̄ᵀEᵀ w_b)_i
        gk[3 + i] = (0.5 * kap * sbe_wb + (w0 * w1) * (kd.c[i] + maqm[i])
                     - 0.5 * (w0 * hf1[i] + w1 * hf0[i]))
    # ---------------------------------------------------------------- momentum at (q1, v1)
    C, S = math.cos(q1[2]), math.sin(q1[2])
    Vx, Vy = v1[0], v1[1]
    aesx, aesy = C * (-sy) - S * sx, S * (-sy) + C * sx        # A E s̄
    bx, by = C * Vx + S * Vy, -S * Vx + C * Vy                # Aᵀ Ṙ_1
    af = 0.0
    for i in range(nf):
        af += (kd.k0n[i] + hq1[i]) * v1[3 + i]
    p = np.empty(n)
    p[0] = kd.mass * Vx + w1 * aesx + (C * sf1x - S * sf1y)
    p[1] = kd.mass * Vy + w1 * aesy + (S * sf1x + C * sf1y)
    p[2] = (aesx * Vx + aesy * Vy) + J * w1 + af
    for i in range(nf):
        p[3 + i] = (sbar[0, i] * bx + sbar[1, i] * by) + w1 * (kd.k0n[i] + hq1[i]) + mff1[i]
    # ---------------------------------------------------------------- tangent: reference rows and columns
    data = np.zeros(kd.pat_idx.size)
    top = kd.map_top
    data[top[0]] = c2 * kd.mass
    data[top[n + 1]] = c2 * kd.mass
    asx, asy = C * sx - S * sy, S * sx + C * sy                # A s̄
    aesfx, aesfy = -S * sf1x - C * sf1y, C * sf1x - S * sf1y  # A E S̄ f_1
    data[top[2]] = c2 * aesx - w1 * asx + aesfx
    data[top[n + 2]] = c2 * aesy - w1 * asy + aesfy
    data[top[2 * n]] = c2 * aesx - sig * (ca * (-c0y) - sa * c0x)
    data[top[2 * n + 1]] = c2 * aesy - sig * (sa * (-c0y) + ca * c0x)
    data[top[2 * n + 2]] = (c2 * J - (bx * sx + by * sy)
                            - dt * (0.5 * dsig * X - 0.25 * sig * (b0x * c1x + b0y * c1y + b1x * c0x + b1y * c0y))
                            + sig * (b0x * smx + b0y * smy))
    left = kd.map_left
    for i in range(nf):
        s0i, s1i = sbar[0, i], sbar[1, i]
        asb0, asb1 = C * s0i - S * s1i, S * s0i + C * s1i      # A S̄
        aesb0, aesb1 = -S * s0i - C * s1i, C * s0i - S * s1i  # A E S̄
        ai = kd.k0n[i] + hq1[i]
        cmi = kd.c[i] + maq1[i]
        cmmi = kd.c[i] + maqm[i]
        sbeb = -s1i * bx + s0i * by                            # S̄ᵀEᵀ b
        sbeb0 = -s1i * b0x + s0i * b0y
        sbe_wb = -s1i * wbx + s0i * wby
        sbt_wb = s0i * wbx + s1i * wby
        data[top[3 + i]] = c2 * asb0 + w1 * aesb0
        data[top[n + 3 + i]] = c2 * asb1 + w1 * aesb1
        data[top[2 * n + 3 + i]] = (c2 * ai + sbeb + 2.0 * w1 * cmi - hf1[i] + (0.25 * dt * sig) * sbt_wb
                                    - sig * sbeb0)
        data[left[3 * i]] = c2 * asb0 - (kap * w0) * (-s1i * ca - s0i * sa)
        data[left[3 * i + 1]] = c2 * asb1 - (kap * w0) * (-s1i * sa + s0i * ca)
        data[left[3 * i + 2]] = (c2 * ai + sbeb - dt * (0.5 * dkap * sbe_wb - 0.25 * kap * sbt_wb)
                                 - (kap * sbeb0 + 2.0 * w0 * cmmi - hf0[i]))
    # ---------------------------------------------------------------- constant elastic blocks
    cma = -0.5 * dt * w0 * w1
    ch = w1 + w0
    for k in range(kd.mff_dat.size):
        data[kd.map_mff[k]] += c2 * kd.mff_dat[k]
    for k in range(kd.h_dat.size):
        data[kd.map_h[k]] += ch * kd.h_dat[k]
    for k in range(kd.ma_dat.size):
        data[kd.map_ma[k]] += cma * kd.ma_dat[k]
    # ---------------------------------------------------------------- strain energy: stress at the mean strain
    gp = np.zeros(n)
    for i in range(nf):
        gp[3 + i] = kqm[i]
    hv = np.zeros(data.size)                                   # ∂g_pot/∂q1 in the pattern
    for k in range(kd.k_dat.size):
        hv[kd.map_k[k]] += 0.5 * kd.k_dat[k]
    if kd.green:
        dn, loc, wq, mloc = kd.dn, kd.loc, kd.wq, kd.map_loc
        nel, nqp, nl = dn.shape
        up0, wp0, e0 = _axial_strains(kd, q0)
        up1, wp1, e1 = _axial_strains(kd, q1)
        coef = np.empty((2, 2))
        for e in range(nel):
            for kq in range(nqp):
                k = e * nqp + kq
                upm, wpm = 0.5 * (up0[k] + up1[k]), 0.5 * (wp0[k] + wp1[k])
                t = wq[k] * (0.5 * (e0[k] + e1[k]))
                for l in range(nl):
                    iu, iw = loc[e, l], loc[e, nl + l]
                    if iu >= 0:
                        gp[3 + iu] += dn[e, kq, l] * (t * (1.0 + upm))
                    if iw >= 0:
                        gp[3 + iw] += dn[e, kq, l] * (t * wpm)
                # ½ Σ EA dx [dε(q_m)ᵀ dε(q1) + ½(ε0 + ε1) d²ε]: per-point coefficients of the (u, w) blocks
                wh = 0.5 * wq[k]
                weps = 0.5 * t
                wa0, wa1 = wh * (1.0 + upm), wh * wpm
                b0 = 1.0 + up1[k]
                coef[0, 0] = wa0 * b0 + weps
                coef[0, 1] = wa0 * wp1[k]
                coef[1, 0] = wa1 * b0
                coef[1, 1] = wa1 * wp1[k] + weps
                for ia in range(2 * nl):
                    for ib in range(2 * nl):
                        pos = mloc[e, ia, ib]
                        if pos >= 0:
                            hv[pos] += coef[ia // nl, ib // nl] * (dn[e, kq, ia % nl] * dn[e, kq, ib % nl])
    if kd.quartic:                                             # modal body: cubic and quartic energy terms
        g4, dg4 = quartic_discrete_gradient(kd.k3p, kd.k3q, kd.k3a, kd.k3b, kd.k4a, kd.k4s, kd.k4w, q0, q1, 3)
        for i in range(nf):
            gp[3 + i] += g4[i]
            for j in range(nf):
                hv[kd.map_ee[i * nf + j]] += dg4[i, j]
    floor = np.zeros(n)
    ptr, idx = kd.pat_ptr, kd.pat_idx
    for i in range(n):
        s = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            h = hv[k]
            if h != 0.0:
                data[k] += dt * h
                s += abs(h) * (abs(q0[idx[k]]) + abs(q1[idx[k]]))
        floor[i] = dt * s
    return p, gk, gp, data, floor


@numba.njit(cache=True)
def newmark_terms(kd, q, v, a, c_a, c_v, terms):
    r"""The terms of a floating-frame body in one Newton evaluation of the Newmark schemes (trapezoidal,
    generalized-α: :meth:`Newmark.step <skfem_flex.schemes.integrators.Newmark.step>`), at one state.

    With ω = θ̇, f = q̇_f (from ``v``) and the acceleration ``a`` = (Ä, α, a_f)::

        inertia = M(q) a
        grad    = ∇V(q)
        qv      = Q_v(q, v) = (A(ω² s̄ − 2ω E S̄ f),  −2ω c_mᵀ f,  ω² c_m − 2ω H f)
        data    = c_a M(q) + B(q, a) + K(q) − (∂Q_v/∂q + c_v ∂Q_v/∂v)
        mass_terms = |M(q)| terms

    B(q, a) = ∂(M(q) a)/∂q and K = ∂²V/∂q²: the numpy references are the body methods
    ``mass_matrix``, ``momentum_jacobian``, ``quadratic_velocity_force``, ``potential_gradient`` and
    ``potential_hessian`` (:class:`~skfem_flex.bodies.ffr.FloatingFrame`, FloatingBeam, ModalBody;
    tests/test_floating_newmark_kernel.py). V is the strain energy of :func:`potential_energy`.

    Parameters
    ----------
    kd : FloatingKernelData
        The body's packed arrays (``body.compiled_kernel_data()``).
    q, v, a : ndarray (n,)
        Coordinates (m, rad, elastic), velocities and accelerations (per s, per s²).
    c_a, c_v : float
        ∂a/∂q = c_a (1/s², (1 − α_m)/((1 − α_f) β Δt²)) and ∂v/∂q = c_v (1/s, γ/(β Δt)) of the scheme.
    terms : ndarray (n,)
        Nonnegative weights (the sizes of the terms whose differences make the acceleration).

    Returns
    -------
    inertia : ndarray (n,)
        M(q) a, N and N m.
    grad : ndarray (n,)
        ∇V(q), N and N m.
    qv : ndarray (n,)
        Q_v(q, v), N and N m.
    data : ndarray (nnz,)
        The tangent as the data array of the body's CSR pattern (``kd.pat_ptr``, ``kd.pat_idx``).
    mass_terms : ndarray (n,)
        Σ_j |M_ij(q)| terms_j: the round-off floor of the inertia force (times c_a in the scheme).
    """
    n, nf = kd.n, kd.nf
    sbar = kd.sbar
    om = v[2]
    oa = a[2]
    # ---------------------------------------------------------------- products with the elastic state
    sqx, sqy, sfx, sfy, sax, say = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for i in range(nf):
        sqx += sbar[0, i] * q[3 + i]
        sqy += sbar[1, i] * q[3 + i]
        sfx += sbar[0, i] * v[3 + i]
        sfy += sbar[1, i] * v[3 + i]
        sax += sbar[0, i] * a[3 + i]
        say += sbar[1, i] * a[3 + i]
    maq = _matvec(kd.ma_ptr, kd.ma_idx, kd.ma_dat, q, 3)
    hq = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, q, 3)
    maf = _matvec(kd.ma_ptr, kd.ma_idx, kd.ma_dat, v, 3)
    hf = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, v, 3)
    ha = _matvec(kd.h_ptr, kd.h_idx, kd.h_dat, a, 3)
    kq = _matvec(kd.k_ptr, kd.k_idx, kd.k_dat, q, 3)
    # s̄ = S_0 + S̄ q_f, c_m = c + M_A q_f, J = I_0 + q_f·(c + c_m)
    sx, sy = kd.s0x + sqx, kd.s0y + sqy
    J = kd.i0
    cmf = 0.0
    for i in range(nf):
        cmi = kd.c[i] + maq[i]
        J += q[3 + i] * (kd.c[i] + cmi)
        cmf += cmi * v[3 + i]
    C, S = math.cos(q[2]), math.sin(q[2])
    aesx, aesy = C * (-sy) - S * sx, S * (-sy) + C * sx        # A E s̄
    asx, asy = C * sx - S * sy, S * sx + C * sy                # A s̄
    # ---------------------------------------------------------------- quadratic velocity force
    inx, iny = om * om * sx + 2.0 * om * sfy, om * om * sy - 2.0 * om * sfx   # ω² s̄ − 2ω E S̄ f
    qv = np.empty(n)
    qv[0] = C * inx - S * iny
    qv[1] = S * inx + C * iny
    qv[2] = -2.0 * om * cmf
    for i in range(nf):
        qv[3 + i] = om * om * (kd.c[i] + maq[i]) - 2.0 * om * hf[i]
    # ---------------------------------------------------------------- M alone (inertia, mass_terms), then the tangent
    mdat = np.zeros(kd.pat_idx.size)
    data = np.zeros(kd.pat_idx.size)
    top, left = kd.map_top, kd.map_left
    mdat[top[0]] = kd.mass
    mdat[top[n + 1]] = kd.mass
    mdat[top[2]] = aesx
    mdat[top[n + 2]] = aesy
    mdat[top[2 * n]] = aesx
    mdat[top[2 * n + 1]] = aesy
    mdat[top[2 * n + 2]] = J
    bax, bay = C * a[0] + S * a[1], -S * a[0] + C * a[1]      # Aᵀ R̈
    aesax, aesay = -S * sax - C * say, C * sax - S * say      # A E S̄ a_f
    vx, vy = 2.0 * om * sx + 2.0 * sfy, 2.0 * om * sy - 2.0 * sfx           # 2ω s̄ − 2 E S̄ f
    # column θ of rows R: B − ∂Q_v/∂θ − c_v ∂Q_v/∂ω (A E (ω² s̄ − 2ω E S̄ f) and A(2ω s̄ − 2 E S̄ f))
    data[top[2]] = (-oa * asx + aesax) - (-S * inx - C * iny) - c_v * (C * vx - S * vy)
    data[top[n + 2]] = (-oa * asy + aesay) - (C * inx - S * iny) - c_v * (S * vx + C * vy)
    data[top[2 * n + 2]] = -(bax * sx + bay * sy) + 2.0 * c_v * cmf
    w2 = om * om
    for i in range(nf):
        s0i, s1i = sbar[0, i], sbar[1, i]
        asb0, asb1 = C * s0i - S * s1i, S * s0i + C * s1i      # A S̄
        aesb0, aesb1 = -S * s0i - C * s1i, C * s0i - S * s1i  # A E S̄
        ai = kd.k0n[i] + hq[i]
        cmi = kd.c[i] + maq[i]
        sbeb = -s1i * bax + s0i * bay                          # S̄ᵀEᵀ Aᵀ R̈
        mdat[top[3 + i]] = asb0
        mdat[top[n + 3 + i]] = asb1
        mdat[top[2 * n + 3 + i]] = ai
        mdat[left[3 * i]] = asb0
        mdat[left[3 * i + 1]] = asb1
        mdat[left[3 * i + 2]] = ai
        data[top[3 + i]] = oa * aesb0 - w2 * asb0 + 2.0 * c_v * om * aesb0
        data[top[n + 3 + i]] = oa * aesb1 - w2 * asb1 + 2.0 * c_v * om * aesb1
        data[top[2 * n + 3 + i]] = (sbeb + 2.0 * oa * cmi - ha[i]) + 2.0 * om * maf[i] + 2.0 * c_v * om * cmi
        data[left[3 * i + 2]] = sbeb - c_v * (2.0 * om * cmi - 2.0 * hf[i])
    for k in range(kd.mff_dat.size):
        mdat[kd.map_mff[k]] += kd.mff_dat[k]
    inertia = np.empty(n)
    mass_terms = np.empty(n)
    ptr, idx = kd.pat_ptr, kd.pat_idx
    for i in range(n):
        s, t = 0.0, 0.0
        for k in range(ptr[i], ptr[i + 1]):
            s += mdat[k] * a[idx[k]]
            t += abs(mdat[k]) * terms[idx[k]]
        inertia[i] = s
        mass_terms[i] = t
    for k in range(data.size):
        data[k] += c_a * mdat[k]
    # ---------------------------------------------------------------- constant elastic blocks
    ch = oa + 2.0 * c_v * om
    for k in range(kd.h_dat.size):
        data[kd.map_h[k]] += ch * kd.h_dat[k]
    for k in range(kd.ma_dat.size):
        data[kd.map_ma[k]] -= w2 * kd.ma_dat[k]
    for k in range(kd.k_dat.size):
        data[kd.map_k[k]] += kd.k_dat[k]
    # ---------------------------------------------------------------- strain energy beyond ½ q_fᵀ K q_f
    grad = np.zeros(n)
    for i in range(nf):
        grad[3 + i] = kq[i]
    if kd.green:
        dn, loc, wq, mloc = kd.dn, kd.loc, kd.wq, kd.map_loc
        nel, nqp, nl = dn.shape
        up, wp, eps = _axial_strains(kd, q)
        coef = np.empty((2, 2))
        for e in range(nel):
            for kq_ in range(nqp):
                k = e * nqp + kq_
                t = wq[k] * eps[k]
                b0, b1 = 1.0 + up[k], wp[k]                    # dε = (1 + u') dN_u + w' dN_w
                for l in range(nl):
                    iu, iw = loc[e, l], loc[e, nl + l]
                    if iu >= 0:
                        grad[3 + iu] += dn[e, kq_, l] * (t * b0)
                    if iw >= 0:
                        grad[3 + iw] += dn[e, kq_, l] * (t * b1)
                # EA dx (dεᵀ dε + ε d²ε), d²ε = dN_uᵀ dN_u + dN_wᵀ dN_w
                coef[0, 0] = wq[k] * b0 * b0 + t
                coef[0, 1] = wq[k] * b0 * b1
                coef[1, 0] = coef[0, 1]
                coef[1, 1] = wq[k] * b1 * b1 + t
                for ia in range(2 * nl):
                    for ib in range(2 * nl):
                        pos = mloc[e, ia, ib]
                        if pos >= 0:
                            data[pos] += coef[ia // nl, ib // nl] * (dn[e, kq_, ia % nl] * dn[e, kq_, ib % nl])
    if kd.quartic:
        # the discrete gradient between equal states is the gradient; it is symmetric in its two
        # states, so the Hessian is twice its derivative with respect to one of them
        g4, dg4 = quartic_discrete_gradient(kd.k3p, kd.k3q, kd.k3a, kd.k3b, kd.k4a, kd.k4s, kd.k4w, q, q, 3)
        for i in range(nf):
            grad[3 + i] += g4[i]
            for j in range(nf):
                data[kd.map_ee[i * nf + j]] += 2.0 * dg4[i, j]
    return inertia, grad, qv, data, mass_terms
