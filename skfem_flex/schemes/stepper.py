r"""Steps of a scene under a scheme on the compiled core, from Python: the one driver every run uses.

A :class:`Stepper` holds what a run keeps from chunk to chunk — the workspace (:mod:`skfem_flex.compiled.workspace`),
the scheme's data record, the solver's record and the Newton core's arrays — and offers

* :meth:`Stepper.start` — the consistent acceleration, multipliers and prescribed forces of a state;
* :meth:`Stepper.advance` — many steps in one compiled call, recorded as asked;
* :meth:`Stepper.evaluate` — one evaluation of the step's residual and Newton matrix at given unknowns
  (tests, finite-difference checks of element kernels).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numba
import numpy as np
import scipy.sparse as sps

from ..compiled import solvers
from ..compiled.abi import FAMILY, Fields
from ..compiled.ahead import compile_units
from ..compiled.loop import (NewtonArrays, Records, entry_types, evaluate_once, record_at, run_steps,
                             start_state)
from ..compiled.pack import packed_scene, time_table
from ..compiled.registry import Unit, compiled_function, planning
from ..compiled.sparse_solver import sparse_solver
from ..compiled.storage import DENSE
from ..compiled.tasks import (PHASE_EVALUATE, PHASE_PREDICT, STATUS_MISSED, STATUS_OK, STATUS_PYTHON_ERROR,
                              STATUS_REFUSED)
from ..compiled.workspace import Workspace
from ..errors import ConvergenceError
from ..numerics.band_plans import solve_work
from ..numerics.sparse_lu import SECONDS_PER_CALL, SECONDS_PER_ENTRY, static_lu_plan

__all__ = ["Stepper", "Chunk", "units", "STATIC_LU", "STATIC_LU_GAIN"]

#: the name of the static-pivot sparse LU solver (:meth:`Stepper.plan_sparse_lu`)
STATIC_LU = "sparse LU (static pivots)"


@dataclass
class Chunk:
    """What :meth:`Stepper.advance` returns: the status (``numerics.newton`` codes, or REFUSED), the steps
    done, the records written (``records`` arrays, first ``n_records`` rows valid), Newton iterations."""

    status: int
    steps: int
    n_records: int
    iterations: int
    records: Records


_READY = set()
_SOLVERS = {"dense": solvers.dense_solver, "bordered band": solvers.bordered_band_solver,
            "bordered band (CSR)": solvers.csr_bordered_band_solver, "sparse (SuperLU)": sparse_solver,
            STATIC_LU: solvers.static_lu_solver}
#: the solvers the static-pivot LU can replace, with the kind its kernel falls back to
_STATIC_LU_FALLBACK = {"dense": 0, "bordered band": 1, "bordered band (CSR)": 2}
#: the static-pivot LU replaces the scene's solver when its modeled time is below this share of that solver's
#: (the dense and static-LU models are within about 15 % of measured solves, the band's within 25 %:
#: examples/calibrate_dense_solve.py)
STATIC_LU_GAIN = 0.85


#: modeled time of a band solve per multiply-add of its work model (band_plans.solve_work), s, and per call: a
#: fit to the Newton matrices of eight scenes (24 to 460 unknowns; within 25 % of each, measured by
#: ``python examples/calibrate_dense_solve.py``; the per-call 2e-6 s of before overestimated the small bands of
#: the planar beams 1.6 to 2 times)
SECONDS_PER_SOLVE_WORK, SECONDS_PER_SOLVE = 1e-10, 9e-7
#: modeled time of a dense LAPACK solve (getrf and getrs, with the copy of its right-hand side) of n unknowns:
#: DENSE_SOLVE_SECONDS (n / SMALL_DENSE)^DENSE_SOLVE_EXPONENT, s. At these sizes LAPACK's time grows far slower
#: than n³ (its unblocked kernels and call overhead): measured by ``python examples/calibrate_dense_solve.py``
#: (2.2, 4.2, 8.3, 13, 31 µs at n = 24, 33, 50, 64, 100 on the benchmark machine); the work model above
#: underestimated it by a quarter at n ≈ 30 to 60, where it decides whether the static-pivot LU pays.
DENSE_SOLVE_SECONDS, DENSE_SOLVE_EXPONENT = 2.2e-6, 1.85


def modeled_solve_seconds(nx, plan, dense_storage):
    """Modeled time of one solve of the scene's solver, s: the dense LAPACK fit above without a band ``plan``,
    else the band's work model (:func:`~skfem_flex.numerics.band_plans.solve_work`)."""
    if plan is None:
        return DENSE_SOLVE_SECONDS * (nx / solvers.SMALL_DENSE) ** DENSE_SOLVE_EXPONENT
    return SECONDS_PER_SOLVE_WORK * solve_work(nx, plan, dense_storage) + SECONDS_PER_SOLVE


