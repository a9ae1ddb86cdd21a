r"""Elements without a compiled form — a user's own bodies, forces and constraints — inside the compiled loop.

Their kernel is a Python function the loop calls by address (a ``ctypes`` callback), which runs the
elements' own methods (the body and element contracts, ``docs/user_elements.md``) and writes what
:mod:`..tasks` asks through the same compiled helpers every family uses (:func:`add_entries_at`,
:func:`~skfem_flex.compiled.rows.finish_row` through :func:`finish_row_at`): the step equations,
scales and constraint rows stay the schemes' and the rows module's, for Python elements as for
compiled ones. A Python exception is caught in the callback (it cannot cross compiled code), the
step is abandoned (``ctx.status``) and :func:`raise_pending` raises it again in Python.

Items (``(role, element, where)``): ``"inertia"`` (a body whose mass matrix depends on q),
``"potential"`` (a body's strain energy), ``"gravity"`` (gravity on a body that gives no first moment
of its mass; ``where`` = (indices, g)), ``"force"`` (a force element), ``"constraint"`` (``where`` =
(indices, first row)); ``where`` is the global indices of the element's coordinates otherwise.
"""
from __future__ import annotations

import ctypes
import itertools
from typing import NamedTuple

import numba
import numpy as np
import scipy.sparse as sps

from ..abi import context_at, record_view, vector_view
from ..rows import finish_row
from ..storage import add_qq, storage_of
from ..tasks import (ROWS_ACCELERATION, ROWS_VELOCITY, SCHEME_EM, SCHEME_NEWMARK, STATUS_PYTHON_ERROR, TASK_ENERGY,
                     TASK_EVAL, TASK_EVAL_LOADS, TASK_LOADS, TASK_MOMENTUM, TASK_ROWS)
from . import FamilyPack

NAME = "Python elements"
FORMS = ()

_FAMILIES = {}
_KEYS = itertools.count(1)
_PENDING = []


class Data(NamedTuple):
    key: np.ndarray     # (1,) this family's entry in the module's registry


def pack(items, packer):
    """A family of Python elements; ``items`` as in the module docstring."""
    key = next(_KEYS)
    _FAMILIES[key] = list(items)
    couplings, rows = [], []
    for role, element, where in items:
        if role == "constraint":
            idx, row = where
            couplings.append(idx)
            rows += [(r, idx) for r in range(row, row + element.n_equations)]
        elif role == "gravity":
            couplings.append(where[0])
        else:
            couplings.append(where)
    return FamilyPack(data=Data(np.array([key], dtype=np.int64)), count=len(items), couplings=couplings, rows=rows)


def raise_pending():
    """Raise the exception a Python element raised inside the loop (if any)."""
    if _PENDING:
        exc = _PENDING.pop()
        _PENDING.clear()
        raise exc


# ------------------------------------------------------------------ compiled helpers called from Python
@numba.njit(cache=True)
def add_entries_at(address, rows, cols, vals):
    """Add ``vals`` at global coordinate entries (rows, cols) of the Newton matrix of the context at
    ``address``."""
    ctx = context_at(address)
    st = storage_of(ctx)
    for t in range(vals.size):
        add_qq(ctx, st, rows[t], cols[t], vals[t])


@numba.njit(cache=True)
def finish_row_at(address, row, value, phi_t, phi_tt, cols, cq, d, cv):
    """:func:`~skfem_flex.compiled.rows.finish_row` for the context at ``address``."""
    ctx = context_at(address)
    finish_row(ctx, storage_of(ctx), row, value, phi_t, phi_tt, cols, cq, d, cv, cols.size)


# ------------------------------------------------------------------ the callback
class _Context:
    """Numpy views of a context (record fields by name, vectors through their addresses)."""

    _views = {}

    def __init__(self, address):
        self.address = address
        self.rec = record_view(address)

    def __getitem__(self, name):
        return self.rec[name]

    def vec(self, name, n=None):
        addr = int(self.rec[name])
        n = int(self.rec["n"]) if n is None else int(n)
        key = (addr, n)
        view = self._views.get(key)
        if view is None:
            if len(self._views) > 256:
                self._views.clear()
            view = self._views[key] = vector_view(addr, n)
        return view


def _entries(block, rows, cols, scale):
    """(global rows, global cols, values) of scale · block (dense, sparse or None) on index sets."""
    if block is None or scale == 0.0:
        return None
    c = sps.coo_matrix(block)
    if c.nnz == 0:
        return None
    return (np.asarray(rows)[c.row].astype(np.int64), np.asarray(cols)[c.col].astype(np.int64),
            (scale * c.data).astype(float))


