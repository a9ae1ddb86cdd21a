r"""Position maps of body points in the plane: the one compiled description of where a point of a body is.

Joints, point loads, springs, gravity's first moments and probes all read body points through maps
packed once per scene (:func:`pack_maps`); a map is one of

* LINEAR: r = G q + c (point masses, rigid bodies, exact-beam nodes, the first moment ∫ r dm of a
  body linear in q), G (2, n_b);
* FRAME: r = m_R R + A(θ)(y₀ + Y q_f) with R = q[0:2], θ = q[2], q_f = q[3:] (floating-frame bodies:
  points, and the first moment m R + A(θ)(S₀ + S̄ q_f)).

For each the kernels give the value, the Jacobian, the exact discrete gradient D with
D (q₁ − q₀) = r(q₁) − r(q₀) (FRAME: A(θ₁) − A(θ₀) = sinc(Δθ/2) Δθ A(θ_m) E, (A₀ + A₁)/2 =
cos(Δθ/2) A(θ_m), so D = [m_R I, sinc(Δθ/2) A(θ_m) E s_m, cos(Δθ/2) A(θ_m) Y], s_m = y₀ + Y q_f,m),
its derivative ∂(Dᵀf)/∂q₁ for a fixed f, the Hessian product ∂(r_qᵀ f)/∂q and the velocity Jacobian
∂(r_q v)/∂q. ``q`` is always the body's own block of the coordinates (``off``, ``nb`` of the map).
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from ..numerics.rotations import sinc_half
from .abi import f1, f2, i2
from .storage import add_qq

__all__ = ["add_frame_dgrad_jacobian", "LINEAR", "FRAME", "KIND", "OFF", "NB", "GPTR", "YPTR", "M_R", "CX", "CY", "Y0X", "Y0Y", "MapData", "MapStore", "maps_view", "position_into", "jacobian_into",
           "dgrad_into", "dgrad_jacobian_parts", "frame_offset", "hessian_parts", "velocity_jacobian_into"]

LINEAR, FRAME = 0, 1


#: columns of MapData.ints: kind (LINEAR, FRAME), offset and size of the body's block, where its G and Y start
KIND, OFF, NB, GPTR, YPTR = range(5)
#: columns of MapData.floats: m_R, c (2), y₀ (2)
M_R, CX, CY, Y0X, Y0Y = range(5)


class MapData(NamedTuple):
    """Every map of a scene (k maps): per map the integers (k, 5) and floats (k, 5) named by the column
    constants above, and the flattened G (2 × n_b each, from ints[k, GPTR]) and Y (2 × (n_b − 3) each, from
    ints[k, YPTR])."""
    ints: np.ndarray
    floats: np.ndarray
    gdat: np.ndarray
    ydat: np.ndarray


@numba.njit(cache=True, _nrt=False)
def maps_view(fam):
    """The :class:`MapData` of a maps record (build it once per kernel call and pass it on)."""
    return MapData(i2(fam, 0), f2(fam, 1), f1(fam, 2), f1(fam, 3))


class MapStore:
    """Collects maps while a scene is packed; :meth:`data` gives the :class:`MapData`."""

    def __init__(self):
        self.rows = []
        self.g, self.y, self.blocks = [], [], []
        self.ng = self.ny = 0

    def add(self, entry, off, nb):
        """Add a map from a body point's ``compiled_map()`` entry on the body block at ``off`` of size
        ``nb``: ("linear", G, c) or ("frame", m_R, y0, Y). Returns its index."""
        kind = entry[0]
        if kind == "linear":
            _, G, c = entry
            G = np.asarray(G, dtype=float).reshape(2, nb)
            self.rows.append((LINEAR, off, nb, 0.0, np.asarray(c, dtype=float).reshape(2), np.zeros(2), self.ng,
                              self.ny))
            self.g.append(G.ravel())
            self.ng += G.size
            self.blocks.append(G)
        elif kind == "frame":
            _, m_r, y0, Y = entry
            Y = np.asarray(Y, dtype=float).reshape(2, nb - 3)
            self.rows.append((FRAME, off, nb, float(m_r), np.zeros(2), np.asarray(y0, dtype=float).reshape(2),
                              self.ng, self.ny))
            self.y.append(Y.ravel())
            self.ny += Y.size
            self.blocks.append(Y)
        else:
            raise ValueError(f"unknown position map kind {kind!r}; expected 'linear' or 'frame'")
        return len(self.rows) - 1

    def support(self, k):
        """The scene coordinates map k's position can depend on (:func:`map_support`)."""
        kind, off = self.rows[k][0], self.rows[k][1]
        if kind == LINEAR:
            cols = np.flatnonzero(self.blocks[k].any(axis=0))
        else:
            cols = np.concatenate([[0, 1, 2], 3 + np.flatnonzero(self.blocks[k].any(axis=0))])
        return off + cols.astype(np.int64)

    def data(self):
        ints = np.array([(kind, off, nb, gp, yp) for kind, off, nb, _, _, _, gp, yp in self.rows],
                        dtype=np.int64).reshape(-1, 5)
        floats = np.array([(m_r, c[0], c[1], y0[0], y0[1]) for _, _, _, m_r, c, y0, _, _ in self.rows],
                          dtype=float).reshape(-1, 5)
        return MapData(ints, floats, np.concatenate(self.g + [np.zeros(1)]), np.concatenate(self.y + [np.zeros(1)]))


