r"""The memory a compiled run works in: the context record, the families' records and every work vector.

A :class:`Workspace` is made once per run (scene and scheme) and kept for all its chunks; the kernels
reach its arrays through the addresses in the context (:mod:`.abi`), so it owns them all and never
reallocates them while it lives.
"""
from __future__ import annotations

import numpy as np

from .abi import CONTEXT, FAMILY
from .pack import packed_scene
from .storage import DENSE

__all__ = ["Workspace"]

#: the context's n-vectors and m-vectors, allocated here
_N_VECTORS = ("q1", "v1", "a1", "dv1", "dve", "p", "gk", "gp", "ext", "dtmu", "floor", "terms", "mterms")
_M_VECTORS = ("phi", "mu", "rscale", "rmax", "ddphi", "phit")


class Workspace:
    """The context and the arrays behind it for one scene.

    Parameters
    ----------
    scene : Scene
    settings : NewtonSettings
        Tolerances copied into the context.
    python_only : bool
        Every element through its own Python methods (``simulate(..., compiled=False)``).

    Attributes
    ----------
    ctx : ndarray of CONTEXT, shape (1,)
    families : ndarray of FAMILY, shape (k,)
    packed : PackedScene
    """

    def __init__(self, scene, settings, python_only=False):
        pk = self.packed = packed_scene(scene, python_only)
        n, m, nf = scene.n, pk.m, pk.free.size
        nx = nf + m
        self.scene = scene
        self.keep = []
        self.ctx = np.zeros(1, dtype=CONTEXT)
        c = self.ctx[0]
        c["n"], c["m"], c["nf"], c["nx"], c["npres"] = n, m, nf, nx, pk.pres.size
        c["self"] = self.ctx.ctypes.data
        c["status"], c["bad_family"] = 0, -1
        self.vectors = {}
        for name in _N_VECTORS:
            self._vector(name, n)
        for name in _M_VECTORS:
            self._vector(name, m)
        for name in ("res", "y"):
            self._vector(name, nx)
        self._vector("out", 8)
        self._vector("scratch", 32 * n + 64)
        c["nscratch"] = 32 * n + 64
        # the matrix
        if pk.storage == DENSE:
            self.mat = np.zeros(nx * nx)
            c["csr_ptr"] = c["csr_idx"] = 0
        else:
            self.csr_ptr = pk.pattern.indptr.astype(np.int64)
            self.csr_idx = pk.pattern.indices.astype(np.int64)
            self.mat = np.zeros(max(self.csr_idx.size, 1))
            c["csr_ptr"], c["csr_idx"] = self.csr_ptr.ctypes.data, self.csr_idx.ctypes.data
        c["mat"], c["storage"] = self.mat.ctypes.data, pk.storage
        # where a residual-only evaluation writes its matrix entries (.abi: "fresh")
        self.mat_spare = np.zeros_like(self.mat)
        c["mat_spare"], c["fresh"] = self.mat_spare.ctypes.data, 1
        for name, arr in (("fpos", pk.fpos), ("free", pk.free), ("pres", pk.pres)):
            arr = np.ascontiguousarray(arr, dtype=np.int64)
            if arr.size == 0:
                arr = np.zeros(1, dtype=np.int64)
            self.keep.append(arr)
            c[name] = arr.ctypes.data
        for name, arr in zip(("mass_ptr", "mass_idx", "mass_dat", "mass_pos"), pk.mass):
            arr = np.ascontiguousarray(arr)
            if arr.size == 0:
                arr = np.zeros(1, dtype=arr.dtype)
            self.keep.append(arr)
            c[name] = arr.ctypes.data
        # the maps record and the families' records, side by side
        self.maps = np.zeros(1, dtype=FAMILY)
        self.maps[0] = pk.maps.record(0, -1, 0)
        c["maps"] = self.maps.ctypes.data
        self.families = np.zeros(max(len(pk.families), 1), dtype=FAMILY)
        for k, (mod, fields, count) in enumerate(pk.families):
            self.families[k] = fields.record(mod.kernel().address, k, count)
        c["fams"], c["nfams"] = self.families.ctypes.data, len(pk.families)
        c["rtol"], c["ctol"], c["etol"] = settings.rtol, settings.ctol, settings.etol
        c["length_scale"] = float(scene.length_scale)
        c["ncol"] = max(len(pk.columns), 1)

    def _vector(self, name, size):
        arr = np.zeros(max(size, 1))
        self.vectors[name] = arr
        self.ctx[0][name] = arr.ctypes.data
        return arr

    def bind_state(self, scheme_fields):
        """Point the context at the scheme's state arrays (λ, prescribed forces, work) and keep them."""
        c = self.ctx[0]
        self.keep.append(scheme_fields)
        for name in ("lam", "reaction"):
            arr = scheme_fields.array(name)
            c[name] = arr.ctypes.data if arr.size else self.vectors["out"].ctypes.data
        c["work"] = scheme_fields.array("work").ctypes.data

    def family_name(self, k):
        """The name of family k (for messages)."""
        return self.packed.families[k][0].NAME if 0 <= k < len(self.packed.families) else "?"
