r"""A scene packed once for the compiled core: its families, position maps, constant masses, functions of
time, probes, and the Newton matrix's pattern, storage and solver.

Everything is read through public interfaces of the scene's parts (no type checks):

* a body with a mass matrix that depends on q hands ``compiled_kernel_data()`` and
  ``mass_moment_map()`` (the floating-frame family);
* a body with constant mass hands ``mass_matrix``, ``mass_moment()`` (∫ r dm = Γ q + c) and, with a
  strain energy, ``compiled_strain_data()`` (the exact-beam family);
* a force element its ``compiled_form()``, whose name selects its family
  (:func:`~skfem_flex.compiled.families.family_for`); gravity is packed per body from the first moments;
* a constraint its ``compiled_form()``: one block or ``("rows", [(block, law), ...])``, each block to
  the family of its name;
* a body point its ``compiled_map()`` (:mod:`.points`).

An element with no compiled form is packed into the Python family (its kernel calls the element's
own methods); :attr:`PackedScene.python_elements` names them and why.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps

from ..bodies.base import COMPILED_SIZE_LIMIT, DENSE_LIMIT
from ..numerics.band_plans import DENSE_BORDERED_GAIN, MAX_BANDWIDTH, MAX_BORDER, MIN_DENSE_BORDERED, dense_bordered_plan, plan_work, reordered_band_plan, solve_work
from .abi import Fields
from .families import family_for
from .points import MapStore
from .storage import CSR, DENSE, positions

__all__ = ["Packer", "PackedScene", "packed_scene", "DENSE_STORAGE_LIMIT", "time_table"]

#: the Newton matrix is stored dense up to this many rows, above as the values of its pattern (the
#: package's one dense/sparse threshold)
DENSE_STORAGE_LIMIT = DENSE_LIMIT


def _call(obj, method):
    fn = getattr(obj, method, None)
    return None if fn is None else fn()


class Packer:
    """What a family's ``pack`` may use: the scene's layout, the shared position maps and the chunk's
    columns of functions of time.

    Attributes
    ----------
    scene : Scene
    maps : MapStore
    columns : list of (str, callable, int)
        ("end" | "force", fun, component): a function of time evaluated at each step's end or where the
        scheme evaluates its loads (the mid-point for energy-momentum, the end for Newmark).
    """

    def __init__(self, scene):
        self.scene = scene
        self.maps = MapStore()
        self.columns = []

    def block(self, body):
        """(offset, size) of ``body``'s coordinates."""
        sl = self.scene.slice(body)
        return sl.start, sl.stop - sl.start

    def point_map(self, point):
        """The map index of a body point (its ``compiled_map()``), or None if it has none."""
        entry = _call(point, "compiled_map")
        if entry is None:
            return None
        off, nb = self.block(point.body)
        return self.maps.add(entry, off, nb)

    def maps_support(self, k):
        """The scene coordinates map k's position can depend on."""
        return self.maps.support(k)

    def column(self, fun, component, when):
        """Index of the time-table column for ``fun(t)[component]`` evaluated ``when`` ("end" | "force"). A ``fun``
        with a ``table(times)`` method (a :class:`~skfem_flex.elements.motion.MotionLaw`) is tabulated by it,
        (components, times) in one call (:func:`time_table`)."""
        self.columns.append((when, fun, component))
        return len(self.columns) - 1

    def law_columns(self, law, when="end"):
        """Index of the first of the three columns x, ẋ, ẍ of a motion law ``law(t) = (x, ẋ, ẍ)``."""
        first = self.column(law, 0, when)
        self.column(law, 1, when)
        self.column(law, 2, when)
        return first