@numba.njit(cache=True, _nrt=False)
def frame_offset(maps, k, qa, qb):
    """(s_x, s_y) = y₀ + Y (q_a,f + q_b,f)/2 of FRAME map k (q_a = q_b: at that state, exactly)."""
    ne = maps.ints[k, NB] - 3
    y = maps.ints[k, YPTR]
    sx, sy = maps.floats[k, Y0X], maps.floats[k, Y0Y]
    for j in range(ne):
        qm = 0.5 * (qa[3 + j] + qb[3 + j])
        sx += maps.ydat[y + j] * qm
        sy += maps.ydat[y + ne + j] * qm
    return sx, sy


@numba.njit(cache=True, _nrt=False)
def position_into(maps, k, q, out):
    """out[0:2] = r(q) of map k, m."""
    if maps.ints[k, KIND] == LINEAR:
        n, g0 = maps.ints[k, NB], maps.ints[k, GPTR]
        for a in range(2):
            s = maps.floats[k, CX + a]
            for j in range(n):
                s += maps.gdat[g0 + a * n + j] * q[j]
            out[a] = s
        return
    sx, sy = frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    out[0] = maps.floats[k, M_R] * q[0] + C * sx - S * sy
    out[1] = maps.floats[k, M_R] * q[1] + S * sx + C * sy


@numba.njit(cache=True, _nrt=False)
def jacobian_into(maps, k, q, out):
    """out[:, :n_b] = ∂r/∂q of map k."""
    n = maps.ints[k, NB]
    if maps.ints[k, KIND] == LINEAR:
        g0 = maps.ints[k, GPTR]
        for a in range(2):
            for j in range(n):
                out[a, j] = maps.gdat[g0 + a * n + j]
        return
    ne, y = n - 3, maps.ints[k, YPTR]
    sx, sy = frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    out[0, 0] = out[1, 1] = maps.floats[k, M_R]
    out[0, 1] = out[1, 0] = 0.0
    out[0, 2] = -S * sx - C * sy            # A E s, E = [[0, −1], [1, 0]]
    out[1, 2] = C * sx - S * sy
    for j in range(ne):
        yx, yy = maps.ydat[y + j], maps.ydat[y + ne + j]
        out[0, 3 + j] = C * yx - S * yy
        out[1, 3 + j] = S * yx + C * yy


@numba.njit(cache=True, _nrt=False)
def dgrad_into(maps, k, q0, q1, out):
    """out[:, :n_b] = the exact discrete gradient D of map k: D (q₁ − q₀) = r(q₁) − r(q₀)."""
    if maps.ints[k, KIND] == LINEAR:
        jacobian_into(maps, k, q0, out)
        return
    n = maps.ints[k, NB]
    ne, y = n - 3, maps.ints[k, YPTR]
    half = 0.5 * (q1[2] - q0[2])
    tm = q0[2] + half
    C, S = np.cos(tm), np.sin(tm)
    sig, kap = sinc_half(q1[2] - q0[2])[0], np.cos(half)
    sx, sy = frame_offset(maps, k, q0, q1)
    out[0, 0] = out[1, 1] = maps.floats[k, M_R]
    out[0, 1] = out[1, 0] = 0.0
    out[0, 2] = sig * (-S * sx - C * sy)
    out[1, 2] = sig * (C * sx - S * sy)
    for j in range(ne):
        yx, yy = maps.ydat[y + j], maps.ydat[y + ne + j]
        out[0, 3 + j] = kap * (C * yx - S * yy)
        out[1, 3 + j] = kap * (S * yx + C * yy)