def units(packed, scheme):
    """The compiled units (:class:`~skfem_flex.compiled.registry.Unit`) a run of the packed scene under
    ``scheme`` needs, roughly the largest first: the allocating kernels, then the scheme's step, the time
    loop, the element families, the recorder, the consistent start, the solver, the start's driver."""
    from .newmark import start_kernel
    with planning() as step:
        scheme.kernel()
    with planning() as families:
        for module, _, _ in packed.families:
            module.kernel()
    with planning() as rest:
        start_kernel()
        _SOLVERS[packed.solver]()
    types = entry_types()
    loop = [Unit("function", run_steps.__module__, name, what, argtypes=types[name])
            for name, what in (("run_steps", "the time loop"), ("record_at", "the recorder"),
                               ("start_state", "the consistent start's driver"))]
    ordered = step + loop[:1] + families + loop[1:2] + rest + loop[2:]
    # the kernels that allocate (numba's reference counting: the floating-frame and exact-beam families,
    # the band solvers) are the largest to compile, 7-15 s each: first, so that neither process is left
    # with one of them at the end while the other waits
    return [u for u in ordered if u.nrt] + [u for u in ordered if not u.nrt]


def _boundaries(t0, hs):
    """t0 and the ends of steps of sizes hs from it: (hs.size + 1,)."""
    return float(t0) + np.concatenate([[0.0], np.cumsum(np.asarray(hs, dtype=float))])


def _call(fn, what, *args):
    """``fn(*args)``, compiled first (with a notice) if the cache does not hold it for these argument types
    (checked once per function and process: every later call has the same types)."""
    if fn not in _READY:
        compiled_function(fn, tuple(numba.typeof(a) for a in args), what)
        _READY.add(fn)
    return fn(*args)


def _plan_fields(plan, lapack):
    if plan is None:
        z = np.zeros(1, dtype=np.int64)
        return solvers.SolverPlan(z, z, np.zeros(2, dtype=np.int64), lapack)
    interior, border, lo, up = plan
    return solvers.SolverPlan(np.asarray(interior, dtype=np.int64), np.asarray(border, dtype=np.int64),
                              np.array([lo, up], dtype=np.int64), lapack)


