r"""Floating-frame bodies (:class:`~skfem_flex.bodies.floating.body.FloatingBeam`, a
:class:`~skfem_flex.bodies.modal.body.ModalBody`, reduced or not): inertia with a mass matrix M(q) that
depends on q, and strain energy.

The arithmetic is the bodies' compiled kernels (:mod:`skfem_flex.bodies.floating.kernel`, on each body's
``compiled_kernel_data()``); this family hands them the context's states and puts their results where
the step wants them (:mod:`skfem_flex.compiled.tasks`):

* TASK_EVAL, energy-momentum (q_a, q_b = q₀, q₁; w_p = 1, w_gk = −Δt, w_gp = Δt, dq1 = 1,
  dv1 = 2/Δt): :func:`~skfem_flex.bodies.floating.kernel.energy_momentum_terms` gives p(q₁, v₁), the
  kinetic discrete gradient g_k, the strain discrete gradient g_p, the round-off floor
  Δt |∂g_p/∂q₁| (|q₀| + |q₁|) and the tangent already in these weights,

  .. math::

      J = \tfrac{2}{Δt} M(q_1) + B(q_1, v_1) - Δt\,∂_{q_1} g_k - 2\,∂_{v_1} g_k + Δt\,∂_{q_1} g_p
        = w_p (∂p/∂q_1 + \tfrac{2}{Δt} ∂p/∂v_1) + w_{gk} (∂g_k/∂q_1 + \tfrac{2}{Δt} ∂g_k/∂v_1)
          + w_{gp} ∂g_p/∂q_1;

* TASK_EVAL, Newmark family (q_a = q_b = q₁, w_p = −w_gk = w_gp = Δt, c_dg = 2):
  :func:`~skfem_flex.bodies.floating.kernel.newmark_terms` gives p ← M(q₁) q̈₁, g_k ← Q_v(q₁, v₁),
  g_p ← ∇V(q₁), |M| terms into ``mterms`` and c_a M + B + K − ∂Q_v/∂q − c_v ∂Q_v/∂v with
  c_a = da1/dq1, c_v = dv1/dq1, which times w_p dq1 is the tangent;
* the consistent start (dq1 = 0, da1 = 1, dv1 = 0): the same residual parts, and the tangent
  w_p da1 M(q₁) exactly (M column by column from :func:`~skfem_flex.bodies.floating.kernel.momentum`,
  which is linear in v);
* TASK_MOMENTUM: p = M(q₁) v₁ into ``p``, (p_x, p_y) = (p[R_x], p[R_y]) and L = R × p_R + p_θ about the
  origin into ``out[1], out[2], out[6]`` (the bodies' ``linear_momentum`` and ``angular_momentum``);
* TASK_ENERGY: the strain energy V(q₁) into ``out[0]``.

Each body's tangent is the data array of its own CSR pattern (``kd.pat_ptr``, ``kd.pat_idx``, handed to
the scene as the family's entries); where each of its entries lands in the Newton matrix's storage
(i·nx + j dense, the slot of the pattern CSR, −1 for a prescribed row or column) is computed once per
scene (:func:`pattern_positions`), so a tangent enters by one indirect add per entry.
"""
from __future__ import annotations

from collections import namedtuple

import numba
import numpy as np

from ...bodies.floating.kernel import FloatingKernelData, energy_momentum_terms, momentum, newmark_terms, \
    potential_energy
from ..abi import context_of, f1, f2, f3, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import positions, storage_of
from ..tasks import SCHEME_EM, TASK_ENERGY, TASK_EVAL, TASK_MOMENTUM
from . import FamilyPack

__all__ = ["NAME", "FORMS", "pack", "kernel", "pattern_positions", "body_fields"]

NAME = "floating-frame bodies"
FORMS = ("floating frame",)

#: the family's own fields before the bodies' (offsets, positions in the Newton storage, their pointers)
_HEAD = 3
#: fields per body: those of FloatingKernelData
_NKD = len(FloatingKernelData._fields)


def body_fields(kd, prefix, flatten):
    """(names, arrays) of a kernel-data named tuple's fields for the family's pools: scalars as 0-d arrays,
    the fields named in ``flatten`` (3-D integer arrays: no view intrinsic reads them) raveled."""
    names, arrays = [], []
    for name, value in zip(kd._fields, kd):
        names.append(f"{prefix}{name}")
        a = np.asarray(value)
        arrays.append(np.ravel(a) if name in flatten else a)
    return names, arrays


