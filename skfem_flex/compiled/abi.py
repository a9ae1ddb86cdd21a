r"""The calling convention of the compiled core.

The time loop, the schemes' step equations, the linear solvers and the kernels of every element
family are compiled separately (each a C-callable ``numba.cfunc`` cached on disk) and call each
other by address. A scene therefore compiles only the families it holds, a new scene made of
families compiled before compiles nothing, and a new family is one module that the loop never
has to know about.

Every kernel has the signature ``void(Context*, Family*)``:

* a :data:`CONTEXT` record (one per run, built by :mod:`.workspace`) holds the sizes, the task, the
  scheme's weights and the addresses of every work vector (q0, q1, v0, v1, the residual's parts, the
  Newton matrix), so that a kernel finds what it reads and writes by name;
* a :data:`FAMILY` record holds the kernel's address and its packed data: one float and one int
  pool and a header that says where each named field of the family's data lies in them
  (:func:`pack_fields`); the family's ``view`` rebuilds its named tuple of arrays from it.

Arrays are passed as addresses, so everything a kernel may touch must stay alive and in place
while the loop runs: the workspace owns it (:class:`~skfem_flex.compiled.workspace.Workspace`).
"""
from __future__ import annotations

import ctypes

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

__all__ = ["CONTEXT", "CONTEXT_FIELDS", "FAMILY", "FAMILY_SIZE", "KERNEL_SIGNATURE", "call", "call_pointers", "call_families", "fvec",
           "fmat", "ivec", "i32vec", "context_of", "context_at", "record_view", "vector_view", "family_of", "family_at", "Fields", "f1", "f2", "f3",
           "i1", "i2"]


def _record(*names_types):
    return np.dtype([(name, np.float64 if kind == "f" else np.int64) for name, kind in names_types])