@dataclass
class PackedScene:
    """A scene in the compiled core's form (built once per scene by :func:`packed_scene`)."""

    families: list                      # (module, Fields, count) per family, in calling order
    maps: Fields
    columns: list
    mass: tuple                         # (ptr, idx, dat, pos) CSR of the constant masses over all coordinates and
    #                                     each entry's place in the Newton matrix's values (−1: prescribed)
    free: np.ndarray
    pres: np.ndarray
    fpos: np.ndarray
    cayley: np.ndarray
    angles: np.ndarray                  # free coordinates that are rotation angles (the schemes' turn rule)
    pres_cols: np.ndarray               # first of the (value, rate, acceleration) columns of each law
    probe_names: list                   # (name, first map, number of maps, combine)
    probe_maps: np.ndarray
    storage: int
    pattern: object                     # scipy CSR pattern of the bordered Newton matrix (CSR storage)
    solver: str                         # "dense" | "bordered band" | "bordered band (CSR)"
    plan: tuple                         # (interior, border, (lo, up)) or None
    #: (element, reason) of every element that runs through its Python methods
    python_elements: list = field(default_factory=list)
    m: int = 0
    rheonomic: bool = False             # a constraint depends on time (drivers): Newmark's work needs Φ_t

    @property
    def nx(self):
        """Unknowns of the Newton system: free coordinates and multipliers."""
        return self.free.size + int(self.m)


_PACKED = weakref.WeakKeyDictionary()
_PACKED_PY = weakref.WeakKeyDictionary()


def packed_scene(scene, python_only=False):
    """The scene's :class:`PackedScene`, built on first use; ``python_only``: every element through its own
    Python methods (the Python family), for ``simulate(..., compiled=False)``."""
    cache = _PACKED_PY if python_only else _PACKED
    hit = cache.get(scene)
    if hit is None:
        hit = cache[scene] = _pack(scene, python_only)
    return hit


def _unmapped_point(form):
    """A body point inside a compiled form (nested tuples and lists) that has no compiled position map (a
    point of a user's body), or None: an element holding one runs through its Python methods."""
    if isinstance(form, (tuple, list)):
        for part in form:
            hit = _unmapped_point(part)
            if hit is not None:
                return hit
        return None
    if getattr(form, "body", None) is not None and callable(getattr(form, "compiled_map", None)):
        return form if _call(form, "compiled_map") is None else None
    return None


def build_key(scene, scheme_name, python_only=False):
    """What decides which compiled units a run of ``scene`` under the scheme named ``scheme_name`` needs:
    the scheme, the element families it packs (in calling order), the Newton matrix's storage (dense or
    CSR) and its solver. Two runs with equal keys compile nothing the other has not (numbers such as
    sizes, speeds and steps change values, not code, unless they switch the storage or solver)."""
    pk = packed_scene(scene, python_only)
    return (str(scheme_name), tuple(module.NAME for module, _, _ in pk.families), int(pk.storage), pk.solver)


def _momentum_layout(body):
    """(l_x, l_y, i_x, i_y, X, Y, i_angle) of a planar constant-mass body (local indices): p_x = Σ p[l_x],
    L = Σ (X + q[i_x]) p[i_y] − (Y + q[i_y]) p[i_x] + Σ p[i_angle]; from ``momentum_layout()`` or by
    default R = q[0:2], θ = q[2] where present. A spatial body: ("spatial", triples, anchor, Γ)
    (``spatial_momentum_layout()`` and ``mass_moment()``, :mod:`.families.constant_mass`)."""
    nb = body.n_dofs
    none, zero = np.zeros(0, dtype=np.int64), np.zeros(1)
    spatial = _call(body, "spatial_momentum_layout")
    if spatial is not None:
        triples, anchor = spatial
        gam, _ = body.mass_moment()
        return "spatial", np.asarray(triples, dtype=np.int64), np.asarray(anchor, float), np.asarray(gam, float)
    layout = _call(body, "momentum_layout")
    if layout is not None:
        ix, iy, X, Y, ia = (np.asarray(a) for a in layout)
        return ix, iy, ix, iy, np.asarray(X, float), np.asarray(Y, float), ia
    if nb == 1:
        return np.array([0]), none, none, none, np.zeros(0), np.zeros(0), none
    ix, iy = np.array([0]), np.array([1])
    return ix, iy, ix, iy, zero, zero, (np.array([2]) if nb >= 3 else none)


def _spatial_first_moment(body):
    """(Γ, c) of a spatial body whose positions are linear in q, or None (planar, or not linear: a spatial
    floating-frame body, whose gravity its own family evaluates)."""
    if getattr(body, "dimension", 2) != 3:
        return None
    try:
        return body.mass_moment()
    except NotImplementedError:
        return None