class Stepper:
    """The compiled run of ``scene`` under ``scheme`` (a scheme object of :mod:`skfem_flex.schemes`)."""

    def __init__(self, scene, scheme, python_only=False):
        self.scene, self.scheme = scene, scheme
        pk = packed_scene(scene, python_only)
        kernel = _SOLVERS.get(pk.solver)
        if kernel is None:
            raise NotImplementedError(f"no compiled solver for {pk.solver!r} storage yet")
        compile_units(units(pk, scheme))
        self.ws = Workspace(scene, scheme.newton, python_only)
        pk = self.packed = self.ws.packed
        # an update's check evaluates only the residual where a family can skip its derivatives (loop.run_steps)
        self.lazy = any(getattr(mod, "RESIDUAL_ONLY", False) for mod, _, _ in pk.families)
        self.lapack_work, self.lapack = solvers.lapack_work(pk.nx)
        self.solver_fields = Fields(_plan_fields(pk.plan, self.lapack))
        self.solver_name = pk.solver
        self.solver = np.zeros(1, dtype=FAMILY)
        self.solver[0] = self.solver_fields.record(kernel().address, -1, 0)
        nx = pk.nx
        self.newton = NewtonArrays.empty(nx)
        self.ws.ctx[0]["x"] = self.newton.x_try.ctypes.data
        self.data = None
        self.record = np.zeros(1, dtype=FAMILY)

    # ------------------------------------------------------------------ the scheme's data
    def load(self, state):
        """Put ``state`` (the scheme's state dataclass) into the scheme's data record."""
        self.data = self.scheme.pack_state(self.packed, state)
        self.ws.bind_state(self.data)
        self.record[0] = self.data.record(self.scheme.kernel().address, -1, 0)

    def state(self, t):
        """The scheme's state now (a new dataclass; arrays copied)."""
        return self.scheme.unpack_state(self.data, t)

    def positions(self):
        """(q, v) now: views of the scheme's data, not copies (read them before the next step)."""
        return self.data.array("q"), self.data.array("v")

    # ------------------------------------------------------------------ start, steps, evaluations
    def pivot(self):
        """Leave the band plan for a factorization with pivoting (dense LU, or SuperLU on CSR storage), once;
        True if it switched. A band plan factorizes its interior (the coordinates) first, without pivoting:
        a coordinate without inertia of its own (a spatial beam's normal director d₃, held by its rigidity
        rows) can make that interior singular, at the start (M alone) or in a step, though the whole
        matrix is regular."""
        pk = self.packed
        if pk.plan is None or getattr(self, "_pivoting", None) is not None:
            return False
        kernel = sparse_solver if pk.storage != DENSE else solvers.dense_solver
        if pk.storage == DENSE:
            compile_units(units(replace(pk, solver="dense"), self.scheme))
        self._pivoting = Fields(_plan_fields(None, self.lapack))
        self.solver[0] = self._pivoting.record(kernel().address, -1, 0)
        self.solver_name = "sparse (SuperLU)" if pk.storage != DENSE else "dense"
        return True

    @property
    def static_lu(self):
        """The static-pivot LU solver's data (:data:`~skfem_flex.compiled.solvers.StaticLUFields` in a
        :class:`~skfem_flex.compiled.abi.Fields`: ``array("state")[1]`` counts its failed solves), or None when
        the run does not use it."""
        return getattr(self, "_static_lu", None) if self.solver_name == STATIC_LU else None

    def plan_sparse_lu(self, t, h):
        """Solve with the static-pivot sparse LU from now on (:mod:`skfem_flex.numerics.sparse_lu`) if it models
        at most :data:`STATIC_LU_GAIN` of the scene's solver's time; its pivots are chosen on the Newton matrix
        of a step of size h (s) from the loaded state at time t, at the scheme's Newton start. True if it
        switched. The earlier solver stays as the fallback of a solve whose pivots fail."""
        pk = self.packed
        kind = _STATIC_LU_FALLBACK.get(self.solver_name)
        if kind is None or pk.nx < solvers.SMALL_DENSE or getattr(self, "_pivoting", None) is not None:
            return False
        dense = pk.storage == DENSE
        pattern = pk.pattern.tocsr()
        pattern.sort_indices()
        # the budget: a share of the scene's solver's modeled time, less the LU's backward-error check
        budget = (STATIC_LU_GAIN * modeled_solve_seconds(pk.nx, pk.plan, dense)
                  - SECONDS_PER_SOLVE_WORK * (2.0 * pk.nx ** 2 if dense else 2.0 * pattern.nnz))
        if SECONDS_PER_ENTRY * pattern.nnz + SECONDS_PER_CALL >= budget:
            return False                # not even the entries of A would pay (the band of a beam)
        try:
            _, sample, _ = self.evaluate(t, h)
        except (AssertionError, ConvergenceError, ValueError):
            return False
        if self.ws.ctx[0]["status"] != STATUS_OK:
            return False
        plan = static_lu_plan(pattern, sample, dense, budget)
        if plan is None:
            return False
        compile_units(units(replace(pk, solver=STATIC_LU), self.scheme))
        self._static_lu = Fields(solvers.static_lu_fields(_plan_fields(pk.plan, self.lapack), plan, kind))
        self.solver[0] = self._static_lu.record(solvers.static_lu_solver().address, -1, 0)
        self.solver_name = STATIC_LU
        return True

    def start(self, t, q, v):
        """(acceleration, λ, prescribed forces) consistent with (q, v) at time t: M q̈ + Φ_qᵀλ = Q + Q_v − ∇V,
        Φ_q q̈ = −∂(Φ_q v)/∂q v − Φ_tt; the prescribed coordinates take their laws' accelerations.

        Raises
        ------
        ValueError
            If the mass/constraint matrix is singular (a coordinate without inertia, redundant constraints).
        """
        from .newmark import start_kernel, start_data
        pk = self.packed
        data = start_data(pk, q, v)
        self.ws.bind_state(data)
        rec = np.zeros(1, dtype=FAMILY)
        rec[0] = data.record(start_kernel().address, -1, 0)
        table = time_table(pk.columns, [float(t)], np.zeros(0), False)
        ok = _call(start_state, "the consistent start's driver", self.ws.ctx, rec, self.solver, table, float(t))
        if not ok and self.pivot():
            ok = _call(start_state, "the consistent start's driver", self.ws.ctx, rec, self.solver, table, float(t))
        self._check_status()
        if self.ws.ctx[0]["status"] == STATUS_REFUSED:
            family, exc = self.refusal(q, v, t)
            raise ValueError(f"the start state is refused by the {family}: " + (
                str(exc) if exc is not None else "an element folds inside out or lost its direction"))
        if not ok:
            raise ValueError("the initial mass/constraint matrix is singular: a coordinate has no inertia, or "
                             "constraints are redundant")
        x = self.newton.x_try
        nf = pk.free.size
        acc = np.zeros(self.scene.n)
        acc[pk.free] = x[:nf]
        if pk.pres.size:
            acc[pk.pres] = table[0, pk.pres_cols + 2]
        lam = x[nf:].copy()
        reaction = data.array("r")[pk.pres].copy() if pk.pres.size else np.zeros(0)
        if self.data is not None:
            self.ws.bind_state(self.data)
        return acc, lam, reaction

    def _records(self, nr):
        pk = self.packed
        return Records.empty(nr, self.scene.n, pk.m, pk.pres.size, pk.probe_maps)

    def record_now(self, t):
        """One record (:class:`~skfem_flex.compiled.loop.Records`) of the loaded state at time t."""
        pk = self.packed
        records = self._records(1)
        table = time_table(pk.columns, [float(t)], np.zeros(0), False)
        self.ws.vectors["q1"][:self.scene.n] = self.data.array("q")
        self.ws.vectors["v1"][:self.scene.n] = self.data.array("v")
        _call(record_at, "the recorder", self.ws.ctx, records, float(t), table)
        self._check_status()
        return records

    def raise_python_error(self):
        """Raise what a Python element raised in the last call, if anything."""
        from ..compiled.families import python_elements
        python_elements.raise_pending()

    def advance(self, t0, hs, recorded, max_iterations, line_search, times=None):
        """Steps of sizes ``hs`` from time t0 (the loaded state); ``recorded[k]``: record step k; ``times``: the
        times of the steps' ends (hs.size), t0 + the sums of ``hs`` by default (a run passes its exact times:
        its results do not depend on how it is cut into chunks)."""
        pk = self.packed
        hs = np.ascontiguousarray(hs, dtype=float)
        if times is None:
            times = _boundaries(t0, hs)
        else:
            times = np.concatenate([[float(t0)], np.asarray(times, dtype=float)])
            if times.size != hs.size + 1:
                raise ValueError(f"times must hold the end of each of the {hs.size} steps, got {times.size - 1}")
        table = time_table(pk.columns, times, hs, self.scheme.mid_point_loads)
        records = self._records(int(np.count_nonzero(recorded)))
        status, steps, n_rec, its = _call(run_steps, "the time loop", self.ws.ctx, self.record, self.solver, hs,
                                          times, np.ascontiguousarray(recorded, dtype=np.bool_), records,
                                          self.newton, int(max_iterations), bool(line_search), table, self.lazy)
        self._check_status()
        return Chunk(int(status), int(steps), int(n_rec), int(its), records)

    def evaluate(self, t0, h, x=None):
        """The scheme's residual (nx,) and Newton matrix (dense (nx, nx) or CSR) at unknowns ``x`` (default: the
        scheme's Newton start) for a step of size h from the loaded state at time t0, and the scaled error."""
        pk = self.packed
        table = time_table(pk.columns, _boundaries(t0, [h]), np.array([float(h)]), self.scheme.mid_point_loads)
        c = self.ws.ctx[0]
        c["h"], c["t"] = float(h), float(t0)
        c["trow"] = table.ctypes.data + 8 * c["ncol"]
        c["status"], c["bad_family"], c["refusal"] = STATUS_OK, -1, 0
        _call(evaluate_once, "the single evaluation", self.ws.ctx, self.record, PHASE_PREDICT)   # the step's settings
        if x is not None:
            self.newton.x_try[:] = x
        evaluate_once(self.ws.ctx, self.record, PHASE_EVALUATE)
        self._check_status()
        return self.ws.vectors["res"][:pk.nx].copy(), self.matrix(), float(c["err"])

    def matrix(self):
        """The Newton matrix of the last evaluation (dense (nx, nx) ndarray, or scipy CSR)."""
        pk, nx = self.packed, self.packed.nx
        if pk.storage == DENSE:
            return self.ws.mat[:nx * nx].reshape(nx, nx).copy()
        pat = pk.pattern
        return sps.csr_matrix((self.ws.mat[:pat.nnz].copy(), pat.indices, pat.indptr), shape=(nx, nx))

    # ------------------------------------------------------------------ one step at a time, from states
    def starting_state(self, state):
        """The scheme's state at ``state.t`` from its (q, v), with the consistent accelerations,
        multipliers and prescribed forces (:meth:`start`)."""
        q, v = np.array(state.q, dtype=float), np.array(state.v, dtype=float)
        acc, lam, reaction = self.start(state.t, q, v)
        return self.scheme.make_state(state.t, q, v, acc=acc, pseudo=acc.copy(), lam=lam,
                                      prescribed_force=reaction)

    def step(self, state, h):
        """One step of size ``h`` (s) from ``state`` (the scheme's state type, e.g. from :meth:`starting_state`)
        with the scheme's compiled step: (the new state, Newton iterations). ``simulate`` runs the same
        step many times per call (and halves failed steps; this does not).

        Raises
        ------
        ValueError
            If ``state`` is not the scheme's state type or h is not a positive finite number.
        ConvergenceError
            If the step fails.
        """
        scheme = self.scheme
        if type(state) is not scheme.state_type:
            raise ValueError(f"{scheme.name} steps a {scheme.state_type.__name__}, got a {type(state).__name__} "
                             f"(start it with Stepper.starting_state)")
        if not (isinstance(h, (int, float)) and np.isfinite(h) and h > 0):
            raise ValueError(f"h must be a positive number of seconds, got {h!r}")
        self.load(state)
        chunk = self.advance(state.t, np.array([float(h)]), np.array([False]), scheme.newton.max_iterations,
                             scheme.newton.line_search)
        if chunk.steps != 1:
            self.raise_python_error()
            raise ConvergenceError(f"{scheme.name}: the step of {h:g} s from t = {state.t:.6g} s failed (status "
                                   f"{chunk.status})", iterations=chunk.iterations, residual=float("nan"))
        return self.state(state.t + float(h)), chunk.iterations

    def refusal(self, q, v, t):
        """(the name of the family that refused the last evaluation, the error its elements raise through
        their own methods at state (q, v) at time t — the family's ``refusal_error`` — or None)."""
        k, families = int(self.ws.ctx[0]["bad_family"]), self.packed.families
        if not 0 <= k < len(families):
            return "scheme", None
        fn = getattr(families[k][0], "refusal_error", None)
        return self.ws.family_name(k), (fn(self.scene, q, v, float(t)) if fn is not None else None)

    def _check_status(self):
        c = self.ws.ctx[0]
        if c["status"] == STATUS_PYTHON_ERROR:
            self.raise_python_error()
        if c["status"] == STATUS_MISSED:
            raise AssertionError(f"the {self.ws.family_name(int(c['bad_family']))} family wrote an entry outside "
                                 f"the Newton matrix's pattern (a bug: please report it)")
