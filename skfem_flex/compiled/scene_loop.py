r"""Compiled (Numba) time loops for scenes of bodies, joints, drivers, springs, dampers and loads.

:mod:`skfem_flex.compiled.single_body_loop` runs one floating-frame body without joints or loads. This module
runs the energy-momentum scheme and the Newmark family (trapezoidal, generalized-α; the section "the
Newmark step" at the end) for every other scene: point masses
and rigid bodies, floating-frame bodies (a :class:`~skfem_flex.bodies.FloatingBeam` or a
:class:`~skfem_flex.bodies.ModalBody`, reduced or not), geometrically exact beams (Cayley rotation
rates), gravity, coordinate, two-point and torsion springs, two-point and torsion dampers, global and
follower point forces, moments and the exact beam's loads, pins, revolute joints, welds, distance
constraints, drivers, sliders and prismatic joints on ground lines and on moving bodies, prescribed
coordinates — every catalogue mechanism. A scene is *packed* once into flat arrays
through public interfaces of its parts (no type checks):

* a body with constant mass gives its mass matrix and the first moment of its mass
  ``mass_moment()`` (Γ, c), ∫ r dm = Γ q + c, and, if it has a strain energy, its
  ``compiled_strain_data()`` (an exact beam); a floating-frame body its ``compiled_kernel_data()``
  and ``mass_moment_map()`` (m, S₀, S̄), ∫ r dm = m R + A(θ)(S₀ + S̄ q_f); a body whose momenta are
  not R × p_R + p_θ gives its ``momentum_layout()``;
* a body point its ``compiled_map()``: ("linear", G, c) for r = G q + c, or ("frame", y₀, Y) for
  r = R + A(θ)(y₀ + Y q_f);
* a force element its ``compiled_form()`` (:meth:`skfem_flex.elements.forces.ForceElement.compiled_form`);
* a constraint its ``compiled_form()``: blocks of rows made of its terms' forms
  (:meth:`skfem_flex.elements.point_terms.Term.compiled_form`), each minus a motion law where it has one, or
  ("distance", point, a, l) for Φ = ½(|r − a|² − l²).

Every position map, of a joint's point, a point load and gravity's first moment alike, is one of the
two forms above, and one set of kernels gives its value, Jacobian, exact discrete gradient
(products by the mean-value rule, A(θ₁) − A(θ₀) = sinc(Δθ/2) Δθ A(θ_m) E, as the numpy points do)
and those derivatives' Jacobians. Functions of time (motion laws, load histories) are evaluated in
Python once per chunk into a table (:func:`time_table`). ``tests/test_compiled_scene.py`` holds the
kernels to the numpy points and bodies at 1e-12 and the loop's trajectories to the Python step.

The step is the one of :meth:`~skfem_flex.schemes.integrators.EnergyMomentum.step` (same residual, Cayley
scaling, scales, round-off floor, initial guess), on the package's one Newton core
(:mod:`skfem_flex.numerics.newton`); the bordered Newton matrix is solved as a band with a dense border
(:func:`skfem_flex.numerics.linear_solver.bordered_band_solve`) when the scene's pattern makes that cheaper,
else by LAPACK. Up to :data:`DENSE_STORAGE_LIMIT` rows the matrix is stored dense; above, as the values
of its pattern (fixed once per scene from the packed structure, :func:`_newton_pattern`) and solved by
:func:`skfem_flex.numerics.linear_solver.bordered_band_solve_csr`, so that a step's cost grows linearly with the
mesh (section "the Newton matrix"); the constraint rows are swept over their spans only. On any failure
the loop stops before the failing step and ``simulate`` re-runs that step on the Python path, as for
:mod:`skfem_flex.compiled.single_body_loop`.
"""
from __future__ import annotations

import weakref

import numba
import numpy as np
import scipy.sparse as sps

from ..bodies.exact import kernel as exact_kernel
from ..bodies.base import COMPILED_SIZE_LIMIT, DENSE_LIMIT
from ..bodies.floating.kernel import energy_momentum_terms, momentum, newmark_terms, potential_energy, sinc_half
from .single_body_loop import chunk_records, chunk_schedule, is_recorded, record_buffers, record_count, record_step
from ..schemes.integrators import EnergyMomentum, GeneralizedAlpha, Newmark, Trapezoidal, predictor_acceleration
from ..numerics.linear_solver import (MAX_BORDER, MIN_DENSE_BORDERED, bordered_band_solve, bordered_band_solve_csr,
                            dense_bordered_plan, reordered_band_plan)
from ..numerics.newton import (CONVERGED, EVALUATE, NONFINITE_RESIDUAL, all_finite, max_abs, newton_evaluated, newton_solved,
                     newton_start, predicted_increment, roundoff_floor)
from ..numerics.rotations import SERIES_BELOW, sinc
from ..scene import Scene

__all__ = ["run_loop", "eligible", "run_chunk", "chunk_steps", "pack", "pack_maps", "time_table", "newton_system",
           "newton_matrix", "missed_entries", "DENSE_STORAGE_LIMIT", "map_position", "map_jacobian", "map_dgrad",
           "map_dgrad_jacobian", "map_hessian_product", "LINEAR", "FRAME", "POINTS", "DISTANCE", "OK"]

_TINY = 1e-300
#: status of :func:`run_chunk` when every step was done
OK = CONVERGED
#: kinds of position maps
LINEAR, FRAME = 0, 1
#: kinds of constraint blocks: Σ sign r(point) − c (2 rows), its projection on a constant normal
#: (1 row), g · q + c − x(t) (1 row), ½(|r − a|² − l²) (1 row), the projection on a normal A(g · q + c) n_loc
#: that turns with a body (1 row; g in the linear rows' arrays, c in ``length``, n_loc in ``nrm``)
POINTS, PROJECTED, LINEAR_ROW, DISTANCE, ROTATED = 0, 1, 2, 3, 4
#: kinds of force elements, with their integers | floats in the packed ``loads``: V = ½ k q_i^p (i, p | k);
#: Q = J_rᵀ F(t) (map, table column | ); Q = g F(t) (column, indices | g); V = ½ k (g·q + c)² (indices |
#: k, c, g); Q = −c (g·v) g (indices | c, g); Q = J_rᵀ A(g·q + c) F(t) (map, column, indices | c, g);
#: V = ½ k (|d| − l₀)² and the damper along d, d = r_a − r_b (map a, map b or −1 for the ground | k, l₀, ground
#: point; c, ground point)
COORD_SPRING, POINT_FORCE, GENERALIZED_FORCE, ROW_SPRING, ROW_DAMPER, FOLLOWER_FORCE, TWO_POINT_SPRING, \
    TWO_POINT_DAMPER = range(8)



# ==================================================================== the Newton matrix
# The step's Newton matrix (free coordinates, then multipliers; nx rows) is a flat float array ``mat``,
# addressed through an int array ``fpos`` that every kernel writing to it gets anyway: fpos[:n] is the
# position of each coordinate among the free ones (−1: prescribed), and its last three entries are
# (n, nx, storage). Dense storage (0): entry (i, j) at mat[i·nx + j]. CSR storage (1, scenes above
# DENSE_STORAGE_LIMIT): the values of a fixed pattern (_newton_pattern), whose row pointers and column
# indices follow fpos[:n]; entry (i, j) is found by a binary search of row i. One array instead of three:
# each array passed between compiled functions costs compile time. ``mat``'s last entry counts the
# nonzero values written outside the pattern (a pattern that missed an entry: the step goes to Python).
DENSE, CSR = 0, 1


@numba.njit(cache=True, _nrt=False)
def _entry(fpos, i, j):
    """Where entry (i, j) of the Newton matrix is stored in ``mat``, or −1 if the pattern lacks it."""
    size = fpos.size
    nx = fpos[size - 2]
    if fpos[size - 1] == DENSE:
        return i * nx + j
    n = fpos[size - 3]
    lo, hi = fpos[n + i], fpos[n + i + 1]
    cols = n + nx + 1
    while lo < hi:
        mid = (lo + hi) >> 1
        c = fpos[cols + mid]
        if c < j:
            lo = mid + 1
        elif c > j:
            hi = mid
        else:
            return mid
    return -1


@numba.njit(cache=True, _nrt=False)
def _madd(mat, fpos, i, j, val):
    """mat[i, j] += val (Newton-matrix numbering; see the section's comment)."""
    if val == 0.0:                      # a structural zero need not be looked up
        return
    t = _entry(fpos, i, j)
    if t >= 0:
        mat[t] += val
    else:
        mat[mat.size - 1] += 1.0


@numba.njit(cache=True, _nrt=False)
def _mscale_row(mat, fpos, i, ncols, factor):
    """mat[i, :ncols] *= factor."""
    size = fpos.size
    nx = fpos[size - 2]
    if fpos[size - 1] == DENSE:
        for j in range(ncols):
            mat[i * nx + j] *= factor
        return
    n = fpos[size - 3]
    cols = n + nx + 1
    for t in range(fpos[n + i], fpos[n + i + 1]):
        if fpos[cols + t] < ncols:
            mat[t] *= factor


def _matrix_index(fpos, nx, pattern=None):
    """The ``fpos`` array of the section's comment: dense storage, or CSR storage of ``pattern`` (a scipy
    CSR matrix, nx × nx, sorted indices)."""
    n = fpos.size
    if pattern is None:
        return np.concatenate([fpos, [n, nx, DENSE]]).astype(np.int64)
    return np.concatenate([fpos, pattern.indptr, pattern.indices, [n, nx, CSR]]).astype(np.int64)


def newton_matrix(system):
    """The Newton matrix of a :func:`newton_system` after an evaluation: a dense array, or a scipy CSR
    matrix for scenes stored that way (above :data:`DENSE_STORAGE_LIMIT` coordinates)."""
    packed, ws = system[0], system[2]
    fpos, mat = packed[9][4], ws[1]
    n, nx, storage = (int(a) for a in fpos[-3:])
    if storage == DENSE:
        return mat[:nx * nx].reshape(nx, nx).copy()
    ptr = fpos[n:n + nx + 1]
    nnz = int(ptr[-1])
    return sps.csr_matrix((mat[:nnz].copy(), fpos[n + nx + 1:n + nx + 1 + nnz], ptr), shape=(nx, nx))


def missed_entries(system):
    """How many nonzero values the last evaluation of a :func:`newton_system` wrote outside the scene's
    Newton pattern (0 for a complete pattern; always 0 with dense storage)."""
    return int(system[2][1][-1])


# ==================================================================== position maps
# A map k reads the coordinate block q[off[k] : off[k] + nb[k]] of one body. LINEAR: r = G q + c with G
# (2 × nb) stored row-major at gptr[k]. FRAME: r = mR R + A(θ)(y0 + Y q_f), R = q[0:2], θ = q[2],
# q_f = q[3:], Y (2 × (nb − 3)) stored row-major at yptr[k].
# The functions that allocate nothing are compiled with _nrt=False (see skfem_flex.numerics.newton: no reference
# counting of the arrays they unpack from the packed tuples).

@numba.njit(cache=True, _nrt=False)
def _frame_offset(maps, k, qa, qb):
    """(s_x, s_y) = y0 + Y (qa_f + qb_f)/2 of FRAME map k: the point in the body frame at the mean of two
    states (qa = qb: at that state; 0.5 (a + a) = a exactly)."""
    nb, y0, ydat, yptr = maps[2], maps[5], maps[8], maps[9]
    ne = nb[k] - 3
    y = yptr[k]
    sx, sy = y0[k, 0], y0[k, 1]
    for j in range(ne):
        qm = 0.5 * (qa[3 + j] + qb[3 + j])
        sx += ydat[y + j] * qm
        sy += ydat[y + ne + j] * qm
    return sx, sy


@numba.njit(cache=True, _nrt=False)
def _position_into(maps, k, q, out):
    """out[0:2] = r(q) of map k, m; ``q`` is the body's block."""
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    if kind[k] == LINEAR:
        g0 = gptr[k]
        for a in range(2):
            s = c[k, a]
            for j in range(nb[k]):
                s += gdat[g0 + a * nb[k] + j] * q[j]
            out[a] = s
        return
    sx, sy = _frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    out[0] = m_r[k] * q[0] + C * sx - S * sy
    out[1] = m_r[k] * q[1] + S * sx + C * sy


@numba.njit(cache=True, _nrt=False)
def _jacobian_into(maps, k, q, out):
    """out[:, :nb] = ∂r/∂q of map k."""
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    n = nb[k]
    if kind[k] == LINEAR:
        for a in range(2):
            for j in range(n):
                out[a, j] = gdat[gptr[k] + a * n + j]
        return
    ne = n - 3
    y = yptr[k]
    sx, sy = _frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    out[0, 0] = out[1, 1] = m_r[k]
    out[0, 1] = out[1, 0] = 0.0
    out[0, 2] = -S * sx - C * sy            # A E s, E = [[0, −1], [1, 0]]
    out[1, 2] = C * sx - S * sy
    for j in range(ne):
        yx, yy = ydat[y + j], ydat[y + ne + j]
        out[0, 3 + j] = C * yx - S * yy
        out[1, 3 + j] = S * yx + C * yy


@numba.njit(cache=True, _nrt=False)
def _dgrad_into(maps, k, q0, q1, out):
    """out[:, :nb] = the exact discrete gradient D of map k: D (q1 − q0) = r(q1) − r(q0).

    FRAME: D = [mR I, sinc(Δθ/2) A(θ_m) E s_m, cos(Δθ/2) A(θ_m) Y] with s_m = y0 + Y (q0_f + q1_f)/2."""
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    if kind[k] == LINEAR:
        _jacobian_into(maps, k, q0, out)
        return
    n = nb[k]
    ne = n - 3
    y = yptr[k]
    half = 0.5 * (q1[2] - q0[2])
    tm = q0[2] + half
    C, S = np.cos(tm), np.sin(tm)
    sig, kap = sinc_half(q1[2] - q0[2])[0], np.cos(half)
    sx, sy = _frame_offset(maps, k, q0, q1)
    out[0, 0] = out[1, 1] = m_r[k]
    out[0, 1] = out[1, 0] = 0.0
    out[0, 2] = sig * (-S * sx - C * sy)
    out[1, 2] = sig * (C * sx - S * sy)
    for j in range(ne):
        yx, yy = ydat[y + j], ydat[y + ne + j]
        out[0, 3 + j] = kap * (C * yx - S * yy)
        out[1, 3 + j] = kap * (S * yx + C * yy)


@numba.njit(cache=True)
def map_position(maps, k, q):
    """r(q) of map k (2,), m; ``q`` is the body's block."""
    r = np.empty(2)
    _position_into(maps, k, q, r)
    return r


@numba.njit(cache=True)
def map_jacobian(maps, k, q):
    """∂r/∂q of map k (2, nb)."""
    jac = np.empty((2, maps[2][k]))
    _jacobian_into(maps, k, q, jac)
    return jac


@numba.njit(cache=True)
def map_dgrad(maps, k, q0, q1):
    """Exact discrete gradient D (2, nb) of map k: D (q1 − q0) = r(q1) − r(q0) (see :func:`_dgrad_into`)."""
    d = np.empty((2, maps[2][k]))
    _dgrad_into(maps, k, q0, q1, d)
    return d


@numba.njit(cache=True, _nrt=False)
def _dgrad_jacobian_parts(maps, k, q0, q1, f, row, col):
    """The nonzero parts of ∂(Dᵀ f)/∂q1 of a FRAME map: the (θ, θ) entry (returned), the θ row over
    q_f and the q_f rows of the θ column (into ``row``, ``col``; everything else is zero: D depends on
    q1 through θ and q_f only, and its q_f columns only through θ)."""
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    ne = nb[k] - 3
    y = yptr[k]
    half = 0.5 * (q1[2] - q0[2])
    tm = q0[2] + half
    C, S = np.cos(tm), np.sin(tm)
    sig, dsig = sinc_half(q1[2] - q0[2])          # σ and dσ/dΔθ
    kap, sn = np.cos(half), np.sin(half)
    sx, sy = _frame_offset(maps, k, q0, q1)
    fax = f[0] * C + f[1] * S              # fA = Aᵀ(θ_m) f
    fay = -f[0] * S + f[1] * C
    # fA·(E s) and fA·s; E s = (−sy, sx)
    h22 = dsig * (-fax * sy + fay * sx) - 0.5 * sig * (fax * sx + fay * sy)
    for j in range(ne):
        yx, yy = ydat[y + j], ydat[y + ne + j]
        # ½ σ (fA E)·Y_j with fA E = (fay, −fax)
        row[j] = 0.5 * sig * (fay * yx - fax * yy)
        # −½ sin(Δθ/2) Y_jᵀ fA + ½ cos(Δθ/2) Y_jᵀ Eᵀ fA, Eᵀ fA = (fay, −fax)
        col[j] = -0.5 * sn * (yx * fax + yy * fay) + 0.5 * kap * (yx * fay - yy * fax)
    return h22


