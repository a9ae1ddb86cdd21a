r"""Geometrically exact beams (:class:`~skfem_flex.bodies.exact.body.ExactBeam`): their strain energy.

Their inertia is constant (the scheme's own mass matrix) and their section angles are Cayley coordinates,
whose rows the energy-momentum step scales itself; this family adds only the strain energy, by the
beams' compiled kernels (:mod:`skfem_flex.bodies.exact.kernel`, on each body's ``compiled_strain_data()``):

* TASK_EVAL: g_p ← D_V(q_a, q_b) (:func:`~skfem_flex.bodies.exact.kernel.potential_discrete_gradient`:
  the exact discrete gradient, g · (q_b − q_a) = V(q_b) − V(q_a); at q_a = q_b the gradient), the tangent
  w_gp c_dg dq1 ∂D_V/∂q_b (energy-momentum: Δt ∂g/∂q₁; Newmark: 2Δt × ½ ∇²V) and the round-off floor
  w_gp c_dg dq1 |∂D_V/∂q_b| (|q_a| + |q_b|). A folded element or a nodal turn |Δψ| ≥ MAX_INCREMENT in the
  step sets ``ctx.status`` = STATUS_REFUSED (the step is handed back, and Python raises or halves it);
* TASK_ENERGY: V(q₁) into ``out[0]``.

The tangent is the data of the beam's CSR pattern (``kd.pat_ptr``, ``kd.pat_idx``: the union of its
element blocks, handed to the scene as the family's entries), added through positions in the Newton
matrix's storage fixed once per scene (:func:`.floating_frame.pattern_positions`).
"""
from __future__ import annotations

from collections import namedtuple

import numba
import numpy as np

from ...bodies.exact.kernel import OK, ExactKernelData, discrete_gradient_terms, potential_energy
from ..abi import context_of, f1, f2, f3, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..storage import storage_of
from ..tasks import STATUS_REFUSED, TASK_ENERGY, TASK_EVAL
from . import FamilyPack
from .floating_frame import body_fields, pattern_positions

__all__ = ["NAME", "FORMS", "pack", "kernel", "pack_strain_bodies", "add_strain_terms"]

NAME = "exact beams"
FORMS = ("exact beam",)

_HEAD = 3
_NKD = len(ExactKernelData._fields)


def pack(items, packer):
    """The family's data: each beam's ExactKernelData fields one after another (``b<k>_<name>``), after the
    offsets of the beams' blocks and the positions of their tangents' entries (set by ``finish``).

    Parameters
    ----------
    items : list of (ExactKernelData, ExactBeam, int)
        Per beam its ``compiled_strain_data()``, the beam and the offset of its block.
    packer : Packer

    Returns
    -------
    FamilyPack
        ``entries``: every entry of the beams' tangent patterns (their element blocks), in scene coordinates.
    """
    return pack_strain_bodies(items, ("map_el",), "ExactBeamData")


def pack_strain_bodies(items, flatten, data_name):
    """The data of a family of bodies whose strain-energy tangent is a CSR pattern (``kd.n``, ``kd.pat_ptr``,
    ``kd.pat_idx``): the offsets of their blocks, the positions of their entries in the Newton matrix's
    storage (set by ``finish``), then each body's kernel-data fields (``b<k>_<name>``, the ``flatten`` ones
    raveled). Shared by the planar and the spatial exact beams."""
    names, arrays = ["offs", "pos", "pos_ptr"], [None, None, None]
    offs, rows, cols, ptr = [], [], [], [0]
    for b, (kd, body, off) in enumerate(items):
        nb_names, nb_arrays = body_fields(kd, f"b{b}_", flatten)
        names += nb_names
        arrays += nb_arrays
        offs.append(off)
        n = int(np.asarray(kd.n).ravel()[0])
        rows.append(off + np.repeat(np.arange(n, dtype=np.int64), np.diff(kd.pat_ptr)))
        cols.append(off + np.asarray(kd.pat_idx, dtype=np.int64))
        ptr.append(ptr[-1] + rows[-1].size)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    arrays[0] = np.asarray(offs, dtype=np.int64)
    arrays[1] = -np.ones(rows.size, dtype=np.int64)
    arrays[2] = np.asarray(ptr, dtype=np.int64)
    data = namedtuple(data_name, names)(*arrays)

    def finish(layout):
        return data._replace(pos=pattern_positions(rows, cols, layout))
    return FamilyPack(data=data, count=len(items), entries=(rows, cols), finish=finish)


