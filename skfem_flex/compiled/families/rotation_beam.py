r"""Spatial geometrically exact beams with rotation-interpolated two-node elements
(:class:`~skfem_flex.bodies.exact.spatial_body.SpatialExactBeam` with ``interpolation="rotations"``): their
strain energy.

Their inertia is constant (the scheme's own mass matrix) and their rigidity rows are quadratic constraint
rows; this family adds only the strain energy, by :mod:`skfem_flex.bodies.exact.rotation_kernel` (on each
body's ``compiled_strain_data()``), the same kernel the Python path calls:

* TASK_EVAL: g_p ← the exact discrete gradient D_V(q_a, q_b) (at q_a = q_b the gradient), the tangent
  w_gp c_dg dq1 ∂D_V/∂q_b and the round-off floor w_gp c_dg dq1 Σ abs(∂D_V/∂q_b) (abs(q_a) + abs(q_b));
  when the matrix is not used (``ctx.fresh`` = 0), g_p alone;
* TASK_ENERGY: V(q₁) into ``out[0]``.

Where an element of the step has turned half a turn (its rotation vector undefined), the kernel refuses the
step (``STATUS_REFUSED``); the driver then asks :func:`refusal_error` (the exact-beam family's: the beams'
own methods at the refused state) for the error to raise or to halve the step on.

The tangent is the data of the beam's CSR pattern (the union of its element blocks), added through
positions in the Newton matrix's storage fixed once per scene (:func:`.floating_frame.pattern_positions`).

Each beam's :class:`~skfem_flex.bodies.exact.rotation_kernel.RotationWork` (its results and temporaries) is
packed with its data: the kernel allocates nothing and is compiled without numba's reference counting (the
kernel module's docstring says why).
"""
from __future__ import annotations

from collections import namedtuple

import numba

from ...bodies.exact.rotation_kernel import (RotationKernelData, RotationWork, discrete_gradient_terms_into,
                                             potential_energy_into, rotation_work)
from ..abi import context_of, f1, f2, f3, family_of, fvec, i1, i2
from ..registry import compiled_kernel
from ..tasks import STATUS_REFUSED, TASK_ENERGY, TASK_EVAL
from .exact_beam import REFUSAL_STATE, add_strain_terms, pack_strain_bodies, refusal_error

__all__ = ["NAME", "FORMS", "pack", "kernel", "REFUSAL_STATE", "refusal_error"]

NAME = "rotation-interpolated spatial beams"
FORMS = ("rotation beam",)
#: an evaluation whose matrix is not used (ctx.fresh = 0) forms g alone, neither the tangent nor the floor
#: (about half of the work): the loop then checks an update's residual alone (:func:`..loop.run_steps`, ``lazy``)
RESIDUAL_ONLY = True

_HEAD = 3
_NKD = len(RotationKernelData._fields)
#: fields per beam: those of RotationKernelData, then those of its RotationWork
_NREC = _NKD + len(RotationWork._fields)
_Record = namedtuple("RotationBeamRecord", RotationKernelData._fields + RotationWork._fields)


def pack(items, packer):
    """The family's data: each beam's RotationKernelData fields one after another (``b<k>_<name>``), after
    the offsets of the beams' blocks and the positions of their tangents' entries (set by ``finish``).

    Parameters
    ----------
    items : list of (RotationKernelData, SpatialExactBeam, int)
        Per beam its ``compiled_strain_data()``, the beam and the offset of its block; a new
        :class:`~skfem_flex.bodies.exact.rotation_kernel.RotationWork` is packed after its fields.
    packer : Packer
    """
    return pack_strain_bodies([(_Record(*kd, *rotation_work(kd)), body, off) for kd, body, off in items], (),
                              "RotationBeamData")


@numba.njit(cache=True, _nrt=False, inline="always")
def _work(fam, k):
    """The beam's RotationWork from the pools (its order)."""
    return RotationWork(f1(fam, k), f1(fam, k + 1), f1(fam, k + 2), f2(fam, k + 3), f2(fam, k + 4), f1(fam, k + 5),
                        f1(fam, k + 6), f3(fam, k + 7), f2(fam, k + 8), f3(fam, k + 9), f3(fam, k + 10),
                        f2(fam, k + 11), f2(fam, k + 12), f2(fam, k + 13), f1(fam, k + 14), f2(fam, k + 15),
                        f2(fam, k + 16), f1(fam, k + 17), f1(fam, k + 18), f2(fam, k + 19), f3(fam, k + 20),
                        f1(fam, k + 21), f2(fam, k + 22), f3(fam, k + 23), f3(fam, k + 24), f3(fam, k + 25),
                        f3(fam, k + 26), f3(fam, k + 27), f3(fam, k + 28), f2(fam, k + 29), f2(fam, k + 30),
                        f1(fam, k + 31))


@numba.njit(cache=True, _nrt=False, inline="always")
def _beams(ctx, fam):
    """Every beam's part of TASK_EVAL or TASK_ENERGY (module docstring); ``fam``: the family record."""
    offs, pos_all, ptr = i1(fam, 0), i1(fam, 1), i1(fam, 2)
    for b in range(offs.size):
        k = _HEAD + _NREC * b
        kd = RotationKernelData(i1(fam, k), i2(fam, k + 1), f1(fam, k + 2), f1(fam, k + 3), f1(fam, k + 4),
                                i1(fam, k + 5), i1(fam, k + 6), i1(fam, k + 7))
        wk = _work(fam, k + _NKD)
        o, nb = offs[b], kd.n[0]
        if ctx.task == TASK_ENERGY:
            fvec(ctx.out, 7)[0] += potential_energy_into(kd, wk, fvec(ctx.q1 + 8 * o, nb))
            continue
        # an update's check (its matrix not used): g alone, no tangent and no floor (.loop.run_steps)
        residual = ctx.fresh == 0
        if not discrete_gradient_terms_into(kd, wk, fvec(ctx.qa + 8 * o, nb), fvec(ctx.qb + 8 * o, nb), residual):
            ctx.status = STATUS_REFUSED
            return
        # a residual's data are stale (its floor is zero): none of them is added
        add_strain_terms(ctx, o, wk.g, wk.data[:0 if residual else wk.data.size], wk.floor, pos_all, ptr[b])


def _kernel(ctx_p, fam_p):
    """The family's kernel (signature of :mod:`..abi`): TASK_EVAL and TASK_ENERGY."""
    ctx = context_of(ctx_p)
    if ctx.task == TASK_EVAL or ctx.task == TASK_ENERGY:
        _beams(ctx, family_of(fam_p))


def kernel():
    """The compiled kernel (from the cache, or compiled now)."""
    return compiled_kernel(_kernel, "the rotation-interpolated spatial-beam family")