@numba.njit(cache=True)
def map_dgrad_jacobian(maps, k, q0, q1, f):
    """∂(Dᵀ f)/∂q1 (nb, nb) of :func:`map_dgrad` at a fixed vector f (2,); zero for LINEAR maps."""
    n = maps[2][k]
    h = np.zeros((n, n))
    if maps[0][k] == LINEAR:
        return h
    row, col = np.empty(n), np.empty(n)
    h22 = _dgrad_jacobian_parts(maps, k, q0, q1, f, row, col)
    h[2, 2] = h22
    for j in range(n - 3):
        h[2, 3 + j] = row[j]
        h[3 + j, 2] = col[j]
    return h


@numba.njit(cache=True, _nrt=False)
def _add_hessian_product(maps, k, q, f, scale, mat, fpos):
    """mat[F, F] += scale · ∂(Jᵀ f)/∂q of map k at the body block q (f fixed, (2,)); zero for LINEAR maps.

    FRAME: the (θ, θ) entry −f · A s and the (θ, q_f) entries f · A E Y_j, symmetric."""
    if maps[0][k] == LINEAR:
        return
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    o, ne, y = off[k], nb[k] - 3, yptr[k]
    sx, sy = _frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    fax = f[0] * C + f[1] * S              # Aᵀ f
    fay = -f[0] * S + f[1] * C
    i2 = fpos[o + 2]
    if i2 < 0:
        return
    _madd(mat, fpos, i2, i2, -scale * (fax * sx + fay * sy))
    for j in range(ne):
        ij = fpos[o + 3 + j]
        if ij >= 0:
            val = scale * (fay * ydat[y + j] - fax * ydat[y + ne + j])   # (Aᵀf) · E Y_j
            if val != 0.0:
                _madd(mat, fpos, i2, ij, val)
                _madd(mat, fpos, ij, i2, val)


@numba.njit(cache=True)
def map_hessian_product(maps, k, q, f):
    """∂(Jᵀ f)/∂q (nb, nb) of map k at a fixed vector f (2,), for a map on its own block (offset 0)."""
    n = maps[2][k]
    h = np.zeros(n * n + 1)
    fpos = np.arange(n + 3)
    fpos[n], fpos[n + 1], fpos[n + 2] = n, n, DENSE
    _add_hessian_product(maps, k, q, f, 1.0, h, fpos)
    return h[:n * n].reshape(n, n)


@numba.njit(cache=True, _nrt=False)
def _add_dgrad_jacobian(maps, k, q0, q1, f, scale, mat, fpos, floor, scratch):
    """mat[F, F] += scale · ∂(Dᵀ f)/∂q1 of map k, and, if ``floor`` is not empty, its round-off floor
    |scale ∂(Dᵀf)/∂q1| (|q0| + |q1|) added to floor[o:o + nb] (the body's block; q0, q1 are the block's);
    ``scratch``: (2, ≥ nb) to work in."""
    if maps[0][k] == LINEAR:
        return
    o, n = maps[1][k], maps[2][k]
    row, col = scratch[0], scratch[1]
    h22 = _dgrad_jacobian_parts(maps, k, q0, q1, f, row, col)
    i2 = fpos[o + 2]
    a2 = abs(q0[2]) + abs(q1[2])
    if i2 >= 0:
        _madd(mat, fpos, i2, i2, scale * h22)
    fl2 = abs(scale * h22) * a2
    for j in range(n - 3):
        ij = fpos[o + 3 + j]
        if ij >= 0 and i2 >= 0:
            _madd(mat, fpos, i2, ij, scale * row[j])
            _madd(mat, fpos, ij, i2, scale * col[j])
        if floor.size:
            fl2 += abs(scale * row[j]) * (abs(q0[3 + j]) + abs(q1[3 + j]))
            floor[o + 3 + j] += abs(scale * col[j]) * a2
    if floor.size:
        floor[o + 2] += fl2


# ==================================================================== packing
def _map_of(entry, off, nb, store):
    """Append one map (a ``compiled_map()`` entry) to ``store``; its index."""
    kind = entry[0]
    k = len(store["kind"])
    store["off"].append(off)
    store["nb"].append(nb)
    store["gptr"].append(len(store["g"]))
    store["yptr"].append(len(store["y"]))
    if kind == "linear":
        _, G, c = entry
        G = np.asarray(G, dtype=float).reshape(2, nb)
        store["kind"].append(LINEAR)
        store["m_r"].append(0.0)
        store["c"].append(np.asarray(c, dtype=float).reshape(2))
        store["y0"].append(np.zeros(2))
        store["g"].extend(G.ravel())
    elif kind == "frame":
        _, m_r, y0, Y = entry
        Y = np.asarray(Y, dtype=float).reshape(2, nb - 3)
        store["kind"].append(FRAME)
        store["m_r"].append(float(m_r))
        store["c"].append(np.zeros(2))
        store["y0"].append(np.asarray(y0, dtype=float).reshape(2))
        store["y"].extend(Y.ravel())
    else:
        raise ValueError(f"unknown map kind {kind!r}")
    return k


def _finish_maps(store):
    nm = len(store["kind"])
    return (np.asarray(store["kind"], dtype=np.int64), np.asarray(store["off"], dtype=np.int64),
            np.asarray(store["nb"], dtype=np.int64), np.asarray(store["m_r"], dtype=float),
            np.asarray(store["c"], dtype=float).reshape(nm, 2), np.asarray(store["y0"], dtype=float).reshape(nm, 2),
            np.asarray(store["g"] or [0.0], dtype=float), np.asarray(store["gptr"], dtype=np.int64),
            np.asarray(store["y"] or [0.0], dtype=float), np.asarray(store["yptr"], dtype=np.int64))


def pack_maps(entries):
    """Position maps as the kernels read them, each on its own body block (offset 0).

    Parameters
    ----------
    entries : sequence of (map, nb)
        A ``compiled_map()``-style tuple and the size of the body's coordinate block.

    Returns
    -------
    tuple
        The ``maps`` argument of :func:`map_position` and the other map kernels; map k is entry k.
    """
    store = {k: [] for k in ("kind", "off", "nb", "m_r", "c", "y0", "g", "gptr", "y", "yptr")}
    for entry, nb in entries:
        _map_of(entry, 0, int(nb), store)
    return _finish_maps(store)


def _call(obj, method):
    fn = getattr(obj, method, None)
    return None if fn is None else fn()


_PACKS = weakref.WeakKeyDictionary()


def pack(scene):
    """The scene as flat arrays for the compiled loop, or None if a part has no compiled form.

    Returns
    -------
    tuple or None
        (mass, frames, frame_off, maps, gravity, constraints, bodies) — see the source; built
        once per scene.
    """
    return _packed(scene)[0]


def _packed(scene):
    """(packed scene or None, names of the probes the loop records, the time table's columns), built once
    per scene. A column is ("end" or "mid", function of time, component): evaluated at each step's end
    time (motion laws of drivers: position and velocity) or mid time (loads)."""
    hit = _PACKS.get(scene)
    if hit is None:
        hit = _PACKS[scene] = _pack(scene)
    return hit


def _pack(scene):
    if type(scene) is not Scene:
        return None, (), ()
    n = scene.n
    store = {k: [] for k in ("kind", "off", "nb", "m_r", "c", "y0", "g", "gptr", "y", "yptr")}
    mass_blocks = []
    frames, frame_off = [], []
    momentum = tuple([] for _ in range(7))
    strains, strain_off = [], []
    first_moment = {}
    rng = np.random.default_rng(0)
    for b in scene.bodies:
        sl = scene.slice(b)
        off = sl.start
        kd = _call(b, "compiled_kernel_data")
        if kd is not None:
            moment = _call(b, "mass_moment_map")
            if moment is None:
                return None, (), ()
            frames.append(kd)
            frame_off.append(off)
            first_moment[id(b)] = ("frame", moment[0], moment[1], moment[2])
        elif b.constant_mass and (not b.has_potential or _call(b, "compiled_strain_data") is not None):
            try:
                gam, c = b.mass_moment()
            except NotImplementedError:
                return None, (), ()
            block = sps.coo_matrix(b.mass_matrix(np.asarray(b.q0, dtype=float)))
            mass_blocks.append((block.row + off, block.col + off, block.data))
            first_moment[id(b)] = ("linear", gam, c)
            if b.has_potential:
                strains.append(b.compiled_strain_data())
                strain_off.append(off)
        else:
            return None, (), ()
        layout = _momentum_layout(b, kd, rng)
        if layout is None:
            return None, (), ()
        for store_k, a in zip(momentum, layout):
            store_k.append(a + off if a.dtype == np.int64 else a)
    # force elements; functions of time become columns of the chunk's time table
    table = []
    force_index = {id(f): i for f, i in scene.conservative_forces + scene.loads}
    grav_maps, grav_g = [], []
    e_kind, e_ptr, e_int, e_float = [], [(0, 0)], [], []

    def add_element(kind, ints, floats):
        e_kind.append(kind)
        e_int.extend(int(i) for i in ints)
        e_float.extend(float(x) for x in floats)
        e_ptr.append((len(e_int), len(e_float)))

    def point_map(point):
        cm = _call(point, "compiled_map")
        if cm is None:
            return None
        sl = scene.slice(point.body)
        return _map_of(cm, sl.start, sl.stop - sl.start, store)

    for f in scene.forces:
        form = _call(f, "compiled_form")
        if form is None:
            return None, (), ()
        idx = np.asarray(force_index[id(f)], dtype=np.int64)
        name = form[0]
        if name == "gravity":
            for b in (f.bodies if f.bodies is not None else scene.bodies):
                sl = scene.slice(b)
                grav_maps.append(_map_of(first_moment[id(b)], sl.start, sl.stop - sl.start, store))
                grav_g.append(np.asarray(form[1], dtype=float))
        elif name == "coordinate spring":
            _, i, k, power = form
            add_element(COORD_SPRING, (idx[i], power), (k,))
        elif name in ("point force", "follower force"):
            k = point_map(form[1])
            if k is None:
                return None, (), ()
            if name == "point force":
                add_element(POINT_FORCE, (k, len(table)), ())
            else:
                grad = np.asarray(form[2], dtype=float)
                nz = np.flatnonzero(grad)
                add_element(FOLLOWER_FORCE, [k, len(table)] + list(idx[nz]), [form[3]] + list(grad[nz]))
            table += [("mid", form[-1], 0), ("mid", form[-1], 1)]
        elif name == "generalized force":        # Q = Gᵀ F(t): one table column per row of G
            _, gmat, fun = form
            for comp, grad in enumerate(np.atleast_2d(np.asarray(gmat, dtype=float))):
                nz = np.flatnonzero(grad)
                add_element(GENERALIZED_FORCE, [len(table)] + list(idx[nz]), grad[nz])
                table.append(("mid", fun, comp))
        elif name in ("quadratic spring", "linear damper"):
            grad = np.asarray(form[1], dtype=float)
            nz = np.flatnonzero(grad)
            if name == "quadratic spring":
                add_element(ROW_SPRING, idx[nz], [form[3], form[2]] + list(grad[nz]))
            else:
                add_element(ROW_DAMPER, idx[nz], [form[2]] + list(grad[nz]))
        elif name in ("two-point spring", "two-point damper"):
            ka = point_map(form[1])
            kb = -1 if form[2] is None else point_map(form[2])
            if ka is None or kb is None:
                return None, (), ()
            anchor = np.zeros(2) if form[3] is None else np.asarray(form[3], dtype=float).reshape(2)
            if name == "two-point spring":
                add_element(TWO_POINT_SPRING, (ka, kb), [form[4], form[5]] + list(anchor))
            else:
                add_element(TWO_POINT_DAMPER, (ka, kb), [form[4]] + list(anchor))
        else:
            return None, (), ()
    # constraints: blocks of rows (module docstring)
    con_kind, con_row, con_t0, term_map, term_sign, con_c, con_len = [], [], [], [], [], [], []
    con_l0, lin_idx, lin_coef, con_nrm, con_law = [], [], [], [], []
    probe_names = []

    def add_points(points_form):
        _, terms, const = points_form
        for point, sign in terms:
            cm = _call(point, "compiled_map")
            if cm is None:
                return None
            sl = scene.slice(point.body)
            term_map.append(_map_of(cm, sl.start, sl.stop - sl.start, store))
            term_sign.append(float(sign))
        return np.asarray(const, dtype=float).reshape(2)

    for c, (idx, rows) in zip(scene.constraints, scene.constraint_layout):
        form = _call(c, "compiled_form")
        if form is None:
            return None, (), ()
        blocks = form[1] if form[0] == "rows" else [(form, None)]
        r = int(rows[0])
        for term, law in blocks:
            con_row.append(r)
            con_t0.append(len(term_map))
            con_l0.append(len(lin_idx))
            nrm, const, length, col = np.zeros(2), np.zeros(2), 0.0, -1
            if law is not None and term[0] != "linear":
                return None, (), ()
            if term[0] == "points":
                kind, const = POINTS, add_points(term)
            elif term[0] == "projected":
                kind, nrm, const = PROJECTED, np.asarray(term[1], dtype=float).reshape(2), add_points(term[2])
            elif term[0] == "rotated projected":
                _, grad, length, nrm, points = term
                kind, nrm, const = ROTATED, np.asarray(nrm, dtype=float).reshape(2), add_points(points)
                grad = np.asarray(grad, dtype=float)
                nz = np.flatnonzero(grad)
                lin_idx.extend(np.asarray(idx)[nz])
                lin_coef.extend(grad[nz])
            elif term[0] == "linear":
                kind = LINEAR_ROW
                grad = np.asarray(term[1], dtype=float)
                nz = np.flatnonzero(grad)
                lin_idx.extend(np.asarray(idx)[nz])
                lin_coef.extend(grad[nz])
                const = np.array([float(term[2]), 0.0])
                if law is not None:
                    col = len(table)
                    table += [("end", law.position, 0), ("end", law.velocity, 0)]
            elif term[0] == "distance":
                _, point, anchor, length = term
                cm = _call(point, "compiled_map")
                if cm is None or cm[0] != "linear":
                    return None, (), ()
                sl = scene.slice(point.body)
                kind, const, length = DISTANCE, np.asarray(anchor, dtype=float).reshape(2), float(length)
                term_map.append(_map_of(cm, sl.start, sl.stop - sl.start, store))
                term_sign.append(1.0)
            else:
                return None, (), ()
            if const is None:
                return None, (), ()
            con_kind.append(kind)
            con_c.append(const)
            con_nrm.append(nrm)
            con_len.append(length)
            con_law.append(col)
            r += 2 if kind == POINTS else 1
    con_t0.append(len(term_map))
    con_l0.append(len(lin_idx))
    nc = len(con_kind)
    # probes made of position maps (a PointProbe or LinearProbe: one; a CombinedProbe: several, combined
    # in Python over a whole chunk) are recorded by the loop; the others are called in Python
    probe_maps = []
    for name, fn in scene.probes.items():
        parts = getattr(fn, "parts", None)
        parts, combine = (tuple(parts), fn.combine) if parts is not None else ((fn,), None)
        found = []
        for part in parts:
            cm = _call(part, "compiled_map")
            body = getattr(part, "body", None)
            if cm is None or body is None or not any(body is b for b in scene.bodies):
                break
            sl = scene.slice(body)
            found.append((cm, sl.start, sl.stop - sl.start))
        else:
            probe_names.append((name, len(probe_maps), len(found), combine))
            probe_maps += [_map_of(cm, o, nb, store) for cm, o, nb in found]
    maps = _finish_maps(store)
    gravity = (np.asarray(grav_maps, dtype=np.int64), np.asarray(grav_g, dtype=float).reshape(len(grav_maps), 2))
    constraints = (np.asarray(con_kind, dtype=np.int64), np.asarray(con_row, dtype=np.int64),
                   np.asarray(con_t0, dtype=np.int64), np.asarray(term_map, dtype=np.int64),
                   np.asarray(term_sign, dtype=float), np.asarray(con_c, dtype=float).reshape(nc, 2),
                   np.asarray(con_len, dtype=float), int(scene.n_constraints), float(scene.length_scale),
                   np.asarray(con_l0, dtype=np.int64), np.asarray(lin_idx, dtype=np.int64),
                   np.asarray(lin_coef, dtype=float), np.asarray(con_nrm, dtype=float).reshape(nc, 2),
                   np.asarray(con_law, dtype=np.int64),
                   np.flatnonzero(np.asarray(con_kind) == ROTATED).astype(np.int64) if ROTATED in con_kind else None)
    # None without force elements (beyond gravity), as the ROTATED blocks' list without lines on moving
    # bodies: the functions of these parts begin with a None test Numba prunes, so a scene without them
    # never compiles their code
    loads = (np.asarray(e_kind, dtype=np.int64), np.asarray(e_ptr, dtype=np.int64).reshape(-1, 2),
             np.asarray(e_int, dtype=np.int64), np.asarray(e_float, dtype=float)) if e_kind else None
    # momenta (module docstring of _momentum_layout) and the probes the loop records
    bodies = tuple(np.concatenate(parts) if parts else np.zeros(0) for parts in momentum) + \
        (np.asarray(probe_maps, dtype=np.int64),)
    rows, cols, vals = (np.concatenate([blk[i] for blk in mass_blocks]) if mass_blocks else np.zeros(0)
                        for i in range(3))
    mass = sps.csr_matrix((vals, (rows.astype(np.int64), cols.astype(np.int64))), shape=(n, n))
    mass.sum_duplicates()
    mass.eliminate_zeros()
    mass.sort_indices()
    mass = (mass.indptr.astype(np.int64), mass.indices.astype(np.int64), mass.data.astype(float))
    # where each entry of the bodies' kernel patterns lands in the flattened Newton matrix (−1: a row or
    # column of a prescribed coordinate): one indirect add per entry in the loop
    fpos, nx = _free_positions(scene), scene.free_index.size + scene.n_constraints
    frame_pos = _pattern_positions(frames, frame_off, fpos, nx)
    strain_pos = _pattern_positions(strains, strain_off, fpos, nx)
    strain = (tuple(strains) if strains else None, np.asarray(strain_off, dtype=np.int64),
              np.asarray(scene.cayley_index, dtype=np.int64), frame_pos, strain_pos)
    # no band plan yet, dense storage (_planned decides both, from the Newton pattern)
    dense = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), 0, 0, _matrix_index(fpos, nx), None)
    packed = (mass, tuple(frames) if frames else None, np.asarray(frame_off, dtype=np.int64), maps, gravity,
              constraints, bodies, loads, strain, dense)
    return packed, tuple(probe_names), tuple(table)