@numba.njit(cache=True, _nrt=False)
def dgrad_jacobian_parts(maps, k, q0, q1, f, row, col):
    """The nonzero parts of ∂(Dᵀ f)/∂q₁ of a FRAME map (zero for LINEAR): the (θ, θ) entry (returned),
    the θ row over q_f (``row``) and the q_f rows of the θ column (``col``)."""
    ne, y = maps.ints[k, NB] - 3, maps.ints[k, YPTR]
    half = 0.5 * (q1[2] - q0[2])
    tm = q0[2] + half
    C, S = np.cos(tm), np.sin(tm)
    sig, dsig = sinc_half(q1[2] - q0[2])
    kap, sn = np.cos(half), np.sin(half)
    sx, sy = frame_offset(maps, k, q0, q1)
    fax = f[0] * C + f[1] * S              # Aᵀ(θ_m) f
    fay = -f[0] * S + f[1] * C
    h22 = dsig * (-fax * sy + fay * sx) - 0.5 * sig * (fax * sx + fay * sy)
    for j in range(ne):
        yx, yy = maps.ydat[y + j], maps.ydat[y + ne + j]
        row[j] = 0.5 * sig * (fay * yx - fax * yy)
        col[j] = -0.5 * sn * (yx * fax + yy * fay) + 0.5 * kap * (yx * fay - yy * fax)
    return h22


@numba.njit(cache=True, _nrt=False)
def hessian_parts(maps, k, q, f, row):
    """The nonzero parts of ∂(r_qᵀ f)/∂q of a FRAME map (symmetric): the (θ, θ) entry −f·A s (returned)
    and the (θ, q_f) entries f·A E Y_j (``row``)."""
    ne, y = maps.ints[k, NB] - 3, maps.ints[k, YPTR]
    sx, sy = frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    fax = f[0] * C + f[1] * S
    fay = -f[0] * S + f[1] * C
    for j in range(ne):
        row[j] = fay * maps.ydat[y + j] - fax * maps.ydat[y + ne + j]
    return -(fax * sx + fay * sy)


@numba.njit(cache=True, _nrt=False)
def velocity_jacobian_into(maps, k, q, v, out):
    """out[:, :n_b] = ∂(r_q v)/∂q of map k (zero for LINEAR): for FRAME only the θ and q_f columns,
    ∂/∂θ = −ω A s + A E Y v_f, ∂/∂q_f,j = ω A E Y_j."""
    n = maps.ints[k, NB]
    for a in range(2):
        for j in range(n):
            out[a, j] = 0.0
    if maps.ints[k, KIND] == LINEAR:
        return
    ne, y = n - 3, maps.ints[k, YPTR]
    sx, sy = frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    w = v[2]
    # Y v_f
    ux, uy = 0.0, 0.0
    for j in range(ne):
        ux += maps.ydat[y + j] * v[3 + j]
        uy += maps.ydat[y + ne + j] * v[3 + j]
    # −ω A s + A E u, A E u = A (−uy, ux)
    out[0, 2] = -w * (C * sx - S * sy) + (C * (-uy) - S * ux)
    out[1, 2] = -w * (S * sx + C * sy) + (S * (-uy) + C * ux)
    for j in range(ne):
        yx, yy = maps.ydat[y + j], maps.ydat[y + ne + j]
        out[0, 3 + j] = w * (C * (-yy) - S * yx)
        out[1, 3 + j] = w * (S * (-yy) + C * yx)


@numba.njit(cache=True, _nrt=False)
def add_frame_dgrad_jacobian(ctx, st, maps, k, qa, qb, fx, fy, w, work, floor):
    """Newton matrix += w ∂(D_kᵀ f)/∂q_b of map k (zero for LINEAR), and its round-off floor
    |w ∂(Dᵀf)/∂q_b| (|q_a| + |q_b|) into ``floor`` (global); qa, qb the global coordinates, ``work`` ≥
    2 n_b + 2 floats."""
    if maps.ints[k, KIND] == LINEAR:
        return
    o, nb = maps.ints[k, OFF], maps.ints[k, NB]
    f = work[:2]
    f[0], f[1] = fx, fy
    row, col = work[2:nb - 1], work[nb - 1:2 * nb - 4]
    h22 = dgrad_jacobian_parts(maps, k, qa[o:o + nb], qb[o:o + nb], f, row, col)
    a2 = abs(qa[o + 2]) + abs(qb[o + 2])
    add_qq(ctx, st, o + 2, o + 2, w * h22)
    fl2 = abs(w * h22) * a2
    for j in range(nb - 3):
        add_qq(ctx, st, o + 2, o + 3 + j, w * row[j])
        add_qq(ctx, st, o + 3 + j, o + 2, w * col[j])
        fl2 += abs(w * row[j]) * (abs(qa[o + 3 + j]) + abs(qb[o + 3 + j]))
        floor[o + 3 + j] += abs(w * col[j]) * a2
    floor[o + 2] += fl2