def pattern_positions(rows, cols, layout):
    """Where the entries (rows[t], cols[t]) (scene coordinates) of a tangent land in the Newton matrix's
    storage: i·nx + j (dense) or the entry's slot in the pattern (CSR), with (i, j) the free positions;
    −1 where the row or the column is prescribed.

    Parameters
    ----------
    rows, cols : ndarray of int
        Scene coordinates of the entries.
    layout : tuple
        (storage kind, scipy CSR pattern of the bordered Newton matrix, fpos, nx) (:func:`.pack._plan`).

    Returns
    -------
    ndarray of int64
    """
    fpos = layout[2]
    return positions(layout, fpos[np.asarray(rows, dtype=np.int64)], fpos[np.asarray(cols, dtype=np.int64)])


def pack(items, packer):
    """The family's data: each body's FloatingKernelData fields one after another (field names ``b<k>_<name>``,
    after the offsets of the bodies' blocks and the positions of their tangents' entries, set by ``finish``).

    Parameters
    ----------
    items : list of (FloatingKernelData, Body, int)
        Per body its ``compiled_kernel_data()``, the body and the offset of its block in the scene's coordinates.
    packer : Packer

    Returns
    -------
    FamilyPack
        ``entries``: every entry of the bodies' tangent patterns, in scene coordinates.
    """
    names, arrays = ["offs", "pos", "pos_ptr"], [None, None, None]
    offs, rows, cols, ptr = [], [], [], [0]
    for b, (kd, body, off) in enumerate(items):
        nb_names, nb_arrays = body_fields(kd, f"b{b}_", ("map_loc",))
        names += nb_names
        arrays += nb_arrays
        offs.append(off)
        n = int(kd.n)
        rows.append(off + np.repeat(np.arange(n, dtype=np.int64), np.diff(kd.pat_ptr)))
        cols.append(off + np.asarray(kd.pat_idx, dtype=np.int64))
        ptr.append(ptr[-1] + rows[-1].size)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    kind = namedtuple("FloatingFrameData", names)
    arrays[0] = np.asarray(offs, dtype=np.int64)
    arrays[1] = -np.ones(rows.size, dtype=np.int64)
    arrays[2] = np.asarray(ptr, dtype=np.int64)
    data = kind(*arrays)

    def finish(layout):
        return data._replace(pos=pattern_positions(rows, cols, layout))
    return FamilyPack(data=data, count=len(items), entries=(rows, cols), finish=finish)


@numba.njit(cache=True)
def _scatter(mat, pos, data, w):
    """mat[pos[t]] += w data[t] where pos[t] ≥ 0."""
    for t in range(data.size):
        k = pos[t]
        if k >= 0:
            mat[k] += w * data[t]


@numba.njit(cache=True)
def _add(dst, o, src):
    """dst[o + i] += src[i]."""
    for i in range(src.size):
        dst[o + i] += src[i]