def _pack(scene, python_only=False):
    packer = Packer(scene)
    n = scene.n
    items = {}                                            # family module → list of items
    python, reasons = [], []                              # Python-family items; (element, why) for Result

    def add(mod, item):
        items.setdefault(mod, []).append(item)

    def in_python(role, element, where, why):
        python.append((role, element, where))
        if all(e is not element for e, _ in reasons):
            reasons.append((element, why))

    first_moment = {}
    own_gravity = {}                                      # bodies whose family evaluates gravity on them: its form
    mass_blocks = []
    angles = [np.asarray(scene.cayley_index, dtype=np.int64)]
    for b in scene.bodies:
        off, nb = packer.block(b)
        idx = np.arange(off, off + nb)
        kd = None if python_only else _call(b, "compiled_kernel_data")
        if kd is not None:
            form = getattr(b, "inertia_family", "floating frame")
            if family_for(form) is None or (form != "floating frame" and family_for(form + " gravity") is None):
                raise ValueError(f"body {b.name!r} names the inertia family {form!r}, which no compiled family "
                                 f"packs (with its gravity, {form + ' gravity'!r})")
            add(family_for(form), (kd, b, off))
            if form != "floating frame":               # gravity quadratic in q: the body's own family takes it
                own_gravity[id(b)] = form + " gravity"
                continue
            moment = _call(b, "mass_moment_map")
            angles.append(np.array([off + 2]))          # the frame's angle θ
            if moment is not None:
                first_moment[id(b)] = ("frame", moment[0], moment[1], moment[2])
            continue
        if b.constant_mass:
            block = sps.coo_matrix(b.mass_matrix(np.asarray(b.q0, dtype=float)))
            mass_blocks.append((block.row + off, block.col + off, block.data))
            layout = _momentum_layout(b)
            if not isinstance(layout[0], str):         # planar: its angle coordinates
                angles.append(off + np.asarray(layout[6], dtype=np.int64))
            add(family_for("constant mass"), (layout, b, off))
            if not python_only and getattr(b, "dimension", 2) == 2:
                try:
                    gam, c = b.mass_moment()
                    first_moment[id(b)] = ("linear", gam, c)
                except NotImplementedError:
                    pass
        else:
            in_python("inertia", b, idx, "compiled=False" if python_only else
                      getattr(b, "compiled_refusal", None)
                      or "its mass matrix depends on q and it has no compiled_kernel_data()")
        if b.has_potential:
            strain = None if python_only else _call(b, "compiled_strain_data")
            if strain is not None:
                add(family_for(b.strain_family), (strain, b, off))
            else:
                in_python("potential", b, idx, "compiled=False" if python_only else
                          "its strain energy has no compiled_strain_data()")
    for f, idx in scene.conservative_forces + scene.loads:
        form = None if python_only else _call(f, "compiled_form")
        mod = family_for(form[0]) if form is not None else None
        if form is not None and form[0] == "gravity":
            for b in (f.bodies if f.bodies is not None else scene.bodies):
                moment = _spatial_first_moment(b)
                if moment is not None:
                    # a spatial body linear in q: V = −g·(Γ q + c), a constant gradient
                    off, nb = packer.block(b)
                    gam, c = moment
                    g3 = np.asarray(form[1], dtype=float)
                    add(family_for("linear potential"), ((-(g3 @ gam), -float(g3 @ c)), b, np.arange(off, off + nb)))
                elif id(b) in own_gravity:
                    add(family_for(own_gravity[id(b)]), (("gravity", np.asarray(form[1], dtype=float)), b,
                                                         packer.block(b)[0]))
                elif id(b) in first_moment:
                    add(mod, ((first_moment[id(b)], np.asarray(form[1], dtype=float)), b, packer.block(b)))
                else:
                    off, nb = packer.block(b)
                    in_python("gravity", b, (np.arange(off, off + nb), np.asarray(form[1], dtype=float)),
                              f"body {b.name!r} gives no first moment of its mass")
        elif mod is not None and _unmapped_point(form) is not None:
            in_python("force", f, np.asarray(idx), f"body {_unmapped_point(form).body.name!r} gives no compiled "
                      f"position map of its points")
        elif mod is not None:
            add(mod, (form, f, idx))
        else:
            in_python("force", f, np.asarray(idx), "compiled=False" if python_only else
                      ("it has no compiled form" if form is None else f"no family packs {form[0]!r}"))
    for c, (idx, rows) in zip(scene.constraints, scene.constraint_layout):
        form = None if python_only else _call(c, "compiled_form")
        blocks = [] if form is None else (form[1] if form[0] == "rows" else [(form, None)])
        mods = [family_for(term[0]) for term, _ in blocks]
        unmapped = None if form is None else _unmapped_point(form)
        if form is None or any(m_ is None for m_ in mods) or unmapped is not None:
            in_python("constraint", c, (np.asarray(idx), int(rows[0])), "compiled=False" if python_only else
                      ("it has no compiled form" if form is None else "a block of it has no family"
                       if unmapped is None else f"body {unmapped.body.name!r} gives no compiled position map "
                       f"of its points"))
            continue
        r = int(rows[0])
        for (term, law), mod in zip(blocks, mods):
            add(mod, ((term, law), c, (np.asarray(idx), r)))
            r += mod.row_count(term)
    packs = []
    for mod, its in items.items():
        pk = mod.pack(its, packer)
        if pk is not None:
            packs.append((mod, pk))
    if python:
        from .families import python_elements           # the fallback family
        packs.append((python_elements, python_elements.pack(python, packer)))
    # prescribed coordinates: (value, rate, acceleration) columns of their laws at the step's end
    pres_cols = []
    for p in scene.prescribed:
        law = p.law
        pres_cols.append(packer.law_columns(law))
    # probes made of position maps are recorded by the loop; the others are called in Python
    probe_names, probe_maps = [], []
    for name, fn in scene.probes.items():
        parts = getattr(fn, "parts", None)
        parts, combine = (tuple(parts), fn.combine) if parts is not None else ((fn,), None)
        found = []
        for part in parts:
            body = getattr(part, "body", None)
            if body is None or not any(body is b for b in scene.bodies) or _call(part, "compiled_map") is None:
                break
            found.append(part)
        else:
            probe_names.append((name, len(probe_maps), len(found), combine))
            probe_maps += [packer.point_map(part) for part in found]
    rows, cols, vals = (np.concatenate([blk[i] for blk in mass_blocks]) if mass_blocks else np.zeros(0)
                        for i in range(3))
    mass = sps.csr_matrix((vals, (rows.astype(np.int64), cols.astype(np.int64))), shape=(n, n))
    mass.sum_duplicates()
    mass.eliminate_zeros()
    mass.sort_indices()
    free = np.asarray(scene.free_index, dtype=np.int64)
    fpos = -np.ones(n, dtype=np.int64)
    fpos[free] = np.arange(free.size)
    packed = PackedScene(
        families=[], maps=Fields(packer.maps.data()), columns=packer.columns,
        mass=(mass.indptr.astype(np.int64), mass.indices.astype(np.int64), mass.data.astype(float)),
        free=free, pres=np.asarray(scene.prescribed_index, dtype=np.int64), fpos=fpos,
        cayley=np.asarray(scene.cayley_index, dtype=np.int64),
        angles=np.intersect1d(np.concatenate(angles), free).astype(np.int64), pres_cols=np.asarray(pres_cols, dtype=np.int64),
        probe_names=probe_names, probe_maps=np.asarray(probe_maps, dtype=np.int64), storage=DENSE,
        pattern=None, solver="dense", plan=None, python_elements=reasons, m=int(scene.n_constraints),
        rheonomic=any(getattr(c, "rheonomic", False) for c in scene.constraints))
    _plan(packed, scene, packs)
    return packed