@numba.njit(cache=True)
def add_strain_terms(ctx, o, g, data, fl, pos, first):
    """Add a body's discrete gradient g (into g_p), its floor and its tangent (CSR data, whose entry t lands
    at ``pos[first + t]`` of the Newton matrix's storage, −1: nowhere), weighted w_gp c_dg dq1; ``o``: the
    offset of the body's block."""
    n = ctx.n
    gp, floor = fvec(ctx.gp, n), fvec(ctx.floor, n)
    w = ctx.w_gp * ctx.c_dg * ctx.dq1
    for a in range(g.size):
        gp[o + a] += g[a]
        floor[o + a] += w * fl[a]
    if w != 0.0:
        mat = storage_of(ctx)[0]
        for t in range(data.size):
            p = pos[first + t]
            if p >= 0:
                mat[p] += w * data[t]


@numba.njit(cache=True)
def _beams(ctx, fam):
    """Every beam's part of TASK_EVAL or TASK_ENERGY (module docstring); ``fam``: the family record."""
    n = ctx.n
    offs, pos_all, ptr = i1(fam, 0), i1(fam, 1), i1(fam, 2)
    for b in range(offs.size):
        k = _HEAD + _NKD * b
        ed = i2(fam, k + 1)
        ne, nloc = ed.shape[0], ed.shape[1]
        # the beam's ExactKernelData, field by field (its order) from the pools
        kd = ExactKernelData(
            i1(fam, k)[0], ed, f3(fam, k + 2), f3(fam, k + 3), f2(fam, k + 4), f1(fam, k + 5)[0],
            f1(fam, k + 6)[0], f1(fam, k + 7)[0], f1(fam, k + 8)[0], f1(fam, k + 9)[0], f1(fam, k + 10)[0],
            f1(fam, k + 11)[0], i1(fam, k + 12), i1(fam, k + 13), i1(fam, k + 14),
            i1(fam, k + 15).reshape(ne, nloc, nloc))
        o, nb = offs[b], kd.n
        if ctx.task == TASK_ENERGY:
            fvec(ctx.out, 7)[0] += potential_energy(kd, fvec(ctx.q1, n)[o:o + nb])
            continue
        qa, qb = fvec(ctx.qa, n), fvec(ctx.qb, n)
        status, g, data, fl = discrete_gradient_terms(kd, qa[o:o + nb], qb[o:o + nb])
        if status != OK:
            ctx.status = STATUS_REFUSED
            return
        add_strain_terms(ctx, o, g, data, fl, pos_all, ptr[b])


#: the driver's :func:`refusal_error` looks at the refused trial end state (q_1, v_1, t_1)
REFUSAL_STATE = "end"


def refusal_error(scene, q, v, t):
    """The error the exact beams' own methods raise at the state this family refused (an element folded
    inside out: :class:`~skfem_flex.bodies.ElementInversionError`, naming the body and the element), or None.

    Parameters
    ----------
    scene : Scene
    q, v : ndarray
        The refused trial coordinates and velocities (m, rad; m/s, rad/s).
    t : float
        Its time, s.
    """
    for b in scene.bodies:
        if not b.has_potential or getattr(b, "compiled_strain_data", None) is None:
            continue
        try:
            b.potential_gradient(np.asarray(q[scene.slice(b)], dtype=float))
        except ValueError as exc:
            return exc
    return None


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL and TASK_ENERGY."""
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ENERGY:
        _beams(ctx, family_of(fam_p))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the exact-beam family", nrt=True)