# ------------------------------------------------------------------ the context record
#: every field of the context: (name, "f" float64 | "i" int64 or address); see .tasks for their meaning
CONTEXT_FIELDS = (
    # sizes: coordinates, constraint rows, free coordinates, unknowns (nf + m), prescribed, families
    ("n", "i"), ("m", "i"), ("nf", "i"), ("nx", "i"), ("npres", "i"), ("nfams", "i"),
    # the record's own address and its families' (an array of FAMILY records)
    ("self", "i"), ("fams", "i"),
    # what is asked: the scheme's phase (PHASE_*), the families' task (TASK_*), which scheme (SCHEME_*),
    # the level of the constraint rows (ROWS_*)
    ("phase", "i"), ("task", "i"), ("scheme", "i"), ("rows", "i"),
    # the step: start time and Δt (s), when loads and when constraint rows are evaluated (s); weights of the residual's parts and derivatives of the states
    # with respect to the unknowns (.tasks)
    ("t", "f"), ("h", "f"), ("te", "f"), ("t1", "f"), ("w_p", "f"), ("w_gk", "f"), ("w_gp", "f"), ("w_ext", "f"), ("w_mu", "f"),
    ("c_dg", "f"), ("dq1", "f"), ("da1", "f"), ("dqe", "f"), ("c_v", "f"),
    # states (n-vectors): start and end of the step, acceleration at the end, where loads are evaluated,
    # the end points of the discrete gradients; ∂v1/∂x and ∂v_e/∂x per coordinate
    ("q0", "i"), ("q1", "i"), ("v0", "i"), ("v1", "i"), ("a1", "i"), ("qe", "i"), ("ve", "i"),
    ("qa", "i"), ("qb", "i"), ("dv1", "i"), ("dve", "i"),
    # parts of the residual (n-vectors): momentum, kinetic and potential discrete gradients, loads,
    # constraint forces Dᵀμ, round-off floor of the stiff internal forces; for the Newmark step the
    # sizes |Δq| + Δt|v0| + Δt²|½ − β||a0| of the acceleration's terms and |M| times them
    ("p", "i"), ("gk", "i"), ("gp", "i"), ("ext", "i"), ("dtmu", "i"), ("floor", "i"), ("terms", "i"),
    ("mterms", "i"),
    # constraint rows (m-vectors): value, multipliers μ, Σ|Φ_q||q1|, max|Φ_q|, D·(q_b − q_a), Φ_t
    ("phi", "i"), ("mu", "i"), ("rscale", "i"), ("rmax", "i"), ("ddphi", "i"), ("phit", "i"),
    # the Newton matrix (.storage)
    ("mat", "i"), ("fpos", "i"), ("storage", "i"), ("csr_ptr", "i"), ("csr_idx", "i"), ("missed", "i"),
    # the scene's constant masses (CSR over all coordinates) and each entry's place in the Newton matrix
    ("mass_ptr", "i"), ("mass_idx", "i"), ("mass_dat", "i"), ("mass_pos", "i"),
    # free and prescribed coordinates (index arrays of nf and npres entries)
    ("free", "i"), ("pres", "i"),
    # the Newton iteration: where to evaluate (x, nx), residual and update (nx), J regular, scaled error,
    # size of the state the increments belong to, iterations of the last step, tolerances
    ("x", "i"), ("res", "i"), ("y", "i"), ("regular", "i"), ("err", "f"), ("x_scale", "f"), ("its", "i"),
    ("rtol", "f"), ("ctol", "f"), ("etol", "f"), ("length_scale", "f"),
    # functions of time at this step (a row of the chunk's time table, ncol columns)
    ("trow", "i"), ("ncol", "i"),
    # the position maps every family shares (a FAMILY record of .points)
    ("maps", "i"),
    # scalar outputs of the ENERGY and MOMENTUM tasks: V, linear momentum (3), angular momentum (3)
    ("out", "i"),
    # the scheme's state that the loop records: multipliers λ (m), prescribed forces (npres), work (1)
    ("lam", "i"), ("reaction", "i"), ("work", "i"),
    # an element refused the state or a Python element raised (STATUS_*), and which family; why the scheme
    # refused a step itself (REFUSAL_*, when bad_family < 0)
    ("status", "i"), ("bad_family", "i"), ("refusal", "i"),
    # a float pool kernels may use during one call
    ("scratch", "i"), ("nscratch", "i"),
    # 1 when an evaluation is to form the Newton matrix; 0 when only its residual is used (the check of an
    # update: the loop points ``mat`` at ``mat_spare``, which nobody reads, and a family may skip its
    # derivatives, :data:`..compiled.families` ``RESIDUAL_ONLY``)
    ("fresh", "i"), ("mat_spare", "i"),
    # T at (q1, v1) and 1 while it and ``out`` hold the energies and momenta of the state there
    # (:func:`..compiled.acceptance.energies`): a step's record reuses what its acceptance computed
    ("kin", "f"), ("energies_valid", "i"),
)
CONTEXT = _record(*CONTEXT_FIELDS)
CONTEXT_TYPE = numba.from_dtype(CONTEXT)

# ------------------------------------------------------------------ the family record
FAMILY = _record(("kernel", "i"), ("index", "i"), ("fpool", "i"), ("nfpool", "i"), ("ipool", "i"),
                 ("nipool", "i"), ("header", "i"), ("nfields", "i"), ("count", "i"))
FAMILY_TYPE = numba.from_dtype(FAMILY)
#: bytes per FAMILY record (records of a scene lie side by side)
FAMILY_SIZE = FAMILY.itemsize

#: every kernel: void(Context*, Family*)
KERNEL_SIGNATURE = types.void(types.CPointer(CONTEXT_TYPE), types.CPointer(FAMILY_TYPE))


# ------------------------------------------------------------------ calling by address
@intrinsic
def call(typingctx, kernel, ctx_address, fam_address):
    """Call the kernel at address ``kernel`` with the records at ``ctx_address`` and ``fam_address``
    (all int64)."""
    sig = types.void(kernel, ctx_address, fam_address)

    def codegen(context, builder, signature, args):
        i8p = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i8p])
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        builder.call(fn, [builder.inttoptr(args[1], i8p), builder.inttoptr(args[2], i8p)])
        return context.get_dummy_value()
    return sig, codegen


@intrinsic
def call_pointers(typingctx, function, addresses):
    """Call the C or Fortran function at ``function`` with the pointers in the tuple ``addresses`` (int64
    each; LAPACK takes every argument by reference)."""
    sig = types.void(function, addresses)
    count = len(addresses)

    def codegen(context, builder, signature, llargs):
        i8p = ir.IntType(8).as_pointer()
        values = cgutils.unpack_tuple(builder, llargs[1], count)
        fnty = ir.FunctionType(ir.VoidType(), [i8p] * count)
        builder.call(builder.inttoptr(llargs[0], fnty.as_pointer()), [builder.inttoptr(v, i8p) for v in values])
        return context.get_dummy_value()
    return sig, codegen