_PLANNED = weakref.WeakKeyDictionary()
#: plans by Newton-matrix pattern: a scene built again (a sweep, a benchmark's repeats) finds its plan
#: here instead of searching its border again (1–3 ms for the catalogue's mechanisms)
_PLANS_BY_PATTERN = {}
_MAX_PLANS = 64
#: the Newton matrix is stored as the values of its pattern (CSR) above this many rows when it has a plan
#: as a band with a dense border (the package's one dense/sparse threshold: the dense matrix is zeroed at
#: every evaluation and its solve checked with a dense residual; `python examples/profile_compiled_scene.py
#: --n-elements N --dt 2e-4 --dense-storage-limit L` gives 180 µs per step stored as CSR against 175 dense
#: at 197 rows, 362 against 428 at 389),
#: else stored dense up to COMPILED_SIZE_LIMIT rows; a larger scene without such a plan runs in Python
DENSE_STORAGE_LIMIT = DENSE_LIMIT


def _planned(scene):
    """The packed scene with its Newton matrix's storage (section "the Newton matrix") and plan for the
    solve (a band with a dense border, or dense LU when that is not cheaper), fixed once per scene by the
    matrix's pattern (made on the first run). Above DENSE_STORAGE_LIMIT rows the plan's border holds at
    most MAX_BORDER coordinates, in the natural order or else after reordering
    (:func:`~skfem_flex.numerics.linear_solver.reordered_band_plan`). None if the scene's matrix has more than
    COMPILED_SIZE_LIMIT rows and no such plan (it runs in Python, with SuperLU)."""
    hit = _PLANNED.get(scene)
    if hit is not None:
        return hit[0]
    packed = _packed(scene)[0]
    nx = scene.free_index.size + scene.n_constraints
    plan = None
    if nx >= MIN_DENSE_BORDERED:
        pattern = _newton_pattern(scene, packed)
        key = (pattern.shape, pattern.indptr.tobytes(), pattern.indices.tobytes())
        if key not in _PLANS_BY_PATTERN:
            if len(_PLANS_BY_PATTERN) >= _MAX_PLANS:
                _PLANS_BY_PATTERN.clear()
            _PLANS_BY_PATTERN[key] = dense_bordered_plan(pattern, max_border=MAX_BORDER if nx > DENSE_STORAGE_LIMIT
                                                          else None)
        plan = _PLANS_BY_PATTERN[key]
    fpos = _free_positions(scene)
    if nx > DENSE_STORAGE_LIMIT and plan is None:
        # no band with a small border in the natural order (a long chain's multipliers): reorder
        plan = reordered_band_plan(pattern)
    if nx <= DENSE_STORAGE_LIMIT or (plan is None and nx <= COMPILED_SIZE_LIMIT):
        empty = np.zeros(0, dtype=np.int64)
        packed = packed[:9] + ((plan if plan is not None else (empty, empty, 0, 0)) + (_matrix_index(fpos, nx), None),)
    elif plan is None:
        packed = None
    else:
        # the kernels' flat positions i·nx + j become positions among the pattern's stored entries
        keys = np.repeat(np.arange(nx, dtype=np.int64), np.diff(pattern.indptr)) * nx + pattern.indices
        strain = packed[8]
        moved = []
        for pos, ptr in (strain[3], strain[4]):
            slot = np.searchsorted(keys, pos)
            inside = (pos >= 0) & (slot < keys.size)
            inside[inside] = keys[slot[inside]] == pos[inside]
            if not np.array_equal(inside, pos >= 0):
                raise AssertionError("a kernel entry outside the scene's Newton pattern")
            moved.append((np.where(pos >= 0, slot, -1).astype(np.int64), ptr))
        index = _matrix_index(fpos, nx, pattern)
        n = fpos.size
        csr = (index[n:n + nx + 1], index[n + nx + 1:n + nx + 1 + pattern.nnz])      # views into the index
        packed = packed[:8] + (strain[:3] + tuple(moved), plan + (index, csr))
    _PLANNED[scene] = (packed,)
    return packed


def _pattern_positions(kernels, offsets, fpos, nx):
    """(positions, pointers): entry t of kernel i's CSR pattern goes to flat index positions[ptr[i] + t]
    of the (nx × nx) Newton matrix, or nowhere (−1)."""
    parts, ptr = [], [0]
    for kd, o in zip(kernels, offsets):
        rows = fpos[o + np.repeat(np.arange(kd.n), np.diff(kd.pat_ptr))]
        cols = fpos[o + np.asarray(kd.pat_idx)]
        parts.append(np.where((rows >= 0) & (cols >= 0), rows * nx + cols, -1))
        ptr.append(ptr[-1] + rows.size)
    return (np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, dtype=np.int64),
            np.asarray(ptr, dtype=np.int64))


def _map_support(maps, k):
    """The scene coordinates on which map k's position can depend: the columns of G that are not zero
    (LINEAR), or R, θ and the columns of Y that are not zero (FRAME)."""
    kind, off, nb, _, _, _, gdat, gptr, ydat, yptr = maps
    o, n = off[k], nb[k]
    if kind[k] == LINEAR:
        cols = np.flatnonzero(gdat[gptr[k]:gptr[k] + 2 * n].reshape(2, n).any(axis=0))
    else:
        y = ydat[yptr[k]:yptr[k] + 2 * (n - 3)].reshape(2, n - 3)
        cols = np.concatenate([[0, 1, 2], 3 + np.flatnonzero(y.any(axis=0))])
    return o + cols.astype(np.int64)


def _element_coordinates(maps, loads):
    """For each force element that couples coordinates in the Newton matrix, the coordinates it couples:
    the supports of its points' maps and the coordinates of its rows g."""
    if loads is None:
        return []
    kind, ptr, ints, _ = loads
    out = []
    for e in range(kind.size):
        own = ints[ptr[e, 0]:ptr[e + 1, 0]]
        if kind[e] in (ROW_SPRING, ROW_DAMPER):
            out.append(own)
        elif kind[e] == FOLLOWER_FORCE:
            out.append(np.concatenate([_map_support(maps, own[0]), own[2:]]))
        elif kind[e] in (TWO_POINT_SPRING, TWO_POINT_DAMPER):
            out.append(np.concatenate([_map_support(maps, k) for k in own[:2] if k >= 0]))
    return out


def _constraint_coordinates(maps, constraints):
    """For each constraint block whose ∂(Φ_qᵀ μ)/∂q couples coordinates beyond a floating frame's rows
    (which its kernel pattern holds), the coordinates it couples: a line on a moving body (ROTATED) the
    supports of its points' maps and the guiding angle's coordinates, a DISTANCE block its map's support."""
    kind, t0, term_map, l0, lin_idx = constraints[0], constraints[2], constraints[3], constraints[9], constraints[10]
    out = []
    for i in range(kind.size):
        if kind[i] == ROTATED:
            out.append(np.concatenate([_map_support(maps, k) for k in term_map[t0[i]:t0[i + 1]]]
                                      + [lin_idx[l0[i]:l0[i + 1]]]))
        elif kind[i] == DISTANCE:
            out.append(_map_support(maps, term_map[t0[i]]))
    return out


def _newton_pattern(scene, packed):
    """Where the bordered Newton matrix (free coordinates, then multipliers) can be nonzero, from the
    structure of the packed scene, as a scipy CSR matrix with sorted indices: the constant masses, the
    floating-frame and exact beams' kernel patterns (a floating body's frame rows and columns hold every
    tangent of its points, loads and gravity), the diagonal (springs, Cayley terms), the blocks of the
    force elements and constraint blocks that couple coordinates, and each constraint's rows and columns
    over all coordinates of its bodies. With dense storage an entry missed here could not give a wrong
    step (the bordered band solve checks its backward error, the dense solve takes over); with CSR
    storage the step counts it (:func:`missed_entries`) and goes to Python."""
    mass, frames, frame_off = packed[0], packed[1], packed[2]
    strains, strain_off = packed[8][0], packed[8][1]
    n, m = scene.n, scene.n_constraints
    rows, cols = [np.arange(n)], [np.arange(n)]   # no diagonal on the multipliers' rows: border coordinates
    ptr, idx, _ = mass
    rows.append(np.repeat(np.arange(n), np.diff(ptr)))
    cols.append(idx)
    for group, offsets in ((frames, frame_off), (strains, strain_off)):
        for kd, o in zip(group or (), offsets):
            rows.append(o + np.repeat(np.arange(kd.n), np.diff(kd.pat_ptr)))
            cols.append(o + np.asarray(kd.pat_idx))
    for coords in _element_coordinates(packed[3], packed[7]) + _constraint_coordinates(packed[3], packed[5]):
        rows.append(np.repeat(coords, coords.size))
        cols.append(np.tile(coords, coords.size))
    for idx_c, rows_c in scene.constraint_layout:
        r = n + np.repeat(np.asarray(rows_c), len(idx_c))
        c = np.tile(np.asarray(idx_c), len(rows_c))
        rows += [r, c]
        cols += [c, r]
    rows, cols = np.concatenate(rows).astype(np.int64), np.concatenate(cols).astype(np.int64)
    pat = sps.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(n + m, n + m))
    sel = np.concatenate([scene.free_index, n + np.arange(m)])
    pat = pat[sel][:, sel].tocsr()
    pat.sum_duplicates()
    pat.sort_indices()
    pat.data[:] = 1
    return pat


def _momentum_layout(body, kd, rng):
    """(l_x, l_y, i_x, i_y, X, Y, i_angle) of the body's block: linear momentum (Σ p[l_x], Σ p[l_y]) and
    L = Σ (X + q[i_x]) p[i_y] − (Y + q[i_y]) p[i_x] + Σ p[i_angle], p = M v. From the body's
    ``momentum_layout()`` (i_x, i_y, X, Y, i_angle; l = i), or by default R = q[0:2] and θ = q[2] where
    present (point masses, rigid and floating-frame bodies; a one-coordinate body: p[0] along x).
    None if that does not give the body's own momenta (checked at two states): the scene then runs
    in Python."""
    nb = body.n_dofs
    none, zero = np.zeros(0, dtype=np.int64), np.zeros(1)
    layout = _call(body, "momentum_layout")
    if layout is not None:
        ix, iy, X, Y, ia = (np.asarray(a) for a in layout)
        lx, ly = ix, iy
    elif nb == 1:
        lx, ly, ix, iy, X, Y, ia = np.array([0]), none, none, none, np.zeros(0), np.zeros(0), none
    else:
        ix, iy = np.array([0]), np.array([1])
        lx, ly, X, Y, ia = ix, iy, zero, zero, (np.array([2]) if nb >= 3 else none)
    for _ in range(2):
        q = np.asarray(body.q0, dtype=float) + 0.1 * rng.standard_normal(nb)
        v = rng.standard_normal(nb)
        p = body.momentum(q, v) if kd is not None else np.asarray(body.mass_matrix(q) @ v).ravel()
        lin = np.array([p[lx].sum(), p[ly].sum()])
        ang = ((X + q[ix]) * p[iy]).sum() - ((Y + q[iy]) * p[ix]).sum() + p[ia].sum()
        try:
            ref_lin, ref_ang = body.linear_momentum(q, v), body.angular_momentum(q, v)
        except NotImplementedError:
            return None
        if ref_lin is None or ref_ang is None:
            return None
        ref = np.zeros(2)
        ref[:np.size(ref_lin)] = np.ravel(ref_lin)[:2]
        scale = max(np.abs(p).max(), 1.0) * max(np.abs(q).max() + np.abs(np.concatenate([X, Y, zero])).max(), 1.0)
        if np.abs(ref - lin).max() > 1e-12 * scale or abs(float(ref_ang) - ang) > 1e-12 * scale:
            return None
    return tuple(np.asarray(a, dtype=np.int64) for a in (lx, ly, ix, iy)) + (np.asarray(X, float), np.asarray(Y, float),
                                                                             np.asarray(ia, dtype=np.int64))


#: the Newmark-family schemes the compiled Newmark step stands for (the classes themselves, not subclasses)
NEWMARK_SCHEMES = (Newmark, Trapezoidal, GeneralizedAlpha)


def eligible(scene, scheme):
    """True if ``simulate`` may run ``scene`` with ``scheme`` through this loop: the
    :class:`~skfem_flex.schemes.integrators.EnergyMomentum` class itself or one of :data:`NEWMARK_SCHEMES`, on a
    plain scene whose bodies, force elements, constraints and joint points all have compiled forms
    (module docstring) and whose Newton matrix is stored dense (at most :data:`DENSE_STORAGE_LIMIT` rows)
    or, larger, has a plan as a band with a dense border (every beam scene)."""
    if type(scheme) is not EnergyMomentum and type(scheme) not in NEWMARK_SCHEMES:
        return False
    return _compiles(scene)


def _compiles(scene):
    return pack(scene) is not None and _planned(scene) is not None