@numba.njit(cache=True)
def _bodies(ctx, fam):
    """Every body's part of the context's task (module docstring); ``fam``: the family record."""
    n = ctx.n
    task = ctx.task
    offs, pos_all, ptr = i1(fam, 0), i1(fam, 1), i1(fam, 2)
    q1, v1 = fvec(ctx.q1, n), fvec(ctx.v1, n)
    for b in range(offs.size):
        k = _HEAD + _NKD * b
        dn = f3(fam, k + 30)
        nel, nl = dn.shape[0], dn.shape[2]
        # the body's FloatingKernelData, field by field (its order) from the pools
        kd = FloatingKernelData(
            i1(fam, k)[0], i1(fam, k + 1)[0], i1(fam, k + 2)[0] != 0, f1(fam, k + 3)[0], f1(fam, k + 4)[0],
            f1(fam, k + 5)[0], f1(fam, k + 6)[0], f2(fam, k + 7), f1(fam, k + 8), f1(fam, k + 9),
            i1(fam, k + 10), i1(fam, k + 11), f1(fam, k + 12), i1(fam, k + 13), i1(fam, k + 14), f1(fam, k + 15),
            i1(fam, k + 16), i1(fam, k + 17), f1(fam, k + 18), i1(fam, k + 19), i1(fam, k + 20), f1(fam, k + 21),
            i1(fam, k + 22), i1(fam, k + 23), i1(fam, k + 24), i1(fam, k + 25), i1(fam, k + 26), i1(fam, k + 27),
            i1(fam, k + 28), i1(fam, k + 29), dn, i2(fam, k + 31), f1(fam, k + 32),
            i1(fam, k + 33).reshape(nel, 2 * nl, 2 * nl), i1(fam, k + 34)[0] != 0, f2(fam, k + 35),
            f2(fam, k + 36), f2(fam, k + 37), f2(fam, k + 38), f2(fam, k + 39), f2(fam, k + 40), f2(fam, k + 41),
            i1(fam, k + 42))
        o, nb = offs[b], kd.n
        qb1, vb1 = q1[o:o + nb], v1[o:o + nb]
        if task == TASK_MOMENTUM:
            pb = momentum(kd, qb1, vb1)
            _add(fvec(ctx.p, n), o, pb)
            out = fvec(ctx.out, 7)
            out[1] += pb[0]
            out[2] += pb[1]
            out[6] += qb1[0] * pb[1] - qb1[1] * pb[0] + pb[2]
            continue
        if task == TASK_ENERGY:
            fvec(ctx.out, 7)[0] += potential_energy(kd, qb1)
            continue
        mat = storage_of(ctx)[0]
        pos = pos_all[ptr[b]:ptr[b + 1]]
        if ctx.scheme == SCHEME_EM:
            q0, v0 = fvec(ctx.q0, n), fvec(ctx.v0, n)
            pb, gkb, gpb, data, flb = energy_momentum_terms(kd, q0[o:o + nb], qb1, v0[o:o + nb], vb1, ctx.h)
            _add(fvec(ctx.p, n), o, pb)
            _add(fvec(ctx.gk, n), o, gkb)
            _add(fvec(ctx.gp, n), o, gpb)
            _add(fvec(ctx.floor, n), o, flb)
            _scatter(mat, pos, data, 1.0)
            continue
        # the Newmark family and the consistent start: everything at q1
        dv1, a1, terms = fvec(ctx.dv1, n), fvec(ctx.a1, n), fvec(ctx.terms, n)
        dq1 = ctx.dq1
        c_a, c_v = (ctx.da1 / dq1, dv1[o] / dq1) if dq1 != 0.0 else (ctx.da1, dv1[o])
        ib, gb, qvb, data, mb = newmark_terms(kd, qb1, vb1, a1[o:o + nb], c_a, c_v, terms[o:o + nb])
        _add(fvec(ctx.p, n), o, ib)
        _add(fvec(ctx.gp, n), o, gb)
        _add(fvec(ctx.gk, n), o, qvb)
        _add(fvec(ctx.mterms, n), o, mb)
        if dq1 != 0.0:
            _scatter(mat, pos, data, ctx.w_p * dq1)
            continue
        # Δq fixed (the start): the tangent is w_p da1 M(q1) alone; M by columns, M e_j = p(q1, e_j)
        w = ctx.w_p * ctx.da1
        e = fvec(ctx.scratch, ctx.nscratch)[:nb]
        for i in range(nb):
            e[i] = 0.0
        pp, pi = kd.pat_ptr, kd.pat_idx
        for j in range(nb):
            e[j] = 1.0
            col = momentum(kd, qb1, e)
            e[j] = 0.0
            for i in range(nb):
                t = _entry(pi, pp[i], pp[i + 1], j)
                if t >= 0 and pos[t] >= 0:
                    mat[pos[t]] += w * col[i]


@numba.njit(cache=True, _nrt=False)
def _entry(idx, lo, hi, j):
    """Position of column j among the sorted idx[lo:hi] (a CSR row), or −1."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if idx[mid] < j:
            lo = mid + 1
        elif idx[mid] > j:
            hi = mid
        else:
            return mid
    return -1


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL, TASK_MOMENTUM and TASK_ENERGY."""
    ctx = context_of(ctx_p)
    task = ctx.task
    if task == TASK_EVAL or task == TASK_MOMENTUM or task == TASK_ENERGY:
        _bodies(ctx, family_of(fam_p))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the floating-frame family", nrt=True)