@numba.njit(cache=True, _nrt=False)
def call_families(ctx, task):
    """Ask every family of the scene to do ``task`` (ctx: the context record)."""
    ctx.task = task
    for k in range(ctx.nfams):
        fam = ctx.fams + k * FAMILY_SIZE
        call(family_at(fam).kernel, ctx.self, fam)
        if (ctx.status != 0 or ctx.missed != 0) and ctx.bad_family < 0:
            ctx.bad_family = k


def _array_value(context, builder, aryty, address, dims):
    """An array struct of type ``aryty`` (C order, no owner) over the memory at the int64 ``address``."""
    ary = make_array(aryty)(context, builder)
    dtype = context.get_data_type(aryty.dtype)
    data = builder.inttoptr(address, dtype.as_pointer())
    intp = context.get_value_type(types.intp)
    shape = [builder.sext(d, intp) if d.type.width < intp.width else d for d in dims]
    itemsize = context.get_abi_sizeof(dtype)
    strides, stride = [], context.get_constant(types.intp, itemsize)
    for d in reversed(shape):
        strides.insert(0, stride)
        stride = builder.mul(stride, d)
    populate_array(ary, data=data, shape=cgutils.pack_array(builder, shape),
                   strides=cgutils.pack_array(builder, strides),
                   itemsize=context.get_constant(types.intp, itemsize), meminfo=None)
    return ary._getvalue()


@intrinsic
def fvec(typingctx, address, n):
    """The float64 array of length n at ``address`` (an intrinsic: nothing to compile per call site)."""
    aryty = types.Array(types.float64, 1, "C")
    return aryty(address, n), lambda c, b, s, a: _array_value(c, b, aryty, a[0], a[1:])


@intrinsic
def fmat(typingctx, address, n, m):
    """The (n, m) float64 array (C order) at ``address``."""
    aryty = types.Array(types.float64, 2, "C")
    return aryty(address, n, m), lambda c, b, s, a: _array_value(c, b, aryty, a[0], a[1:])


@intrinsic
def ivec(typingctx, address, n):
    """The int64 array of length n at ``address``."""
    aryty = types.Array(types.int64, 1, "C")
    return aryty(address, n), lambda c, b, s, a: _array_value(c, b, aryty, a[0], a[1:])


@intrinsic
def i32vec(typingctx, address, n):
    """The int32 array of length n at ``address`` (Fortran integers for LAPACK)."""
    aryty = types.Array(types.int32, 1, "C")
    return aryty(address, n), lambda c, b, s, a: _array_value(c, b, aryty, a[0], a[1:])


def _record_intrinsic(record_type, doc):
    @intrinsic
    def at(typingctx, address):
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(record_type))
        return record_type(address), codegen
    at.__doc__ = doc
    return at


context_at = _record_intrinsic(CONTEXT_TYPE, "The context record at ``address`` (writes go through).")


def record_view(address, dtype=CONTEXT):
    """From Python: the record of ``dtype`` at ``address`` as a numpy record (writes go through); the
    Python side of the ABI, for kernels that are ctypes callbacks."""
    return np.frombuffer((ctypes.c_char * dtype.itemsize).from_address(int(address)), dtype=dtype)[0]


def vector_view(address, n, dtype=np.float64):
    """From Python: the ``n`` entries of ``dtype`` at ``address`` as a numpy array (writes go through)."""
    ctype = ctypes.c_double if np.dtype(dtype) == np.float64 else ctypes.c_int64
    return np.ctypeslib.as_array(ctypes.cast(int(address), ctypes.POINTER(ctype)), shape=(max(int(n), 1),))[:int(n)]
family_at = _record_intrinsic(FAMILY_TYPE, "The family record at ``address``.")


@intrinsic
def context_of(typingctx, ctx_p):
    """The context record behind a kernel's first argument (a reference: writes go through)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(CONTEXT_TYPE))
    return CONTEXT_TYPE(ctx_p), codegen


@intrinsic
def family_of(typingctx, fam_p):
    """The family record behind a kernel's second argument."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(FAMILY_TYPE))
    return FAMILY_TYPE(fam_p), codegen