def _add(ctx, *parts):
    for p in parts:
        if p is not None:
            add_entries_at(ctx.address, p[0], p[1], p[2])


def _columns(block, idx, factor):
    """block · diag(factor[idx]) (dense or sparse)."""
    if block is None:
        return None
    f = factor[idx]
    return block @ sps.diags(f) if sps.issparse(block) else np.asarray(block) * f[None, :]


def _times(ctx):
    """(time of the loads, time of the constraint rows) of this evaluation, s."""
    return float(ctx["te"]), float(ctx["t1"])


def _inertia(ctx, body, idx):
    task = ctx["task"]
    q1, v1 = ctx.vec("q1")[idx], ctx.vec("v1")[idx]
    if task == TASK_MOMENTUM:
        ctx.vec("p")[idx] += body.momentum(q1, v1)
        _momenta(ctx, body, q1, v1)
        return
    if task != TASK_EVAL or ctx["scheme"] not in (SCHEME_EM, SCHEME_NEWMARK):
        return
    dq1, dv1 = float(ctx["dq1"]), ctx.vec("dv1")
    w_p, w_gk = float(ctx["w_p"]), float(ctx["w_gk"])
    mass = body.mass_matrix(q1)
    if ctx["scheme"] == SCHEME_EM:
        q0, v0 = ctx.vec("q0")[idx], ctx.vec("v0")[idx]
        ctx.vec("p")[idx] += body.momentum(q1, v1)
        g, g_q, g_v = body.kinetic_discrete_gradient(q0, q1, v0, v1)
        ctx.vec("gk")[idx] += g
        _add(ctx, _entries(body.momentum_jacobian(q1, v1), idx, idx, w_p * dq1),
             _entries(_columns(mass, idx, dv1), idx, idx, w_p), _entries(g_q, idx, idx, w_gk * dq1),
             _entries(_columns(g_v, idx, dv1), idx, idx, w_gk))
    else:
        a1 = ctx.vec("a1")[idx]
        ctx.vec("p")[idx] += np.asarray(mass @ a1).ravel()
        qv, qv_q, qv_v = body.quadratic_velocity_force(q1, v1)
        ctx.vec("gk")[idx] += qv
        _add(ctx, _entries(body.momentum_jacobian(q1, a1), idx, idx, w_p * dq1),
             _entries(mass, idx, idx, w_p * float(ctx["da1"])), _entries(qv_q, idx, idx, w_gk * dq1),
             _entries(_columns(qv_v, idx, dv1), idx, idx, w_gk))
        terms = ctx.vec("terms")[idx]
        ctx.vec("mterms")[idx] += np.asarray(abs(mass) @ terms).ravel()


def _momenta(ctx, body, q, v):
    out = ctx.vec("out", 7)
    lin, ang = body.linear_momentum(q, v), body.angular_momentum(q, v)
    if lin is not None:
        lin = np.ravel(lin)
        out[1:1 + lin.size] += lin
    if ang is not None:
        ang = np.ravel(ang)
        if ang.size == 1:
            out[6] += ang[0]
        else:
            out[4:4 + ang.size] += ang


def _conservative(ctx, idx, energy, gradient, hessian, discrete_gradient):
    """A potential's part of TASK_EVAL and TASK_ENERGY from its Python methods."""
    task = ctx["task"]
    if task == TASK_ENERGY:
        ctx.vec("out", 7)[0] += energy(ctx.vec("q1")[idx])
        return
    if task != TASK_EVAL:
        return
    qa, qb = ctx.vec("qa")[idx], ctx.vec("qb")[idx]
    w = float(ctx["w_gp"]) * float(ctx["dq1"])
    if ctx["qa"] == ctx["qb"]:          # equal end points: the gradient and the Hessian
        ctx.vec("gp")[idx] += gradient(qb)
        _add(ctx, _entries(hessian(qb), idx, idx, w))
        return
    g, g_q = discrete_gradient(qa, qb)
    ctx.vec("gp")[idx] += g
    w *= float(ctx["c_dg"])
    _add(ctx, _entries(g_q, idx, idx, w))
    if g_q is not None:
        ctx.vec("floor")[idx] += np.asarray(abs(w * g_q) @ (np.abs(qa) + np.abs(qb))).ravel()