def _newton_pattern(scene, packed, packs):
    """Where the bordered Newton matrix (free coordinates, then multipliers) can be nonzero: the constant
    masses, the diagonal, every family's coupled blocks and entries, each constraint row with the
    coordinates it touches; scipy CSR with sorted indices."""
    n, m = scene.n, scene.n_constraints
    rows, cols = [np.arange(n)], [np.arange(n)]
    ptr, idx = packed.mass[:2]
    rows.append(np.repeat(np.arange(n), np.diff(ptr)))
    cols.append(idx)
    for _, pk in packs:
        for coords in pk.couplings:
            coords = np.asarray(coords, dtype=np.int64)
            rows.append(np.repeat(coords, coords.size))
            cols.append(np.tile(coords, coords.size))
        if pk.entries is not None:
            rows.append(np.asarray(pk.entries[0], dtype=np.int64))
            cols.append(np.asarray(pk.entries[1], dtype=np.int64))
        for row, coords in pk.rows:
            coords = np.asarray(coords, dtype=np.int64)
            r = np.full(coords.size, n + row)
            rows += [r, coords]
            cols += [coords, r]
    rows, cols = np.concatenate(rows).astype(np.int64), np.concatenate(cols).astype(np.int64)
    pat = sps.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(n + m, n + m))
    sel = np.concatenate([scene.free_index, n + np.arange(m)]).astype(np.int64)
    pat = pat[sel][:, sel].tocsr()
    pat.sum_duplicates()
    pat.sort_indices()
    pat.data[:] = 1
    return pat