# ------------------------------------------------------------------ named fields in pools
# header row of a field: (pool 0 float | 1 int, offset, ndim, d0, d1, d2)
_HEADER_WIDTH = 6


class Fields:
    """A family's packed data: its named fields in one float and one int pool, with the header the
    compiled views read (:func:`f1` …). Kept alive by whoever holds the family record.

    Parameters
    ----------
    data : NamedTuple of ndarray
        The family's data; float fields are stored as float64, integer fields as int64.
    """

    def __init__(self, data):
        self.data = data
        floats, ints, header = [], [], []
        nf = ni = 0
        for name, arr in zip(data._fields, data):
            a = np.asarray(arr)
            if a.ndim > 3:
                raise ValueError(f"field {name!r} has {a.ndim} dimensions; at most 3")
            shape = list(a.shape) + [1] * (3 - a.ndim)
            if np.issubdtype(a.dtype, np.integer) or a.dtype == bool:
                ints.append(np.ascontiguousarray(a, dtype=np.int64).ravel())
                header.append((1, ni, a.ndim, *shape))
                ni += a.size
            else:
                floats.append(np.ascontiguousarray(a, dtype=np.float64).ravel())
                header.append((0, nf, a.ndim, *shape))
                nf += a.size
        # a pool is never empty: its address must be valid
        self.fpool = np.concatenate(floats + [np.zeros(1)])
        self.ipool = np.concatenate(ints + [np.zeros(1, dtype=np.int64)])
        self.header = np.asarray(header, dtype=np.int64).reshape(len(header), _HEADER_WIDTH)
        if not self.header.size:
            self.header = np.zeros((1, _HEADER_WIDTH), dtype=np.int64)

    def array(self, name):
        """The pool's view of field ``name`` (writes go to the pool the kernels read)."""
        k = self.data._fields.index(name)
        pool, off, ndim, d0, d1, d2 = self.header[k]
        shape = (d0, d1, d2)[:ndim]
        size = int(np.prod(shape)) if ndim else 1
        src = self.ipool if pool else self.fpool
        return src[off:off + size].reshape(shape)

    def record(self, kernel, index, count):
        """The FAMILY record of these fields with the kernel at address ``kernel``."""
        rec = np.zeros(1, dtype=FAMILY)[0]
        rec["kernel"], rec["index"], rec["count"] = kernel, index, count
        rec["fpool"], rec["nfpool"] = self.fpool.ctypes.data, self.fpool.size
        rec["ipool"], rec["nipool"] = self.ipool.ctypes.data, self.ipool.size
        rec["header"], rec["nfields"] = self.header.ctypes.data, len(self.data._fields)
        return rec


def _field_intrinsic(dtype, ndim, pool):
    aryty = types.Array(dtype, ndim, "C")
    hdr_off = FAMILY.fields["header"][1]
    pool_off = FAMILY.fields[pool][1]

    @intrinsic
    def field(typingctx, fam, k):
        def codegen(context, builder, signature, args):
            rec, kk = args
            i64 = ir.IntType(64)
            base = builder.bitcast(rec, ir.IntType(8).as_pointer())

            def member(off):
                ptr = builder.gep(base, [ir.Constant(i64, off)])
                return builder.load(builder.bitcast(ptr, i64.as_pointer()))
            header = builder.inttoptr(member(hdr_off), i64.as_pointer())
            row = builder.gep(header, [builder.mul(kk, ir.Constant(i64, _HEADER_WIDTH))])

            def hdr(j):
                return builder.load(builder.gep(row, [ir.Constant(i64, j)]))
            address = builder.add(member(pool_off), builder.mul(hdr(1), ir.Constant(i64, 8)))
            dims = [hdr(3 + j) for j in range(ndim)]
            return _array_value(context, builder, aryty, address, dims)
        return aryty(fam, k), codegen
    return field


#: field k of a family's data as a 1-D, 2-D or 3-D float array, a 1-D or 2-D int array (the family's
#: ``view`` builds its named tuple from these, in the order of its fields)
f1 = _field_intrinsic(types.float64, 1, "fpool")
f2 = _field_intrinsic(types.float64, 2, "fpool")
f3 = _field_intrinsic(types.float64, 3, "fpool")
i1 = _field_intrinsic(types.int64, 1, "ipool")
i2 = _field_intrinsic(types.int64, 2, "ipool")