def chunk_steps(scene):
    """Steps per compiled call (about 0.1 s of work per call)."""
    return int(min(2000, max(50, 400_000 // max(scene.n, 1) ** 2)))


# ==================================================================== the step
@numba.njit(cache=True)
def _csr_matvec(mass, v):
    ptr, idx, dat = mass
    out = np.zeros(v.size)
    for i in range(v.size):
        s = 0.0
        for t in range(ptr[i], ptr[i + 1]):
            s += dat[t] * v[idx[t]]
        out[i] = s
    return out


@numba.njit(cache=True)
def _scene_momentum(mass, frames, frame_off, q, v):
    p = _csr_matvec(mass, v)
    if frames is None:
        return p
    for i in range(len(frames)):
        kd = frames[i]
        o = frame_off[i]
        p[o:o + kd.n] += momentum(kd, q[o:o + kd.n], v[o:o + kd.n])
    return p


#: rows of the workspace's (n,) vectors ``ws[2]``
_DQ_BASE, _DQ, _Q1, _V1, _P1, _R, _EXT, _GK, _GP, _FLOOR, _DTMU, _Z, _RATIO, _DRATIO, _DZ, _QM, _VM = range(17)


@numba.njit(cache=True)
def _workspace(n, m, nx, nmat, nbmax):
    """The arrays one step works in, allocated once per chunk (per step only the Newton core's state and
    a few small kernel outputs are allocated), as few arrays as possible (each array of a tuple costs
    compile time wherever the tuple goes): the Newton residual and matrix (``nmat`` values, section "the
    Newton matrix"); the (n,) vectors Δq_base,
    Δq, q1, v1, p1, r, Q, g_kin, g_V, floor, Dᵀμ, z (Δq with the Cayley parameter 2 tan(Δψ/2) on
    Cayley coordinates), Δψ/w, d(Δψ/w)/dΔψ, dz/dΔq, the mid-point q0 + Δq/2 and z/Δt (rows of ``ws[2]``,
    names ``_DQ`` …); Φ, Φ_t, μ and the span [lo, hi) of the coordinates each row of Φ_q and D can touch
    (rows of ``ws[3]``, the span set by :func:`_set_constraint_spans`); Φ_q, D; three 2-vectors; six
    (2, 2 nb) map blocks
    (two-point elements span two bodies); and a flag set when an evaluation met a state the Python step
    refuses (a folded element, a turn ≥ MAX_INCREMENT) or wrote an entry outside a CSR-stored Newton
    pattern."""
    wn = np.zeros((17, n))
    wn[_RATIO, :] = 1.0
    wn[_DZ, :] = 1.0
    return (np.zeros(nx), np.zeros(nmat), wn, np.zeros((5, m)), np.zeros((m, n)), np.zeros((m, n)),
            np.zeros((3, 2)), np.zeros((6, 2, 2 * nbmax)), np.zeros(1, dtype=np.int64))


@numba.njit(cache=True, _nrt=False)
def _rotated_row(maps, constraints, i, q0, q1, v1, mu, scale, cq, d, cv, mat, fpos, ws):
    """Block i of kind ROTATED, a line on a moving body: Φ = n(ϑ) · e with n = A(ϑ) n_loc, ϑ = g · q + c the
    angle of the guiding body's point and e = Σ s r − c_e (:class:`~skfem_flex.elements.point_terms.Dot` of a
    :class:`~skfem_flex.elements.point_terms.Rotated` normal and a point difference). Returns Φ(q1); adds Φ_q(q1)
    to row r of ``cq``; if ``d`` has rows, the exact discrete gradient ē · D_n + n̄ · D_e (D_n =
    sinc(Δϑ/2) E A(ϑ_m) n_loc ⊗ g) to row r of ``d``; if ``cv`` has rows, ∂(Φ_q v1)/∂q1 to its row r; and
    scale · μ · ∂Dᵀ/∂q1 to ``mat``. At q0 = q1, D = Φ_q and ∂D/∂q1 is half the Hessian: the Newmark step
    calls this with scale = 2."""
    kind, row, t0, term_map, term_sign, const, length, m, _, l0, lin_idx, lin_coef, nrm, law, _ = constraints
    r0 = row[i]
    f, rv = ws[6][0], ws[6][2]
    jac, dk, scratch, vj = ws[7][0], ws[7][1], ws[7][2], ws[7][3]
    nb_, off_ = maps[2], maps[1]
    no_floor = ws[0][:0]
    th0, th1, gv = length[i], length[i], 0.0
    for t in range(l0[i], l0[i + 1]):
        th0 += lin_coef[t] * q0[lin_idx[t]]
        th1 += lin_coef[t] * q1[lin_idx[t]]
        gv += lin_coef[t] * v1[lin_idx[t]]
    e0x, e0y, e1x, e1y = -const[i, 0], -const[i, 1], -const[i, 0], -const[i, 1]
    for t in range(t0[i], t0[i + 1]):
        k, s = term_map[t], term_sign[t]
        o, nb = off_[k], nb_[k]
        _position_into(maps, k, q0[o:o + nb], rv)
        e0x += s * rv[0]
        e0y += s * rv[1]
        _position_into(maps, k, q1[o:o + nb], rv)
        e1x += s * rv[0]
        e1y += s * rv[1]
    lx, ly = nrm[i, 0], nrm[i, 1]
    n0x, n0y = np.cos(th0) * lx - np.sin(th0) * ly, np.sin(th0) * lx + np.cos(th0) * ly
    n1x, n1y = np.cos(th1) * lx - np.sin(th1) * ly, np.sin(th1) * lx + np.cos(th1) * ly
    tm = 0.5 * (th0 + th1)
    amx, amy = np.cos(tm) * lx - np.sin(tm) * ly, np.sin(tm) * lx + np.cos(tm) * ly    # A(ϑ_m) n_loc
    sig, dsig = sinc_half(th1 - th0)
    ebx, eby = 0.5 * (e0x + e1x), 0.5 * (e0y + e1y)
    nbx, nby = 0.5 * (n0x + n1x), 0.5 * (n0y + n1y)
    mus = scale * mu
    use_d, use_cv = d.shape[0] > 0, cv.shape[0] > 0
    ang_cq = -e1x * n1y + e1y * n1x                     # e1 · E n1
    ang_d = sig * (-ebx * amy + eby * amx)              # σ ē · E a_m
    # the rotation's own term of ∂(μ Dᵀ)/∂q1: μ (dσ/dΔϑ ē · E a_m − ½ σ ē · a_m) g ⊗ g
    cgg = mus * (dsig * (-ebx * amy + eby * amx) - 0.5 * sig * (ebx * amx + eby * amy))
    for a in range(l0[i], l0[i + 1]):
        ia = lin_idx[a]
        cq[r0, ia] += ang_cq * lin_coef[a]
        if use_d:
            d[r0, ia] += ang_d * lin_coef[a]
        if fpos[ia] >= 0:
            for b in range(l0[i], l0[i + 1]):
                if fpos[lin_idx[b]] >= 0:
                    _madd(mat, fpos, fpos[ia], fpos[lin_idx[b]], cgg * lin_coef[a] * lin_coef[b])
    jevx, jevy = 0.0, 0.0
    for t in range(t0[i], t0[i + 1]):
        k, s = term_map[t], term_sign[t]
        o, nb = off_[k], nb_[k]
        qb0, qb1 = q0[o:o + nb], q1[o:o + nb]
        _jacobian_into(maps, k, qb1, jac)
        _dgrad_into(maps, k, qb0, qb1, dk)
        if use_cv:
            _velocity_jacobian_into(maps, k, qb1, v1[o:o + nb], vj)
        for j in range(nb):
            cq[r0, o + j] += s * (n1x * jac[0, j] + n1y * jac[1, j])
            if use_d:
                d[r0, o + j] += s * (nbx * dk[0, j] + nby * dk[1, j])
            if use_cv:
                cv[r0, o + j] += s * (n1x * vj[0, j] + n1y * vj[1, j]) + gv * s * (-n1y * jac[0, j] + n1x * jac[1, j])
                jevx += s * jac[0, j] * v1[o + j]
                jevy += s * jac[1, j] * v1[o + j]
        f[0], f[1] = s * mus * nbx, s * mus * nby       # μ n̄ · ∂D_e/∂q1
        _add_dgrad_jacobian(maps, k, qb0, qb1, f, 1.0, mat, fpos, no_floor, scratch)
        # ½ μ (D_nᵀ J_e1 + D_eᵀ J_n1), J_n1 = E n1 ⊗ g
        for j in range(nb):
            jb = fpos[o + j]
            dn_je = 0.5 * mus * sig * s * (-amy * jac[0, j] + amx * jac[1, j])
            de_jn = 0.5 * mus * s * (-n1y * dk[0, j] + n1x * dk[1, j])
            for a in range(l0[i], l0[i + 1]):
                ia = fpos[lin_idx[a]]
                if ia >= 0 and jb >= 0:
                    _madd(mat, fpos, ia, jb, dn_je * lin_coef[a])
                    _madd(mat, fpos, jb, ia, de_jn * lin_coef[a])
    if use_cv:                                          # (J_e v)·E n1 g − (g·v)(e1·n1) g
        c_g = -jevx * n1y + jevy * n1x - gv * (e1x * n1x + e1y * n1y)
        for a in range(l0[i], l0[i + 1]):
            cv[r0, lin_idx[a]] += c_g * lin_coef[a]
    return n1x * e1x + n1y * e1y


@numba.njit(cache=True, _nrt=False)
def _add_rotated_rows(maps, constraints, lines, q0, q1, v1, mu, scale, cq, d, cv, mat, fpos, ws):
    """The blocks of kind ROTATED (:func:`_rotated_row`; ``lines``, their indices, is None in scenes without
    them, and Numba prunes this function's body there)."""
    if lines is None:
        return
    phi = ws[3][0]
    for i in lines:
        r0 = constraints[1][i]
        phi[r0] = _rotated_row(maps, constraints, i, q0, q1, v1, mu[r0], scale, cq, d, cv, mat, fpos, ws)


@numba.njit(cache=True, _nrt=False, inline="always")
def _block_span(maps, constraints, i):
    """[lo, hi): the coordinates constraint block i's rows of Φ_q, D and ∂(Φ_q v)/∂q can touch: its maps'
    body blocks and its linear rows' indices (a block's rows touch only these, so the loops over them
    cost what the constraints hold, not rows × coordinates)."""
    t0, term_map, l0, lin_idx = constraints[2], constraints[3], constraints[9], constraints[10]
    off, nb = maps[1], maps[2]
    lo, hi = np.int64(-1), np.int64(-1)
    for t in range(t0[i], t0[i + 1]):
        k = term_map[t]
        if lo < 0 or off[k] < lo:
            lo = off[k]
        hi = max(hi, off[k] + nb[k])
    for t in range(l0[i], l0[i + 1]):
        if lo < 0 or lin_idx[t] < lo:
            lo = lin_idx[t]
        hi = max(hi, lin_idx[t] + 1)
    if lo < 0:
        return np.int64(0), np.int64(0)
    return lo, hi


@numba.njit(cache=True, _nrt=False)
def _set_constraint_spans(maps, constraints, span):
    """Each constraint row's span [lo, hi) into rows 3 and 4 of ``span`` (``ws[3]``): fixed by the scene's
    structure, set once when a chunk's workspace is made."""
    kind, row = constraints[0], constraints[1]
    for i in range(kind.size):
        lo, hi = _block_span(maps, constraints, i)
        for r in range(row[i], row[i] + (2 if kind[i] == POINTS else 1)):
            span[3, r] = lo
            span[4, r] = hi


@numba.njit(cache=True, _nrt=False, inline="always")
def _clear_constraint_rows(ws, a, b):
    """Zero Φ, Φ_t and the rows of ``a`` and ``b`` (m × n: Φ_q and D or ∂(Φ_q v)/∂q) over their spans, all
    an evaluation writes of them."""
    span = ws[3]
    for i in range(span.shape[1]):
        span[0, i] = 0.0
        span[1, i] = 0.0
        for j in range(int(span[3, i]), int(span[4, i])):
            a[i, j] = 0.0
            b[i, j] = 0.0


@numba.njit(cache=True, _nrt=False)
def _constraint_terms(maps, constraints, q0, q1, mu, trow, n, mat, fpos, ws):
    """Φ(q1, t1), Φ_t, Φ_q(q1) and D into the workspace, ∂(Dᵀμ)/∂q1 added to ``mat`` (the
    Newton matrix). ``trow`` is the step's row of the time table (drivers' x(t1), ẋ(t1))."""
    kind, row, t0, term_map, term_sign, const, length, m, _, l0, lin_idx, lin_coef, nrm, law, _ = constraints
    phi, phi_t, cq, d = ws[3][0], ws[3][1], ws[4], ws[5]
    f, acc, rv, jac, dk = ws[6][0], ws[6][1], ws[6][2], ws[7][0], ws[7][1]
    nb_, off_ = maps[2], maps[1]
    _clear_constraint_rows(ws, cq, d)
    no_floor = ws[0][:0]
    for i in range(kind.size):
        r0 = row[i]
        if kind[i] == POINTS or kind[i] == PROJECTED:
            proj = kind[i] == PROJECTED
            acc[0], acc[1] = -const[i, 0], -const[i, 1]
            for t in range(t0[i], t0[i + 1]):
                k, s = term_map[t], term_sign[t]
                o, nb = off_[k], nb_[k]
                qb0, qb1 = q0[o:o + nb], q1[o:o + nb]
                _position_into(maps, k, qb1, rv)
                _jacobian_into(maps, k, qb1, jac)
                _dgrad_into(maps, k, qb0, qb1, dk)
                acc[0] += s * rv[0]
                acc[1] += s * rv[1]
                if proj:                    # one row: nrm · (Σ s r − c)
                    for j in range(nb):
                        cq[r0, o + j] += s * (nrm[i, 0] * jac[0, j] + nrm[i, 1] * jac[1, j])
                        d[r0, o + j] += s * (nrm[i, 0] * dk[0, j] + nrm[i, 1] * dk[1, j])
                    f[0], f[1] = s * nrm[i, 0] * mu[r0], s * nrm[i, 1] * mu[r0]
                else:
                    for a in range(2):
                        f[a] = s * mu[r0 + a]
                        for j in range(nb):
                            cq[r0 + a, o + j] += s * jac[a, j]
                            d[r0 + a, o + j] += s * dk[a, j]
                _add_dgrad_jacobian(maps, k, qb0, qb1, f, 1.0, mat, fpos, no_floor, ws[7][2])
            if proj:
                phi[r0] = nrm[i, 0] * acc[0] + nrm[i, 1] * acc[1]
            else:
                phi[r0], phi[r0 + 1] = acc[0], acc[1]
        elif kind[i] == ROTATED:                  # after the loop (_add_rotated_rows)
            continue
        elif kind[i] == LINEAR_ROW:               # g · q + c − x(t1): D = Φ_q = g
            val = const[i, 0]
            for t in range(l0[i], l0[i + 1]):
                val += lin_coef[t] * q1[lin_idx[t]]
                cq[r0, lin_idx[t]] += lin_coef[t]
                d[r0, lin_idx[t]] += lin_coef[t]
            if law[i] >= 0:
                val -= trow[law[i]]
                phi_t[r0] = -trow[law[i] + 1]
            phi[r0] = val
        else:                                   # DISTANCE on a linear map: Φ = ½(|r − a|² − l²)
            k = term_map[t0[i]]
            o, nb = off_[k], nb_[k]
            qb1 = q1[o:o + nb]
            _position_into(maps, k, qb1, rv)
            _jacobian_into(maps, k, qb1, jac)
            dx, dy = rv[0] - const[i, 0], rv[1] - const[i, 1]
            phi[r0] = 0.5 * (dx * dx + dy * dy - length[i] * length[i])
            for j in range(nb):
                cq[r0, o + j] = dx * jac[0, j] + dy * jac[1, j]
            _position_into(maps, k, q0[o:o + nb], acc)
            mx = 0.5 * (acc[0] + rv[0]) - const[i, 0]
            my = 0.5 * (acc[1] + rv[1]) - const[i, 1]
            for j in range(nb):
                d[r0, o + j] = mx * jac[0, j] + my * jac[1, j]
            for a in range(nb):                 # ∂(μ Jᵀ(r̄ − a))/∂q1 = ½ μ JᵀJ (J constant)
                ia = fpos[o + a]
                if ia < 0:
                    continue
                for j in range(nb):
                    jb = fpos[o + j]
                    if jb >= 0:
                        _madd(mat, fpos, ia, jb, 0.5 * mu[r0] * (jac[0, a] * jac[0, j] + jac[1, a] * jac[1, j]))
    _add_rotated_rows(maps, constraints, constraints[14], q0, q1, q1, mu, 1.0, cq, d, cq[:0], mat, fpos, ws)


# ==================================================================== force elements
# The packed ``loads`` = (kind, ptr, ints, floats): element e's integers are ints[ptr[e, 0]:ptr[e + 1, 0]],
# its floats floats[ptr[e, 1]:ptr[e + 1, 1]] (the layout of each kind at the constants above). One array
# set for all kinds: a new kind adds a branch, not arrays that every function unpacking the scene pays
# for in compile time and reference counting.
@numba.njit(cache=True, _nrt=False)
def _pair_distance(maps, ints, fl, i0, f0, q, rv):
    """d = r_a − r_b (b: map ints[i0 + 1] or, if −1, the ground point fl[f0:f0 + 2]) at q, m."""
    ka, kb = ints[i0], ints[i0 + 1]
    o = maps[1][ka]
    _position_into(maps, ka, q[o:o + maps[2][ka]], rv)
    dx, dy = rv[0], rv[1]
    if kb < 0:
        return dx - fl[f0], dy - fl[f0 + 1]
    o = maps[1][kb]
    _position_into(maps, kb, q[o:o + maps[2][kb]], rv)
    return dx - rv[0], dy - rv[1]

@numba.njit(cache=True, _nrt=False)
def _pair_matrix(maps, ints, i0, q0, q1, v, which, block, out):
    """out[:, :slots] = ∂d/∂q (``which`` 0, at q1), the exact discrete gradient of d (1, from q0 to q1) or
    ∂(J_d v)/∂q (2, at q1) of a two-point element over its slots (map a's block, then map b's); returns
    the number of slots. ``block``: (2, ≥ nb) to work in."""
    ns = 0
    for side in range(2):
        k = ints[i0 + side]
        if k < 0:
            break
        o, nb = maps[1][k], maps[2][k]
        if which == 0:
            _jacobian_into(maps, k, q1[o:o + nb], block)
        elif which == 1:
            _dgrad_into(maps, k, q0[o:o + nb], q1[o:o + nb], block)
        else:
            _velocity_jacobian_into(maps, k, q1[o:o + nb], v[o:o + nb], block)
        sign = 1.0 if side == 0 else -1.0
        for a in range(2):
            for j in range(nb):
                out[a, ns + j] = sign * block[a, j]
        ns += nb
    return ns


@numba.njit(cache=True, _nrt=False)
def _slot(maps, ints, i0, s):
    """The scene coordinate of slot s of a two-point element."""
    ka = ints[i0]
    if s < maps[2][ka]:
        return maps[1][ka] + s
    return maps[1][ints[i0 + 1]] + s - maps[2][ka]


@numba.njit(cache=True, _nrt=False)
def _add_conservative(maps, gravity, loads, q0, q1, th, gp, floor, mat, fpos, ws):
    """The exact discrete gradients of gravity and the conservative force elements from q0 to q1 into
    ``gp``, th ∂/∂q1 of them into ``mat`` and, if ``floor`` is not empty, their round-off floor
    |th ∂g/∂q1| (|q0| + |q1|). At q0 = q1 the discrete gradient is ∇V and its ∂/∂q1 half the Hessian
    (the discrete gradients are symmetric in q0, q1): the Newmark step calls this with th = 2h."""
    f = ws[6][0]
    dk, scratch = ws[7][1], ws[7][2]
    gmaps, gvec = gravity
    for i in range(gmaps.size):          # V = −g · ∫ r dm
        k = gmaps[i]
        o, nb = maps[1][k], maps[2][k]
        if maps[0][k] == LINEAR:          # constant gradient −gᵀΓ, no tangent, no floor
            for j in range(nb):
                gp[o + j] -= gvec[i, 0] * maps[6][maps[7][k] + j] + gvec[i, 1] * maps[6][maps[7][k] + nb + j]
            continue
        qb0, qb1 = q0[o:o + nb], q1[o:o + nb]
        _dgrad_into(maps, k, qb0, qb1, dk)
        f[0], f[1] = -gvec[i, 0], -gvec[i, 1]
        for j in range(nb):
            gp[o + j] += f[0] * dk[0, j] + f[1] * dk[1, j]
        _add_dgrad_jacobian(maps, k, qb0, qb1, f, th, mat, fpos, floor, scratch)
    _add_spring_elements(maps, loads, q0, q1, th, gp, floor, mat, fpos, ws)


@numba.njit(cache=True, _nrt=False)
def _add_spring_elements(maps, loads, q0, q1, th, gp, floor, mat, fpos, ws):
    """The conservative force elements' part of :func:`_add_conservative` (``loads`` None: pruned)."""
    if loads is None:
        return
    kind, ptr, ints, fl = loads
    f, rv = ws[6][0], ws[6][2]
    jac, scratch, jd, dd = ws[7][0], ws[7][2], ws[7][3], ws[7][4]
    use_floor = floor.size > 0
    for e in range(kind.size):
        i0, f0, i1 = ptr[e, 0], ptr[e, 1], ptr[e + 1, 0]
        if kind[e] == COORD_SPRING:       # V = ½ k u^p: its exact divided difference (no cancellation)
            i, p, k = ints[i0], ints[i0 + 1], fl[f0]
            u0, u1 = q0[i], q1[i]
            g, tan = 0.0, 0.0
            for a in range(p):
                g += u1 ** a * u0 ** (p - 1 - a)
                if a >= 1:
                    tan += a * u1 ** (a - 1) * u0 ** (p - 1 - a)
            gp[i] += 0.5 * k * g
            tan *= 0.5 * k * th
            if fpos[i] >= 0:
                _madd(mat, fpos, fpos[i], fpos[i], tan)
            if use_floor:
                floor[i] += abs(tan) * (abs(u0) + abs(u1))
        elif kind[e] == ROW_SPRING:       # V = ½ k (g·q + c)²: the mid-point gradient is exact
            k, s = fl[f0], fl[f0 + 1]
            for t in range(i0, i1):
                s += fl[f0 + 2 + t - i0] * 0.5 * (q0[ints[t]] + q1[ints[t]])
            for a in range(i0, i1):
                ia, ga = ints[a], fl[f0 + 2 + a - i0]
                gp[ia] += k * s * ga
                for b in range(i0, i1):
                    jb = ints[b]
                    tan = 0.5 * th * k * ga * fl[f0 + 2 + b - i0]
                    if use_floor:
                        floor[ia] += abs(tan) * (abs(q0[jb]) + abs(q1[jb]))
                    if fpos[ia] >= 0 and fpos[jb] >= 0:
                        _madd(mat, fpos, fpos[ia], fpos[jb], tan)
        elif kind[e] == TWO_POINT_SPRING:
            # V(s) = ½ k (√s − l₀)², s = d·d: divided difference κ = ½ k (1 − 2 l₀/(l_0 + l_1)) times the exact
            # discrete gradient (d0 + d1)ᵀ D of s; ∂/∂q1 = κ (2 ∂(Dᵀ d̄)/∂q1 + Dᵀ J1) + (k l₀/(2 l1 Σl²)) ds ⊗ ∇s1
            k, lr = fl[f0], fl[f0 + 1]
            d0x, d0y = _pair_distance(maps, ints, fl, i0, f0 + 2, q0, rv)
            d1x, d1y = _pair_distance(maps, ints, fl, i0, f0 + 2, q1, rv)
            l0, l1 = np.hypot(d0x, d0y), np.hypot(d1x, d1y)
            kap = 0.5 * k * (1.0 - 2.0 * lr / (l0 + l1)) if lr > 0.0 else 0.5 * k
            c2 = k * lr / (2.0 * l1 * (l0 + l1) ** 2) if lr > 0.0 else 0.0
            sx, sy = d0x + d1x, d0y + d1y
            ns = _pair_matrix(maps, ints, i0, q0, q1, q1, 1, jac, dd)
            _pair_matrix(maps, ints, i0, q0, q1, q1, 0, jac, jd)
            for a in range(ns):
                ia = _slot(maps, ints, i0, a)
                dsa = sx * dd[0, a] + sy * dd[1, a]
                gp[ia] += kap * dsa
                for b in range(ns):
                    jb = _slot(maps, ints, i0, b)
                    tan = th * (kap * (dd[0, a] * jd[0, b] + dd[1, a] * jd[1, b])
                                + c2 * dsa * 2.0 * (d1x * jd[0, b] + d1y * jd[1, b]))
                    if use_floor:
                        floor[ia] += abs(tan) * (abs(q0[jb]) + abs(q1[jb]))
                    if fpos[ia] >= 0 and fpos[jb] >= 0:
                        _madd(mat, fpos, fpos[ia], fpos[jb], tan)
            for side in range(2):
                kk = ints[i0 + side]
                if kk < 0:
                    break
                sign = 1.0 if side == 0 else -1.0
                o, nb = maps[1][kk], maps[2][kk]
                f[0], f[1] = sign * kap * sx, sign * kap * sy
                _add_dgrad_jacobian(maps, kk, q0[o:o + nb], q1[o:o + nb], f, th, mat, fpos, floor, scratch)


@numba.njit(cache=True, _nrt=False)
def _add_loads(maps, loads, q, v, trow, cq, cv, dz, ext, mat, fpos, ws):
    """The non-conservative force elements Q(q, v, t) into ``ext`` and −(cq ∂Q/∂q + cv ∂Q/∂v diag(dz)) into
    ``mat`` (``trow``: the time table's row at t). The energy-momentum step evaluates them at the mid-point
    (q0 + Δq/2, z/Δt) with cq = Δt/2, cv = 1, dz = dz/dΔq; the Newmark step at (q1, v1) with cq = Δt,
    cv = Δt c_v, dz = 1. ``loads`` None (no force elements): nothing, and Numba prunes the body. A damper
    whose two points coincide sets the workspace's flag: the step goes to Python, which raises."""
    if loads is None:
        return
    kind, ptr, ints, fl = loads
    f, rv = ws[6][0], ws[6][2]
    jac, jd, vj, tmp = ws[7][0], ws[7][3], ws[7][4], ws[7][5]
    for e in range(kind.size):
        i0, f0, i1 = ptr[e, 0], ptr[e, 1], ptr[e + 1, 0]
        ke = kind[e]
        if ke == POINT_FORCE or ke == FOLLOWER_FORCE:   # Q = Jᵀ f, f = F(t) or A(ϑ) F(t), ϑ = g·q + c
            k, col = ints[i0], ints[i0 + 1]
            o, nb = maps[1][k], maps[2][k]
            qb = q[o:o + nb]
            _jacobian_into(maps, k, qb, jac)
            f[0], f[1] = trow[col], trow[col + 1]
            if ke == FOLLOWER_FORCE:
                ang = fl[f0]
                for t in range(i0 + 2, i1):
                    ang += fl[f0 + 1 + t - i0 - 2] * q[ints[t]]
                C, S = np.cos(ang), np.sin(ang)
                f[0], f[1] = C * trow[col] - S * trow[col + 1], S * trow[col] + C * trow[col + 1]
                for a in range(nb):             # ∂(Jᵀ A F)/∂ϑ ⊗ g = Jᵀ E f ⊗ g
                    ia = fpos[o + a]
                    if ia < 0:
                        continue
                    jef = -jac[0, a] * f[1] + jac[1, a] * f[0]
                    for t in range(i0 + 2, i1):
                        jb = fpos[ints[t]]
                        if jb >= 0:
                            _madd(mat, fpos, ia, jb, -(cq * jef * fl[f0 + 1 + t - i0 - 2]))
            for a in range(nb):
                ext[o + a] += jac[0, a] * f[0] + jac[1, a] * f[1]
            _add_hessian_product(maps, k, qb, f, -cq, mat, fpos)
        elif ke == GENERALIZED_FORCE:           # Q = g F_c(t)
            val = trow[ints[i0]]
            for t in range(i0 + 1, i1):
                ext[ints[t]] += fl[f0 + t - i0 - 1] * val
        elif ke == ROW_DAMPER:                  # Q = −c (g·v) g
            c, rate = fl[f0], 0.0
            for t in range(i0, i1):
                rate += fl[f0 + 1 + t - i0] * v[ints[t]]
            for a in range(i0, i1):
                ia, ga = ints[a], fl[f0 + 1 + a - i0]
                ext[ia] -= c * rate * ga
                if fpos[ia] < 0:
                    continue
                for b in range(i0, i1):
                    jb = ints[b]
                    if fpos[jb] >= 0:
                        _madd(mat, fpos, fpos[ia], fpos[jb], cv * c * ga * fl[f0 + 1 + b - i0] * dz[jb])
        elif ke == TWO_POINT_DAMPER:
            # Q = −c (u·w) J_dᵀ u, u = d/l, w = J_d v; ∂Q/∂q = −c (J_dᵀu ⊗ ∂(u·w)/∂q + (u·w)(∂(J_dᵀ u)/∂q|_u
            # + J_dᵀ ∂u/∂q)), ∂u/∂q = (I − u uᵀ) J_d / l, ∂(u·w)/∂q = wᵀ ∂u/∂q + uᵀ ∂(J_d v)/∂q
            c = fl[f0]
            dx, dy = _pair_distance(maps, ints, fl, i0, f0 + 1, q, rv)
            ln = np.hypot(dx, dy)
            if ln == 0.0:                       # the direction is undefined: the Python step raises
                ws[8][0] = 1
                return
            ux, uy = dx / ln, dy / ln
            ns = _pair_matrix(maps, ints, i0, q, q, v, 0, jac, jd)
            _pair_matrix(maps, ints, i0, q, q, v, 2, jac, vj)
            wx, wy = 0.0, 0.0
            for a in range(ns):
                va = v[_slot(maps, ints, i0, a)]
                wx += jd[0, a] * va
                wy += jd[1, a] * va
            rate = ux * wx + uy * wy
            jtu, drate = tmp[0], tmp[1]
            for a in range(ns):
                jtu[a] = jd[0, a] * ux + jd[1, a] * uy
                # wᵀ (I − u uᵀ) J_d / l = (w − (u·w) u)ᵀ J_d / l
                drate[a] = ((wx - rate * ux) * jd[0, a] + (wy - rate * uy) * jd[1, a]) / ln \
                    + ux * vj[0, a] + uy * vj[1, a]
            for a in range(ns):
                ia = _slot(maps, ints, i0, a)
                ext[ia] -= c * rate * jtu[a]
                if fpos[ia] < 0:
                    continue
                for b in range(ns):
                    jb = _slot(maps, ints, i0, b)
                    if fpos[jb] < 0:
                        continue
                    # J_dᵀ ∂u/∂q = J_dᵀ (I − u uᵀ) J_d / l
                    jdu = (jd[0, a] * jd[0, b] + jd[1, a] * jd[1, b] - jtu[a] * jtu[b]) / ln
                    fq = -c * (jtu[a] * drate[b] + rate * jdu)
                    fv = -c * jtu[a] * jtu[b]
                    _madd(mat, fpos, fpos[ia], fpos[jb], -(cq * fq + cv * fv * dz[jb]))
            for side in range(2):               # −c (u·w) ∂(J_dᵀ u)/∂q at fixed u
                kk = ints[i0 + side]
                if kk < 0:
                    break
                sign = 1.0 if side == 0 else -1.0
                o, nb = maps[1][kk], maps[2][kk]
                f[0], f[1] = sign * ux, sign * uy
                _add_hessian_product(maps, kk, q[o:o + nb], f, cq * c * rate, mat, fpos)


@numba.njit(cache=True, _nrt=False)
def _add_loads_mid(maps, loads, q0, dq, z, dz, trow, h, ext, mat, fpos, ws):
    """:func:`_add_loads` at the energy-momentum step's mid-point (q0 + Δq/2, z/Δt)."""
    if loads is None:
        return
    qm, vm = ws[2][_QM], ws[2][_VM]
    for i in range(q0.size):
        qm[i] = q0[i] + 0.5 * dq[i]
        vm[i] = z[i] / h
    _add_loads(maps, loads, qm, vm, trow, 0.5 * h, 1.0, dz, ext, mat, fpos, ws)


@numba.njit(cache=True, _nrt=False)
def _element_potential(maps, loads, q, rv):
    """V(q) of the conservative force elements, J."""
    if loads is None:
        return 0.0
    kind, ptr, ints, fl = loads
    pot = 0.0
    for e in range(kind.size):
        i0, f0, i1 = ptr[e, 0], ptr[e, 1], ptr[e + 1, 0]
        if kind[e] == COORD_SPRING:
            pot += 0.5 * fl[f0] * q[ints[i0]] ** ints[i0 + 1]
        elif kind[e] == ROW_SPRING:
            s = fl[f0 + 1]
            for t in range(i0, i1):
                s += fl[f0 + 2 + t - i0] * q[ints[t]]
            pot += 0.5 * fl[f0] * s * s
        elif kind[e] == TWO_POINT_SPRING:
            dx, dy = _pair_distance(maps, ints, fl, i0, f0 + 2, q, rv)
            pot += 0.5 * fl[f0] * (np.hypot(dx, dy) - fl[f0 + 1]) ** 2
    return pot


@numba.njit(cache=True)
def _add_frame_terms(frames, frame_off, frame_pos, q0, q1, v0, v1, h, p1, gk, gp, floor, mat):
    """Add the floating-frame bodies' energy-momentum terms (a separate function: ``frames`` is
    None in scenes without such bodies, and Numba prunes the branch only on an argument);
    ``frame_pos``: where their tangents' entries land in the flattened Newton matrix."""
    if frames is None:
        return
    pos, ptr = frame_pos
    for i in range(len(frames)):
        kd = frames[i]
        o = frame_off[i]
        nb = kd.n
        pb, gkb, gpb, data, flb = energy_momentum_terms(kd, q0[o:o + nb], q1[o:o + nb], v0[o:o + nb],
                                                        v1[o:o + nb], h)
        p1[o:o + nb] += pb
        gk[o:o + nb] += gkb
        gp[o:o + nb] += gpb
        floor[o:o + nb] += flb
        base = ptr[i]
        for t in range(data.size):
            k = pos[base + t]
            if k >= 0:
                mat[k] += data[t]


@numba.njit(cache=True)
def _add_strain_terms(strains, strain_off, strain_pos, q0, q1, h, gp, floor, mat):
    """Add the exact beams' discrete strain gradients (:mod:`skfem_flex.bodies.exact.kernel`), their
    tangent Δt ∂g/∂q1 and round-off floor; False if a step folds an element or turns a section by
    MAX_INCREMENT or more (at any Newton iterate the loop then hands the step to Python, which raises
    the proper error and halves the step, as it does on the Python path)."""
    if strains is None:
        return True
    pos, ptr = strain_pos
    for i in range(len(strains)):
        kd = strains[i]
        o, nb = strain_off[i], kd.n
        g = np.empty(nb)
        data = np.empty(kd.pat_idx.size)
        fl = np.empty(nb)
        if exact_kernel.potential_discrete_gradient(kd, q0[o:o + nb], q1[o:o + nb], g, data, fl) != exact_kernel.OK:
            return False
        for a in range(nb):
            gp[o + a] += g[a]
            floor[o + a] += h * fl[a]
        base = ptr[i]
        for t in range(data.size):
            k = pos[base + t]
            if k >= 0:
                mat[k] += h * data[t]
    return True


@numba.njit(cache=True, _nrt=False)
def cayley_terms(dpsi):
    """(z, Δψ/w, d(Δψ/w)/dΔψ, dz/dΔψ) of an increment Δψ (rad), z = w = 2 tan(Δψ/2): the formulas of
    :func:`~skfem_flex.numerics.rotations.cayley`, ``cayley_ratio``, ``cayley_ratio_derivative`` and
    ``cayley_derivative`` for the compiled step (``tests/test_compiled_scene.py`` holds them to those)."""
    h = 0.5 * dpsi
    c = np.cos(h)
    if abs(dpsi) < SERIES_BELOW:
        dratio = -dpsi / 6.0 - dpsi ** 3 / 180.0
    else:
        sh = np.sin(h)
        dratio = (np.sin(dpsi) - dpsi) / (4.0 * sh * sh)
    return 2.0 * np.tan(h), c / sinc(h), dratio, 1.0 / (c * c)


@numba.njit(cache=True)
def _strain_energy(frames, frame_off, strains, strain_off, q):
    """Strain energy (J) of the floating-frame bodies (``frames``) and the exact beams (``strains``); either
    may be None (a separate argument each, so that Numba prunes the absent kind)."""
    pot = 0.0
    if frames is not None:
        for i in range(len(frames)):
            kd = frames[i]
            o = frame_off[i]
            pot += potential_energy(kd, q[o:o + kd.n])
    if strains is not None:
        for i in range(len(strains)):
            kd = strains[i]
            o = strain_off[i]
            pot += exact_kernel.potential_energy(kd, q[o:o + kd.n])
    return pot


@numba.njit(cache=True, _nrt=False)
def _dot(a, b):
    s = 0.0
    for i in range(a.size):
        s += a[i] * b[i]
    return s


@numba.njit(cache=True)
def _evaluate(system, x):
    """``evaluate`` of the Newton core: EnergyMomentum.step's residual on the packed scene, its Newton
    matrix [[J_FF, D_Fᵀ], [Φ_q,F, 0]] assembled in place (``system`` = (packed, step data, workspace)).

    With Cayley coordinates (exact beams) the rates are z = 2 tan(Δψ/2) there: v1 = 2z/Δt − v0, the
    force rows (discrete gradients, constraint forces) are scaled by Δψ/w and the Jacobian is
    (2/Δt) M diag(dz/dΔq) + diag(Δψ/w) J_forces + diag(g d(Δψ/w)/dΔψ), as in the Python step."""
    packed, step, ws = system
    mass, frames, frame_off, maps, gravity, constraints, bodies, loads, strain, plan = packed
    q0, v0, p0, free, fpos, sc, table, kk = step
    h, p0_inf, e_scale0, rtol, ctol, etol = sc[0], sc[1], sc[2], sc[3], sc[4], sc[5]
    trow = table[kk[0]]
    res, mat, wn = ws[0], ws[1], ws[2]
    dq_base, dq, q1, v1, p1, r, ext, gk, gp, floor = (wn[_DQ_BASE], wn[_DQ], wn[_Q1], wn[_V1], wn[_P1], wn[_R],
                                                      wn[_EXT], wn[_GK], wn[_GP], wn[_FLOOR])
    dtmu, z, ratio, dratio, dz = wn[_DTMU], wn[_Z], wn[_RATIO], wn[_DRATIO], wn[_DZ]
    phi, cq, d, span = ws[3][0], ws[4], ws[5], ws[3]
    strains, strain_off, cay = strain[0], strain[1], strain[2]
    n, nf = q0.size, free.size
    m = constraints[7]
    mu = x[nf:]
    dq[:] = dq_base
    for i in range(nf):
        dq[free[i]] = x[i]
    for i in range(n):
        q1[i] = q0[i] + dq[i]
        z[i] = dq[i]
    for c in cay:
        z[c], ratio[c], dratio[c], dz[c] = cayley_terms(dq[c])
    for i in range(n):
        v1[i] = (2.0 / h) * z[i] - v0[i]
    mat[:] = 0.0
    ptr, idx, dat = mass
    for i in range(n):                  # p1 = M v1 of the constant-mass bodies
        s = 0.0
        for t in range(ptr[i], ptr[i + 1]):
            s += dat[t] * v1[idx[t]]
        p1[i] = s
    gk[:] = 0.0
    gp[:] = 0.0
    floor[:] = 0.0
    _add_frame_terms(frames, frame_off, strain[3], q0, q1, v0, v1, h, p1, gk, gp, floor, mat)
    if not _add_strain_terms(strains, strain_off, strain[4], q0, q1, h, gp, floor, mat):
        ws[8][0] = 1
        return np.nan
    _add_conservative(maps, gravity, loads, q0, q1, h, gp, floor, mat, fpos, ws)
    for i in range(n):                  # the discrete-gradient forces (Dᵀμ added below)
        r[i] = h * gp[i] - h * gk[i]
    scale = max(max_abs(p1), p0_inf)
    scale = max(scale, h * max_abs(gk), h * max_abs(gp))
    err_c = 0.0
    if m:
        _constraint_terms(maps, constraints, q0, q1, mu, trow, n, mat, fpos, ws)
        dtmu[:] = 0.0
        for i in range(m):              # each coordinate's sum in the order of the rows, as a full product
            for j in range(int(span[3, i]), int(span[4, i])):
                dtmu[j] += d[i, j] * mu[i]
        for j in range(n):
            r[j] += dtmu[j]
        scale = max(scale, max_abs(dtmu))
    for c in cay:                       # forces conjugate to Δq → to the Cayley rate z
        ic = fpos[c]
        if ic >= 0:
            _mscale_row(mat, fpos, ic, nf, ratio[c])
            _madd(mat, fpos, ic, ic, r[c] * dratio[c])
        r[c] *= ratio[c]
        floor[c] *= ratio[c]
    for i in range(n):                  # (2/Δt) M dz/dΔq of the constant-mass bodies
        ia = fpos[i]
        if ia < 0:
            continue
        for t in range(ptr[i], ptr[i + 1]):
            jb = fpos[idx[t]]
            if jb >= 0:
                _madd(mat, fpos, ia, jb, (2.0 / h) * dat[t] * dz[idx[t]])
    ext[:] = 0.0
    _add_loads_mid(maps, loads, q0, dq, z, dz, trow, h, ext, mat, fpos, ws)
    scale = max(scale, h * max_abs(ext))
    for i in range(n):
        r[i] = (p1[i] - p0[i]) + r[i] - h * ext[i]
    if m:
        cqq, cq_inf = 0.0, 0.0
        for i in range(m):
            s, sa = 0.0, 0.0
            for j in range(int(span[3, i]), int(span[4, i])):
                a = abs(cq[i, j])
                s += a * abs(q1[j])
                sa = max(sa, a)
            cqq = max(cqq, s)
            cq_inf = max(cq_inf, sa)
        c_scale = max(cqq, cq_inf * constraints[8], _TINY)
        err_c = max_abs(phi) / (ctol * c_scale)
        for i in range(m):
            for c in range(int(span[3, i]), int(span[4, i])):   # the border, on a zeroed matrix: adds are sets
                j = fpos[c]
                if j >= 0:
                    _madd(mat, fpos, j, nf + i, d[i, c] * ratio[c])
                    _madd(mat, fpos, nf + i, j, cq[i, c])
            res[nf + i] = phi[i]
    vr, fl_inf, vfl = 0.0, 0.0, 0.0
    for i in range(nf):
        a = free[i]
        res[i] = r[a]
        vb = z[a] / h
        vr += vb * r[a]
        fl_inf = max(fl_inf, abs(floor[a]))
        vfl += abs(vb) * floor[a]
    vr = abs(vr)
    r_inf = max_abs(res[:nf])
    zg = 0.0
    for i in range(n):
        zg += z[i] * ratio[i] * gp[i]
    e_scale = max(e_scale0, abs(0.5 * _dot(v1, p1)), abs(zg), _TINY)
    err = max(r_inf / (rtol * max(scale, _TINY)), err_c, vr / (etol * e_scale))
    err = roundoff_floor(err, err_c, r_inf, fl_inf, vr, vfl)
    if mat[mat.size - 1] != 0.0:        # an entry outside the Newton pattern: the step goes to Python
        ws[8][0] = 1
    return err if all_finite(res) else np.nan


@numba.njit(cache=True)
def _solve(csr, system):
    """``solve`` of the Newton core: the bordered Newton matrix as a band with a dense border when the
    scene's plan has one (:func:`skfem_flex.numerics.linear_solver.bordered_band_solve`, several times faster
    on beams), else, or when that solve is not backward stable, by LAPACK gesv; stored as CSR, by
    :func:`skfem_flex.numerics.linear_solver.bordered_band_solve_csr`. ``csr`` is the plan's last entry, None
    (dense storage) or the pattern's (row pointers, column indices): an argument of its own, so that
    Numba prunes the storage a scene does not use (each costs seconds of compilation)."""
    interior, border, lo, up = system[0][9][:4]
    res, mat = system[2][0], system[2][1]
    if csr is not None:                 # no dense fallback: a failed solve hands the step to Python
        return bordered_band_solve_csr(mat, csr[0], csr[1], res, interior, border, lo, up)
    nx = res.size
    a = mat[:nx * nx].reshape(nx, nx)
    if interior.size:
        x, ok = bordered_band_solve(a, res, interior, border, lo, up)
        if ok:
            return x, True
    try:
        return np.linalg.solve(a, res), True
    except Exception:                  # singular: numba raises LinAlgError
        return res.copy(), False


@numba.njit(cache=True)
def _derived(packed, q, v, p, rv):
    """(T, V, p_x, p_y, L about the origin) of the scene at (q, v) with momentum p (``rv``: a 2-vector to
    work in)."""
    mass, frames, frame_off, maps, gravity, constraints, bodies, loads, strain, plan = packed
    pot = _strain_energy(frames, frame_off, strain[0], strain[1], q) + _element_potential(maps, loads, q, rv)
    gmaps, gvec = gravity
    for i in range(gmaps.size):
        k = gmaps[i]
        o, nb = maps[1][k], maps[2][k]
        _position_into(maps, k, q[o:o + nb], rv)
        pot -= gvec[i, 0] * rv[0] + gvec[i, 1] * rv[1]
    lx, ly, ix, iy, X, Y, ia = bodies[:7]
    px, py, ang = 0.0, 0.0, 0.0
    for i in lx:
        px += p[i]
    for i in ly:
        py += p[i]
    for j in range(ix.size):
        ang += (X[j] + q[ix[j]]) * p[iy[j]] - (Y[j] + q[iy[j]]) * p[ix[j]]
    for i in ia:
        ang += p[i]
    return 0.5 * _dot(v, p), pot, px, py, ang


@numba.njit(cache=True)
def _chunk_workspace(packed, n, nf):
    """:func:`_workspace` of a chunk: n coordinates, nf of them free, the packed scene's multipliers and
    largest body block."""
    maps, fpos = packed[3], packed[9][4]
    nbmax = 1
    for k in range(maps[2].size):
        nbmax = max(nbmax, maps[2][k])
    m = packed[5][7]
    size = fpos.size
    nx = fpos[size - 2]
    nmat = nx * nx + 1 if fpos[size - 1] == DENSE else fpos[fpos[size - 3] + nx] + 1
    ws = _workspace(n, m, nf + m, nmat, nbmax)
    _set_constraint_spans(maps, packed[5], ws[3])
    return ws


@numba.njit(cache=True)
def _mechanism_records(packed, n, npr, n_rec):
    """The record arrays of a chunk of n_rec records: the buffers of
    :func:`~skfem_flex.compiled.single_body_loop.record_step`, λ, the derived values (T, V, p_x, p_y, L, ‖Φ‖∞,
    ‖Φ_q v + Φ_t‖∞) and the probes' positions."""
    return (record_buffers(n_rec, n, npr), np.empty((n_rec, packed[5][7])), np.empty((n_rec, 7)),
            np.empty((n_rec, packed[6][7].size, 2)))


@numba.njit(cache=True, _nrt=False)
def _record_mechanism(packed, records, i_rec, t, q, v, p, work, its, reaction, lam, ws):
    """Record i_rec of a step of either mechanism loop: state, work, iterations, reactions, λ, the derived
    values from the step's last evaluation (Φ, Φ_q, Φ_t in the workspace) and the probes."""
    buffers, rec_lam, rec_derived, rec_probe = records
    maps, probe_maps = packed[3], packed[6][7]
    phi, phi_t, cq, rv = ws[3][0], ws[3][1], ws[4], ws[6][2]
    record_step(buffers, i_rec, t, q, v, work, its, reaction)
    for i in range(lam.size):
        rec_lam[i_rec, i] = lam[i]
    tk, vk, px, py, ang = _derived(packed, q, v, p, rv)
    rec_derived[i_rec, 0] = tk
    rec_derived[i_rec, 1] = vk
    rec_derived[i_rec, 2] = px
    rec_derived[i_rec, 3] = py
    rec_derived[i_rec, 4] = ang
    vres = 0.0
    span = ws[3]
    for i in range(cq.shape[0]):
        s = 0.0
        for j in range(int(span[3, i]), int(span[4, i])):
            s += cq[i, j] * v[j]
        vres = max(vres, abs(s + phi_t[i]))
    rec_derived[i_rec, 5] = max_abs(phi)
    rec_derived[i_rec, 6] = vres
    for j in range(probe_maps.size):
        kp = probe_maps[j]
        o = maps[1][kp]
        _position_into(maps, kp, q[o:o + maps[2][kp]], rv)
        rec_probe[i_rec, j, 0] = rv[0]
        rec_probe[i_rec, j, 1] = rv[1]


@numba.njit(cache=True)
def _run(packed, q_start, v_start, acc_start, t, hs, qp, table, pres, free, fpos, lam_start, reaction_start, rtol,
         ctol, etol, max_iterations, line_search, work, first_step, record_every, n_steps):
    mass, frames, frame_off, maps, gravity, constraints, bodies, loads, strain, plan = packed
    n, ns, npr, m = q_start.size, hs.size, pres.size, constraints[7]
    records = _mechanism_records(packed, n, npr, record_count(first_step, ns, record_every, n_steps))
    its_total = 0
    nf = free.size
    ws = _chunk_workspace(packed, n, nf)
    wn = ws[2]
    dq_base, cay = wn[_DQ_BASE], strain[2]
    q1, v1, p1, r, ext = wn[_Q1], wn[_V1], wn[_P1], wn[_R], wn[_EXT]
    mu, d = ws[3][2], ws[5]
    z, ratio = wn[_Z], wn[_RATIO]
    # the state, updated in place after each step (the caller's arrays are not touched)
    q, v, acc = q_start.copy(), v_start.copy(), acc_start.copy()
    lam, reaction = lam_start.copy(), reaction_start.copy()
    p = _scene_momentum(mass, frames, frame_off, q, v)
    # the step's data: arrays updated in place, so that the system tuple is built once per chunk
    sc = np.array([0.0, 0.0, 0.0, rtol, ctol, etol])
    kk = np.zeros(1, dtype=np.int64)
    system = (packed, (q, v, p, free, fpos, sc, table, kk), ws)
    i_rec = np.int64(0)                 # not the literal 0: the record helpers compile once, for int64
    for k in range(ns):
        h = hs[k]
        # one energy-momentum step from (q, v, p): the new state is left in the workspace
        dq_base[:] = 0.0
        for i in range(npr):
            dq_base[pres[i]] = qp[k, i] - q[pres[i]]
        x = np.empty(nf + m)
        x_scale = 0.0
        predicted_increment(v, acc, h, free, x)
        for i in range(nf):
            x_scale = max(x_scale, abs(q[free[i]]))
        for c in cay:                   # the Cayley rate of the last step, continued: Δψ = 2 atan(Δt ω0/2)
            if fpos[c] >= 0:
                x[fpos[c]] = 2.0 * np.arctan(0.5 * x[fpos[c]])
        for i in range(m):
            x[nf + i] = h * lam[i]
        sc[0], sc[1], sc[2] = h, max_abs(p), abs(0.5 * _dot(v, p))
        kk[0] = k
        state = newton_start(x, x_scale, max_iterations, line_search)
        status = EVALUATE
        ws[8][0] = 0
        while status < 0:               # do what the Newton core asks; its rules are all in the core
            if status == EVALUATE:
                err = _evaluate(system, state[2])
                if ws[8][0]:
                    # the Python step raises here, at any iterate (no backtracking): the step goes to Python
                    status = NONFINITE_RESIDUAL
                    break
                status = newton_evaluated(state, err)
            else:
                y, regular = _solve(plan[5], system)
                status = newton_solved(state, y, regular)
        its = state[4][0]
        mu[:] = state[0][nf:]
        if status == OK and not (all_finite(q1) and all_finite(v1)):
            status = NONFINITE_RESIDUAL
        if status != OK:
            return (status, k, t, q, v, acc, lam, reaction, work, its_total, i_rec) + records
        w = _dot(z, ext)
        for i in range(npr):
            reaction[i] = r[pres[i]] / h
            w += z[pres[i]] * reaction[i]
        if m:
            # Φ, Φ_q and D are those of the last evaluation: the Newton core ends at the point it
            # evaluated last (module newton: no exit evaluates a point it then leaves)
            dphi = 0.0                          # D diag(Δψ/w) z = D Δq = ΔΦ + Δx
            span = ws[3]
            for i in range(m):
                for j in range(int(span[3, i]), int(span[4, i])):
                    dphi += mu[i] * d[i, j] * ratio[j] * z[j]
            w -= dphi / h                       # μ = Δt λ̄: the work is −λ̄·ΔΦ
        work += w
        t = t + h
        for i in range(n):
            acc[i] = (v1[i] - v[i]) / h
        q[:] = q1
        v[:] = v1
        p[:] = p1
        for i in range(m):
            lam[i] = mu[i] / h
        its_total += its
        s = first_step + k
        if is_recorded(s, record_every, n_steps):
            _record_mechanism(packed, records, i_rec, t, q, v, p, work, its, reaction, lam, ws)
            i_rec += 1
    return (OK, ns, t, q, v, acc, lam, reaction, work, its_total, i_rec) + records


def time_table(columns, t, hs, at_end=False):
    """The functions of time the loop needs, evaluated in Python for a chunk of steps from time ``t`` (s)
    with sizes ``hs``: row k, column c is ``fun(t_k+1)[comp]`` ("end": drivers' motion laws, as the
    Python step evaluates Φ(q1, t1)) or ``fun(t_k + h_k/2)[comp]`` ("mid": loads at the mid-point).

    ``at_end``: every column at the end times (the Newmark step's loads act at t_{n+1}).

    Each function is called once per step (its ``unchecked`` form when it has one), and the table is
    checked at once: an entry that is not finite raises the function's own error (or a ValueError
    naming it and the time)."""
    table = np.zeros((hs.size, max(len(columns), 1)))
    if not columns:
        return table
    ends = np.empty(hs.size)
    mids = np.empty(hs.size)
    for k in range(hs.size):              # the sums of the Python loop: t1 = t0 + h, t_m = t0 + h/2
        mids[k] = t + 0.5 * hs[k]
        t = t + hs[k]
        ends[k] = t
    groups = {}
    for c, (when, fun, comp) in enumerate(columns):
        groups.setdefault((id(fun), when), (fun, when, []))[2].append((c, comp))
    for fun, when, targets in groups.values():
        raw = getattr(fun, "unchecked", fun)
        times = ends if when == "end" or at_end else mids
        vals = np.array([np.ravel(raw(tk)) for tk in times], dtype=float).reshape(hs.size, -1)
        bad = ~np.isfinite(vals).all(axis=1)
        if bad.any():
            tk = float(times[int(np.argmax(bad))])
            fun(tk)                           # raises its own error if it has one
            raise ValueError(f"{getattr(fun, '__qualname__', fun)!s}({tk!r}) is not finite")
        for c, comp in targets:
            table[:, c] = vals[:, comp]
    return table


def _free_positions(scene):
    """fpos[i] = position of coordinate i among the free ones, −1 for a prescribed one."""
    fpos = -np.ones(scene.n, dtype=np.int64)
    fpos[scene.free_index] = np.arange(scene.free_index.size)
    return fpos


def newton_system(scene, q0, v0, h, t=0.0, lam=None):
    """The Newton system of one step from (q0, v0) at time ``t`` (s) with step ``h`` (s), as the loop's
    ``_evaluate`` and ``_solve`` take it (for profiling and tests of the linear solve); the Newton
    unknowns start at (h v0 on the free coordinates, h λ).

    Returns
    -------
    system : tuple
        (packed scene, step data, workspace); after an evaluation ``system[2][0]`` is the residual and
        ``system[2][1]`` the bordered Newton matrix.
    x0 : ndarray
        The start of the Newton iteration.
    """
    if not _compiles(scene):
        raise ValueError(f"scene {scene.name!r} has a part without a compiled form, or a Newton matrix too large "
                         f"to store dense with no bordered band plan (see compiled_scene.eligible)")
    return _system(scene, _planned(scene), _packed(scene)[2], q0, v0, h, t, lam)


def _system(scene, packed, columns, q0, v0, h, t, lam):
    n, m = scene.n, scene.n_constraints
    q0, v0 = np.asarray(q0, dtype=float), np.asarray(v0, dtype=float)
    free = scene.free_index.astype(np.int64)
    p0 = _scene_momentum(packed[0], packed[1], packed[2], q0, v0)
    trow = time_table(columns, float(t), np.array([float(h)]))[0]
    ws = _chunk_workspace(packed, n, free.size)
    if scene.prescribed_index.size:
        ws[2][_DQ_BASE][scene.prescribed_index] = scene.prescribed_state(t + h)[0] - q0[scene.prescribed_index]
    sc = np.array([float(h), max_abs(p0), abs(0.5 * float(v0 @ p0)), 1e-12, 1e-12, 1e-14])
    step = (q0, v0, p0, free, packed[9][4], sc, np.ascontiguousarray(trow[None, :]),
            np.zeros(1, dtype=np.int64))
    lam = np.zeros(m) if lam is None else np.asarray(lam, dtype=float)
    return (packed, step, ws), np.concatenate([h * v0[free], h * lam])


#: the compiled loop itself (what a cold cache compiles first)
run_loop = _run


def run_chunk(scene, scheme, state, dt, t_end, first_step, n_chunk, n_steps, record_every, work):
    """Run steps ``first_step … first_step + n_chunk − 1`` through the compiled loop.

    As :func:`skfem_flex.compiled.single_body_loop.run_chunk`; the records are arrays, one row per recorded
    step: dict(t, q, v, work, iterations, reaction, derived, lam, probes), ``derived`` = (T, V, p_x,
    p_y, L, ‖Φ‖∞, ‖Φ_q v + Φ_t‖∞), ``lam`` the multipliers (mean over each step), ``probes`` the
    values of the probes with a position map ({name: (n_rec, 2)}); the result also holds ``lam``
    (the multipliers, mean over the last step).
    """
    if type(scheme) is not EnergyMomentum:
        return _run_chunk_newmark(scene, scheme, state, dt, t_end, first_step, n_chunk, n_steps, record_every, work)
    s = scheme.newton
    packed = _planned(scene)
    hs, qp = chunk_schedule(scene, state.t, dt, t_end, first_step, n_chunk, n_steps)
    table = time_table(_packed(scene)[2], float(state.t), hs)
    m = scene.n_constraints
    lam = np.asarray(state.lam, dtype=float) if np.size(state.lam) == m else np.zeros(m)
    npr = scene.prescribed_index.size
    reaction = (np.asarray(state.prescribed_force, dtype=float) if np.size(state.prescribed_force) == npr
                else np.zeros(npr))
    out = _run(packed, np.ascontiguousarray(state.q, dtype=float),
               np.ascontiguousarray(state.v, dtype=float), predictor_acceleration(state), float(state.t), hs, qp, table,
               scene.prescribed_index.astype(np.int64), scene.free_index.astype(np.int64), packed[9][4],
               lam, reaction,
               float(s.rtol), float(s.ctol), float(s.etol), int(s.max_iterations), bool(s.line_search), float(work),
               int(first_step), int(record_every), int(n_steps))
    status, done, t, q, v, acc, lam, reaction, work, its_total, n_rec, buffers, rec_lam, rec_derived, rec_probe = out
    return _chunk_result(scene, status, done, t, q, v, acc, None, lam, reaction, work, its_total, n_rec, buffers,
                         rec_lam, rec_derived, rec_probe)


def _chunk_result(scene, status, done, t, q, v, acc, pseudo, lam, reaction, work, its_total, n_rec, buffers, rec_lam,
                  rec_derived, rec_probe):
    probes = {}
    for name, j, k, combine in _packed(scene)[1]:
        probes[name] = rec_probe[:n_rec, j] if combine is None else combine(rec_probe[:n_rec, j:j + k])
    records = chunk_records(buffers, n_rec, rec_derived[:n_rec], rec_lam[:n_rec], probes)
    return dict(status=int(status), done=int(done), t=float(t), q=q, v=v, acc=acc, pseudo=pseudo, lam=lam,
                reaction=reaction, work=float(work), iterations=int(its_total), records=records)


def _run_chunk_newmark(scene, scheme, state, dt, t_end, first_step, n_chunk, n_steps, record_every, work):
    """:func:`run_chunk` for the Newmark family: the prescribed laws' positions, rates and accelerations
    and the other functions of time at the steps' end times (and the chunk's start time) from Python."""
    s = scheme.newton
    packed = _planned(scene)
    hs, _ = chunk_schedule(scene, state.t, dt, t_end, first_step, n_chunk, n_steps)
    npr, m, n = scene.prescribed_index.size, scene.n_constraints, scene.n
    qp, vp, ap = (np.zeros((n_chunk, npr)) for _ in range(3))
    t = float(state.t)
    for k in range(n_chunk):              # the Python loop's sums t + h
        t = t + hs[k]
        if npr:
            qp[k], vp[k], ap[k] = scene.prescribed_state(t)
    table = time_table(_packed(scene)[2], float(state.t), np.concatenate([[0.0], hs]), at_end=True)
    lam = np.asarray(state.lam, dtype=float) if np.size(state.lam) == m else np.zeros(m)
    have_reaction = np.size(state.prescribed_force) == npr
    reaction = np.asarray(state.prescribed_force, dtype=float) if have_reaction else np.zeros(npr)
    acc = np.ascontiguousarray(state.acc, dtype=float)
    pseudo = np.ascontiguousarray(state.pseudo, dtype=float)
    if acc.size != n or pseudo.size != n:
        raise ValueError(f"a {scheme.name} step needs the state's acc and pseudo ({n} values each; "
                         f"Integrator.start makes them)")
    out = _run_newmark(packed, np.ascontiguousarray(state.q, dtype=float), np.ascontiguousarray(state.v, dtype=float),
                       acc, pseudo, float(state.t), hs, qp, vp, ap, table, scene.prescribed_index.astype(np.int64),
                       scene.free_index.astype(np.int64), packed[9][4], lam, reaction, have_reaction,
                       scheme.alpha_m, scheme.alpha_f, scheme.beta, scheme.gamma,
                       scheme.constraint_level == "velocity", any(c.rheonomic for c in scene.constraints),
                       float(s.rtol), float(s.ctol), int(s.max_iterations), bool(s.line_search), float(work),
                       int(first_step), int(record_every), int(n_steps))
    (status, done, t, q, v, acc, pseudo, lam, reaction, work, its_total, n_rec, buffers, rec_lam, rec_derived,
     rec_probe) = out
    return _chunk_result(scene, status, done, t, q, v, acc, pseudo, lam, reaction, work, its_total, n_rec, buffers,
                         rec_lam, rec_derived, rec_probe)


# ==================================================================== the Newmark step
# The Newmark family (Trapezoidal, GeneralizedAlpha, Newmark; integrators.Newmark.step) on the same
# packed scene: the residual h (M(q1) q̈1 + ∇V(q1) − Q_v − Q) + Φ_qᵀ μ with constraints at position level
# (Φ(q1, t1)) or velocity level ((Φ_q v1 + Φ_t)/c_v), its Newton matrix and scaled error, exactly as the
# Python step forms them; the same Newton core. Functions of time enter at the step's end time.

@numba.njit(cache=True, _nrt=False)
def _velocity_jacobian_into(maps, k, q, v, out):
    """out[:, :nb] = ∂(J(q) v)/∂q of map k at the body's block q, velocities v (zero for LINEAR maps).

    FRAME: J v = m_R Ṙ + A E s θ̇ + A Y ḟ with s = y₀ + Y q_f, so ∂/∂θ = −A s θ̇ + A E Y ḟ and
    ∂/∂q_f,j = A E Y_j θ̇."""
    kind, off, nb, m_r, c, y0, gdat, gptr, ydat, yptr = maps
    n = nb[k]
    for a in range(2):
        for j in range(n):
            out[a, j] = 0.0
    if kind[k] == LINEAR:
        return
    ne, y = n - 3, yptr[k]
    sx, sy = _frame_offset(maps, k, q, q)
    C, S = np.cos(q[2]), np.sin(q[2])
    w = v[2]
    fx, fy = 0.0, 0.0                       # Y ḟ
    for j in range(ne):
        fx += ydat[y + j] * v[3 + j]
        fy += ydat[y + ne + j] * v[3 + j]
    out[0, 2] = -(C * sx - S * sy) * w + (-C * fy - S * fx)
    out[1, 2] = -(S * sx + C * sy) * w + (-S * fy + C * fx)
    for j in range(ne):
        yx, yy = ydat[y + j], ydat[y + ne + j]
        out[0, 3 + j] = w * (-C * yy - S * yx)
        out[1, 3 + j] = w * (-S * yy + C * yx)


@numba.njit(cache=True, _nrt=False)
def _constraint_terms_at(maps, constraints, q1, v1, mu, trow, mat, fpos, ws, cv):
    """Φ(q1, t1), Φ_t and Φ_q(q1) into the workspace, ∂(Φ_qᵀ μ)/∂q1 added to ``mat`` and ∂(Φ_q v1)/∂q1 into
    ``cv`` (m × n). ``trow``: the time table's row at t1 (drivers' x(t1), ẋ(t1))."""
    kind, row, t0, term_map, term_sign, const, length, m, _, l0, lin_idx, lin_coef, nrm, law, _ = constraints
    phi, phi_t, cq = ws[3][0], ws[3][1], ws[4]
    f, acc, rv, jac, vj = ws[6][0], ws[6][1], ws[6][2], ws[7][0], ws[7][1]
    nb_, off_ = maps[2], maps[1]
    _clear_constraint_rows(ws, cq, cv)
    for i in range(kind.size):
        r0 = row[i]
        if kind[i] == POINTS or kind[i] == PROJECTED:
            proj = kind[i] == PROJECTED
            acc[0], acc[1] = -const[i, 0], -const[i, 1]
            for t in range(t0[i], t0[i + 1]):
                k, s = term_map[t], term_sign[t]
                o, nb = off_[k], nb_[k]
                qb1 = q1[o:o + nb]
                _position_into(maps, k, qb1, rv)
                _jacobian_into(maps, k, qb1, jac)
                _velocity_jacobian_into(maps, k, qb1, v1[o:o + nb], vj)
                acc[0] += s * rv[0]
                acc[1] += s * rv[1]
                if proj:
                    for j in range(nb):
                        cq[r0, o + j] += s * (nrm[i, 0] * jac[0, j] + nrm[i, 1] * jac[1, j])
                        cv[r0, o + j] += s * (nrm[i, 0] * vj[0, j] + nrm[i, 1] * vj[1, j])
                    f[0], f[1] = s * nrm[i, 0] * mu[r0], s * nrm[i, 1] * mu[r0]
                else:
                    for a in range(2):
                        f[a] = s * mu[r0 + a]
                        for j in range(nb):
                            cq[r0 + a, o + j] += s * jac[a, j]
                            cv[r0 + a, o + j] += s * vj[a, j]
                _add_hessian_product(maps, k, qb1, f, 1.0, mat, fpos)
            if proj:
                phi[r0] = nrm[i, 0] * acc[0] + nrm[i, 1] * acc[1]
            else:
                phi[r0], phi[r0 + 1] = acc[0], acc[1]
        elif kind[i] == ROTATED:                  # after the loop (_add_rotated_rows)
            continue
        elif kind[i] == LINEAR_ROW:               # g · q + c − x(t1): Φ_q = g
            val = const[i, 0]
            for t in range(l0[i], l0[i + 1]):
                val += lin_coef[t] * q1[lin_idx[t]]
                cq[r0, lin_idx[t]] += lin_coef[t]
            if law[i] >= 0:
                val -= trow[law[i]]
                phi_t[r0] = -trow[law[i] + 1]
            phi[r0] = val
        else:                                   # DISTANCE on a linear map: Φ = ½(|r − a|² − l²)
            k = term_map[t0[i]]
            o, nb = off_[k], nb_[k]
            qb1 = q1[o:o + nb]
            _position_into(maps, k, qb1, rv)
            _jacobian_into(maps, k, qb1, jac)
            dx, dy = rv[0] - const[i, 0], rv[1] - const[i, 1]
            phi[r0] = 0.5 * (dx * dx + dy * dy - length[i] * length[i])
            jvx, jvy = 0.0, 0.0
            for j in range(nb):
                cq[r0, o + j] = dx * jac[0, j] + dy * jac[1, j]
                jvx += jac[0, j] * v1[o + j]
                jvy += jac[1, j] * v1[o + j]
            for j in range(nb):                 # ∂((r − a)ᵀ J v)/∂q = (J v)ᵀ J (J constant)
                cv[r0, o + j] = jvx * jac[0, j] + jvy * jac[1, j]
            for a in range(nb):                 # ∂(μ Jᵀ(r − a))/∂q = μ JᵀJ
                ia = fpos[o + a]
                if ia < 0:
                    continue
                for j in range(nb):
                    jb = fpos[o + j]
                    if jb >= 0:
                        _madd(mat, fpos, ia, jb, mu[r0] * (jac[0, a] * jac[0, j] + jac[1, a] * jac[1, j]))
    _add_rotated_rows(maps, constraints, constraints[14], q1, q1, v1, mu, 2.0, cq, cq[:0], cv, mat, fpos, ws)

@numba.njit(cache=True)
def _add_strain_potential(strains, strain_off, strain_pos, q1, h, grad, mat):
    """The exact beams' ∇V(q1) into ``grad`` and h ∇²V(q1) into ``mat`` (False: a folded element); a separate
    function so that Numba prunes it in scenes without exact beams."""
    if strains is None:
        return True
    pos, ptr = strain_pos
    for i in range(len(strains)):
        kd = strains[i]
        o, nb = strain_off[i], kd.n
        g = np.empty(nb)
        data = np.empty(kd.pat_idx.size)
        fl = np.empty(nb)
        qb = q1[o:o + nb]
        # at equal end points the discrete gradient is ∇V and its ∂/∂q1 half the Hessian
        if exact_kernel.potential_discrete_gradient(kd, qb, qb, g, data, fl) != exact_kernel.OK:
            return False
        for a in range(nb):
            grad[o + a] += g[a]
        base = ptr[i]
        for t in range(data.size):
            k = pos[base + t]
            if k >= 0:
                mat[k] += 2.0 * h * data[t]
    return True


@numba.njit(cache=True)
def _add_frame_newmark(frames, frame_off, frame_pos, q1, v1, acc1, terms, c_a, c_v, h, inertia, grad, qv, mterms, mat):
    """Add the floating-frame bodies' Newmark terms (:func:`~skfem_flex.bodies.floating.kernel.newmark_terms`):
    M q̈1, ∇V, Q_v, |M| terms and h (c_a M + B + K − ∂Q_v/∂q − c_v ∂Q_v/∂v) (a separate function, as
    :func:`_add_frame_terms`, so that Numba prunes it in scenes without such bodies)."""
    if frames is None:
        return
    pos, ptr = frame_pos
    for i in range(len(frames)):
        kd = frames[i]
        o = frame_off[i]
        nb = kd.n
        ib, gb, qb, data, mb = newmark_terms(kd, q1[o:o + nb], v1[o:o + nb], acc1[o:o + nb], c_a, c_v,
                                              terms[o:o + nb])
        for a in range(nb):
            inertia[o + a] += ib[a]
            grad[o + a] += gb[a]
            qv[o + a] += qb[a]
            mterms[o + a] += mb[a]
        base = ptr[i]
        for t in range(data.size):
            k = pos[base + t]
            if k >= 0:
                mat[k] += h * data[t]


@numba.njit(cache=True)
def _evaluate_newmark(system, x):
    """``evaluate`` of the Newton core for :meth:`~skfem_flex.schemes.integrators.Newmark.step` on the packed scene:
    its residual, bordered Newton matrix and scaled error (``system`` = (packed, step data, workspace))."""
    packed, step, ws = system
    mass, frames, frame_off, maps, gravity, constraints, bodies, loads, strain, plan = packed
    q0, v0, a0, acc0, free, fpos, sc, by_velocity, vps, aps, pres, table, kk, cv = step
    h, am, af, beta, gamma, rtol, ctol = sc[0], sc[1], sc[2], sc[3], sc[4], sc[5], sc[6]
    k = kk[0]
    vp, ap, trow = vps[k], aps[k], table[k + 1]
    res, mat, wn = ws[0], ws[1], ws[2]
    dq_base, dq, q1, v1, inertia, r, ext, qv, grad, mterms = (wn[_DQ_BASE], wn[_DQ], wn[_Q1], wn[_V1], wn[_P1],
                                                              wn[_R], wn[_EXT], wn[_GK], wn[_GP], wn[_FLOOR])
    a1, acc1, terms = wn[_Z], wn[_RATIO], wn[_DRATIO]
    phi, phi_t, cq, span = ws[3][0], ws[3][1], ws[4], ws[3]
    n, nf, m = q0.size, free.size, constraints[7]
    mu = x[nf:]
    c_a = (1.0 - am) / ((1.0 - af) * beta * h * h)
    c_v = gamma / (beta * h)
    for i in range(n):
        dq[i] = dq_base[i]
    for i in range(nf):
        dq[free[i]] = x[i]
    for i in range(n):
        q1[i] = q0[i] + dq[i]
        a1[i] = (dq[i] - h * v0[i] - h * h * (0.5 - beta) * a0[i]) / (beta * h * h)
        v1[i] = v0[i] + h * ((1.0 - gamma) * a0[i] + gamma * a1[i])
        acc1[i] = ((1.0 - am) * a1[i] + am * a0[i] - af * acc0[i]) / (1.0 - af)
        terms[i] = abs(dq[i]) + h * abs(v0[i]) + h * h * abs(0.5 - beta) * abs(a0[i])
    for j in range(pres.size):
        i = pres[j]
        v1[i], acc1[i], a1[i] = vp[j], ap[j], ap[j]
    mat[:] = 0.0
    ptr, idx, dat = mass
    for i in range(n):                  # the constant-mass bodies: M q̈1, |M| terms, h c_a M
        s, sa = 0.0, 0.0
        ia = fpos[i]
        for t in range(ptr[i], ptr[i + 1]):
            s += dat[t] * acc1[idx[t]]
            sa += abs(dat[t]) * terms[idx[t]]
            jb = fpos[idx[t]]
            if ia >= 0 and jb >= 0:
                _madd(mat, fpos, ia, jb, h * c_a * dat[t])
        inertia[i] = s
        mterms[i] = sa
    grad[:] = 0.0
    qv[:] = 0.0
    _add_frame_newmark(frames, frame_off, strain[3], q1, v1, acc1, terms, c_a, c_v, h, inertia, grad, qv, mterms,
                       mat)
    if not _add_strain_potential(strain[0], strain[1], strain[4], q1, h, grad, mat):
        ws[8][0] = 1                    # a folded element: the step goes to Python
        return np.nan
    _add_conservative(maps, gravity, loads, q1, q1, 2.0 * h, grad, ws[0][:0], mat, fpos, ws)
    scale = max(max_abs(inertia), max_abs(grad), c_a * max_abs(mterms), max_abs(qv))
    ext[:] = 0.0
    _add_loads(maps, loads, q1, v1, trow, h, h * c_v, wn[_DZ], ext, mat, fpos, ws)
    scale = h * max(scale, max_abs(ext))
    for i in range(n):
        r[i] = h * (inertia[i] + grad[i] - qv[i] - ext[i])
    err_c = 0.0
    if m:
        _constraint_terms_at(maps, constraints, q1, v1, mu, trow, mat, fpos, ws, cv)
        ctmu = wn[_DTMU]
        ctmu[:] = 0.0
        for i in range(m):              # each coordinate's sum in the order of the rows, as a full product
            for j in range(int(span[3, i]), int(span[4, i])):
                ctmu[j] += cq[i, j] * mu[i]
        for j in range(n):
            r[j] += ctmu[j]
        scale = max(scale, max_abs(ctmu))
        cqq, cq_inf, cqv = 0.0, 0.0, 0.0
        for i in range(m):
            s, sa, sv = 0.0, 0.0, 0.0
            for j in range(int(span[3, i]), int(span[4, i])):
                a = abs(cq[i, j])
                s += a * abs(q1[j])
                sv += a * abs(v1[j])
                sa = max(sa, a)
            cqq = max(cqq, s)
            cq_inf = max(cq_inf, sa)
            cqv = max(cqv, sv)
        c_scale = max(cqq, cq_inf * constraints[8], _TINY)
        if by_velocity:                 # (βΔt/γ)(Φ_q v1 + Φ_t): a length, like Φ
            c_scale = max(c_scale, cqv / c_v, max_abs(phi_t) / c_v)
            for i in range(m):
                s = 0.0
                for c in range(int(span[3, i]), int(span[4, i])):
                    s += cq[i, c] * v1[c]
                    if fpos[c] >= 0:    # the border, on a zeroed matrix: adds are sets
                        _madd(mat, fpos, nf + i, fpos[c], cq[i, c] + cv[i, c] / c_v)
                res[nf + i] = (s + phi_t[i]) / c_v
        else:
            for i in range(m):
                res[nf + i] = phi[i]
                for c in range(int(span[3, i]), int(span[4, i])):
                    if fpos[c] >= 0:
                        _madd(mat, fpos, nf + i, fpos[c], cq[i, c])
        for i in range(m):
            for c in range(int(span[3, i]), int(span[4, i])):
                if fpos[c] >= 0:
                    _madd(mat, fpos, fpos[c], nf + i, cq[i, c])
        err_c = max_abs(res[nf:]) / (ctol * c_scale)
    for i in range(nf):
        res[i] = r[free[i]]
    err = max(max_abs(res[:nf]) / (rtol * max(scale, _TINY)), err_c)
    if mat[mat.size - 1] != 0.0:        # an entry outside the Newton pattern: the step goes to Python
        ws[8][0] = 1
    return err if all_finite(res) else np.nan


@numba.njit(cache=True)
def _run_newmark(packed, q_start, v_start, acc_start, pseudo_start, t, hs, qp, vp, ap, table, pres, free, fpos,
                 lam_start, reaction_start, have_reaction, am, af, beta, gamma, by_velocity, rheonomic, rtol, ctol,
                 max_iterations, line_search, work, first_step, record_every, n_steps):
    """Steps of :meth:`~skfem_flex.schemes.integrators.Newmark.step` through the Newton core; as :func:`_run`.

    ``table`` row 0 holds the functions of time at the chunk's start time, row k + 1 at step k's end."""
    mass, frames, frame_off, maps, gravity, constraints, bodies, loads, strain, plan = packed
    n, ns, npr, m = q_start.size, hs.size, pres.size, constraints[7]
    records = _mechanism_records(packed, n, npr, record_count(first_step, ns, record_every, n_steps))
    its_total = 0
    nf = free.size
    ws = _chunk_workspace(packed, n, nf)
    wn = ws[2]
    dq_base, dq, q1, v1, r, ext = wn[_DQ_BASE], wn[_DQ], wn[_Q1], wn[_V1], wn[_R], wn[_EXT]
    a1, acc1 = wn[_Z], wn[_RATIO]
    phi_t = ws[3][1]
    cv = np.zeros((m, n))
    q, v, acc, pseudo = q_start.copy(), v_start.copy(), acc_start.copy(), pseudo_start.copy()
    lam, reaction = lam_start.copy(), reaction_start.copy()
    # the loads and Φ_t at the chunk's start (the work of a step uses both ends)
    ext0 = np.zeros(n)
    _add_loads(maps, loads, q, v, table[0], 0.0, 0.0, wn[_DZ], ext0, ws[1], fpos, ws)
    phit0 = np.zeros(m)
    if rheonomic:
        _constraint_terms_at(maps, constraints, q, v, np.zeros(m), table[0], ws[1], fpos, ws, cv)
        phit0[:] = phi_t
    sc = np.array([0.0, am, af, beta, gamma, rtol, ctol])
    kk = np.zeros(1, dtype=np.int64)
    system = (packed, (q, v, pseudo, acc, free, fpos, sc, by_velocity, vp, ap, pres, table, kk, cv), ws)
    i_rec = np.int64(0)                 # not the literal 0: the record helpers compile once, for int64
    for k in range(ns):
        h = hs[k]
        sc[0] = h
        kk[0] = k
        dq_base[:] = 0.0
        for i in range(npr):
            dq_base[pres[i]] = qp[k, i] - q[pres[i]]
        x = np.empty(nf + m)
        x_scale = 0.0
        for i in range(nf):
            x[i] = h * v[free[i]] + 0.5 * h * h * acc[free[i]]
            x_scale = max(x_scale, abs(q[free[i]]))
        for i in range(m):
            x[nf + i] = h * lam[i]
        state = newton_start(x, x_scale, max_iterations, line_search)
        status = EVALUATE
        ws[8][0] = 0
        while status < 0:               # do what the Newton core asks; its rules are all in the core
            if status == EVALUATE:
                err = _evaluate_newmark(system, state[2])
                if ws[8][0]:
                    status = NONFINITE_RESIDUAL
                    break
                status = newton_evaluated(state, err)
            else:
                y, regular = _solve(plan[5], system)
                status = newton_solved(state, y, regular)
        its = state[4][0]
        if status == OK and not (all_finite(q1) and all_finite(v1)):
            status = NONFINITE_RESIDUAL
        if status != OK:
            return (status, k, t, q, v, acc, pseudo, lam, reaction, work, its_total, i_rec) + records
        # work of the loads (trapezoidal in time), of the prescribed laws and of the rheonomic constraints
        w = 0.0
        for i in range(n):
            w += dq[i] * 0.5 * (ext0[i] + ext[i])
        for i in range(npr):
            react = r[pres[i]] / h
            prev = reaction[i] if k > 0 or have_reaction else react
            w += dq[pres[i]] * 0.5 * (prev + react)
            reaction[i] = react
        if rheonomic:
            s0, s1 = 0.0, 0.0
            for i in range(m):
                s0 += lam[i] * phit0[i]
                s1 += state[0][nf + i] / h * phi_t[i]
            w += 0.5 * h * (s0 + s1)
        work += w
        t = t + h
        for i in range(n):
            q[i] = q1[i]
            v[i] = v1[i]
            acc[i] = acc1[i]
            pseudo[i] = a1[i]
            ext0[i] = ext[i]
        for i in range(m):
            lam[i] = state[0][nf + i] / h
            phit0[i] = phi_t[i]
        its_total += its
        s = first_step + k
        if is_recorded(s, record_every, n_steps):
            p = _scene_momentum(mass, frames, frame_off, q, v)
            _record_mechanism(packed, records, i_rec, t, q, v, p, work, its, reaction, lam, ws)
            i_rec += 1
    return (OK, ns, t, q, v, acc, pseudo, lam, reaction, work, its_total, i_rec) + records