def _plan(packed, scene, packs):
    """Fix the Newton matrix's storage and solver from its pattern, then the families' data."""
    nx = packed.nx
    pattern = _newton_pattern(scene, packed, packs)
    plan = None
    if nx >= MIN_DENSE_BORDERED:
        plan = dense_bordered_plan(pattern, max_border=MAX_BORDER if nx > DENSE_STORAGE_LIMIT else None)
        if plan is None and nx <= DENSE_STORAGE_LIMIT:
            # a closed loop of spatial bodies (Bricard: 119 unknowns, 308 entries) has no band in its own order
            # and no small border, but one after reordering: taken when it models under dense LU's work
            reordered = reordered_band_plan(pattern, max_bandwidth=nx // 2)
            if reordered is not None and DENSE_BORDERED_GAIN * solve_work(nx, reordered) <= solve_work(nx):
                plan = reordered
        if nx > DENSE_STORAGE_LIMIT:
            # a chain of bodies: its multipliers in the border make a Schur complement as large as the
            # chain, reordered into the band they cost little (the spatial rigid chain: 110 of 230); a chain
            # of spatial bodies has a band of about 2 × 33 (12 directors, 6 rigidity and 5 hinge rows a body);
            # a band of half the matrix or more is no band
            reordered = reordered_band_plan(pattern, max_bandwidth=min(2 * MAX_BANDWIDTH, nx // 2))
            if reordered is not None and (plan is None or plan_work(reordered) < plan_work(plan)):
                plan = reordered
    if nx <= DENSE_STORAGE_LIMIT or (plan is None and nx <= COMPILED_SIZE_LIMIT):
        packed.storage = DENSE
        packed.solver = "bordered band" if plan is not None else "dense"
    elif plan is None:
        packed.storage = CSR
        packed.solver = "sparse (SuperLU)"
    else:
        packed.storage = CSR
        packed.solver = "bordered band (CSR)"
    packed.pattern = pattern
    packed.plan = plan
    layout = (packed.storage, pattern, packed.fpos, nx)
    ptr, idx = packed.mass[:2]
    mass_rows = np.repeat(np.arange(ptr.size - 1, dtype=np.int64), np.diff(ptr))
    packed.mass = packed.mass[:3] + (positions(layout, packed.fpos[mass_rows], packed.fpos[idx]),)
    for mod, pk in packs:
        data = pk.finish(layout) if pk.finish is not None else pk.data
        packed.families.append((mod, Fields(data), pk.count))


def time_table(columns, times, hs, scheme_mid):
    """The chunk's functions of time: row 0 at times[0], row k + 1 for step k (from times[k] to times[k + 1],
    of size hs[k]); an "end" column at times[k + 1], a "force" column at times[k] + hs[k]/2 when
    ``scheme_mid`` (energy-momentum) else at times[k + 1]."""
    ns = hs.size
    times = np.asarray(times, dtype=float)
    t0, starts, ends = times[0], times[:-1], times[1:]
    table = np.zeros((ns + 1, max(len(columns), 1)))
    cache = {}
    for j, (when, fun, comp) in enumerate(columns):
        at = np.concatenate([[t0], ends if (when == "end" or not scheme_mid) else starts + 0.5 * hs])
        key = (id(fun), when)
        vals = cache.get(key)
        if vals is None:
            tabulate = getattr(fun, "table", None)   # (components, times) in one call (Packer.column)
            vals = cache[key] = (tabulate(at) if tabulate is not None else
                                 np.array([np.atleast_1d(np.asarray(fun(float(t)), dtype=float)) for t in at]).T)
        table[:, j] = vals[comp]
    return table