def _load(ctx, element, idx):
    task = ctx["task"]
    if task not in (TASK_EVAL_LOADS, TASK_LOADS):
        return
    te, _ = _times(ctx)
    out = element.generalized_force(ctx.vec("qe")[idx], ctx.vec("ve")[idx], te)
    if out is None:
        return
    f, f_q, f_v = out
    ctx.vec("ext")[idx] += f
    if task == TASK_EVAL_LOADS:
        w = float(ctx["w_ext"])
        _add(ctx, _entries(f_q, idx, idx, w * float(ctx["dqe"])), _entries(_columns(f_v, idx, ctx.vec("dve")), idx,
                                                                            idx, w))


def _constraint(ctx, c, idx, row):
    task = ctx["task"]
    if task not in (TASK_EVAL, TASK_ROWS):
        return
    _, t1 = _times(ctx)
    q1, v1 = ctx.vec("q1")[idx], ctx.vec("v1")[idx]
    value = np.atleast_1d(c.value(q1, t1))
    cq = _dense(c.jacobian(q1, t1), c.n_equations, idx.size)
    phit = np.atleast_1d(c.time_derivative(q1, t1))
    m = c.n_equations
    if task == TASK_EVAL:
        qa, qb = ctx.vec("qa")[idx], ctx.vec("qb")[idx]
        mu = ctx.vec("mu", ctx["m"])[row:row + m]
        w = float(ctx["w_mu"]) * float(ctx["dq1"])
        if ctx["qa"] == ctx["qb"]:
            d = cq
            _add(ctx, _entries(c.hessian_product(qb, mu, t1), idx, idx, w))
        else:
            d = _dense(c.discrete_gradient(qa, qb, t1), m, idx.size)
            _add(ctx, _entries(c.discrete_gradient_jacobian(qa, qb, mu, t1), idx, idx, w * float(ctx["c_dg"])))
        level = ctx["rows"]
        cv = _dense(c.velocity_jacobian(q1, v1, t1), m, idx.size) if level in (ROWS_VELOCITY, ROWS_ACCELERATION) \
            else np.zeros((m, idx.size))
        if level == ROWS_VELOCITY:
            # the velocity row Φ_q v + Φ_t: its q-derivative also holds Φ_qt (a driver whose Φ_t depends on q)
            cv = cv + _dense(c.time_derivative_jacobian(q1, t1), m, idx.size)
        tt = np.atleast_1d(c.time_terms(q1, v1, t1)) if level == ROWS_ACCELERATION else np.zeros(m)
    else:
        d, cv, tt = cq, np.zeros((m, idx.size)), np.zeros(m)
    cols = np.asarray(idx, dtype=np.int64)
    for i in range(m):
        # Φ_tt of the acceleration rows: the explicit-time part 2 Φ_qt v + Φ_tt
        finish_row_at(ctx.address, row + i, float(value[i]), float(phit[i]), float(tt[i]), cols,
                      np.ascontiguousarray(cq[i]), np.ascontiguousarray(d[i]), np.ascontiguousarray(cv[i]))


def _dense(a, m, n):
    a = a.toarray() if sps.issparse(a) else np.asarray(a, dtype=float)
    return a.reshape(m, n)


def _gravity(ctx, body, idx, g):
    _conservative(ctx, idx, lambda q: body.gravity_potential(q, g)[0], lambda q: body.gravity_potential(q, g)[1],
                  lambda q: body.gravity_potential(q, g)[2], lambda q0, q1: body.gravity_discrete_gradient(q0, q1, g))


def _run(ctx, items):
    for role, element, where in items:
        if role == "inertia":
            _inertia(ctx, element, where)
        elif role == "potential":
            _conservative(ctx, where, element.potential_energy, element.potential_gradient, element.potential_hessian,
                          element.potential_discrete_gradient)
        elif role == "gravity":
            _gravity(ctx, element, where[0], where[1])
        elif role == "force":
            if element.conservative:
                _conservative(ctx, where, element.potential_energy, element.potential_gradient,
                              element.potential_hessian, element.potential_discrete_gradient)
            else:
                _load(ctx, element, where)
        elif role == "constraint":
            _constraint(ctx, element, where[0], where[1])


def _callback(ctx_address, fam_address):
    ctx = _Context(ctx_address)
    try:
        fam = vector_view(fam_address, 9, np.int64)
        key = int(vector_view(fam[4], 1, np.int64)[0])
        _run(ctx, _FAMILIES[key])
    except BaseException as exc:        # nothing may cross the compiled loop: kept and raised in Python
        _PENDING.append(exc)
        ctx.rec["status"] = STATUS_PYTHON_ERROR


_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)(_callback)


class _Kernel:
    address = ctypes.cast(_CALLBACK, ctypes.c_void_p).value


def kernel():
    """The callback (an object with the ``address`` the loop calls)."""
    return _Kernel
