r"""Histories of a run, collected a chunk of recorded steps at a time; a :class:`~.result.Result` at any time.

Each history is a list of blocks (arrays whose first axis runs over records), joined once when a
Result is built: a chunk of a thousand records is stored as one array, not a thousand rows.
"""
from __future__ import annotations

import numpy as np

from ..io.result import Result

__all__ = ["Recorder"]

#: the histories, and the columns of the compiled records they come from
_KEYS = ("t", "q", "v", "lam", "kinetic", "potential", "external_work", "constraint_residual",
         "velocity_constraint_residual", "newton_iterations", "prescribed_force", "linear_momentum",
         "angular_momentum")


class Recorder:
    """Collects the histories of ``scene`` from blocks of compiled records.

    Parameters
    ----------
    scene : Scene
    packed : PackedScene
        Which probes the loop records (position maps) and which are called here.
    dim : int
        Space dimension of positions and momenta (2: planar).
    """

    def __init__(self, scene, packed):
        self.scene, self.packed, self.dim = scene, packed, getattr(scene, "dimension", 2)
        self.rows = {k: [] for k in _KEYS}
        self.probes = {k: [] for k in scene.probes}
        self.with_momentum = None
        self.reaction_rows = {name: [] for name in scene.reaction_names}
        self.count = 0
        #: records whose reactions are in reaction_rows: they are computed in batches when a result is
        #: made (a chain of 400 joints: 400 vectorized calls per batch, not per chunk of one step)
        self.reactions_done = 0

    def prefill(self, prior):
        """Start from the histories of an earlier run (``simulate(..., resume=...)``)."""
        for k in self.rows:
            val = getattr(prior, k, None)
            if val is not None:
                self.rows[k] = [np.asarray(val)]
        self.count = int(np.size(prior.t))
        self.with_momentum = prior.linear_momentum is not None
        for k in self.probes:
            if k not in prior.probes:
                raise ValueError(f"cannot resume: the earlier run has no probe {k!r}")
            self.probes[k] = [np.asarray(prior.probes[k])]
        for k in self.reaction_rows:
            if k in prior.reactions:
                self.reaction_rows[k] = [np.asarray(prior.reactions[k])]
        self.reactions_done = self.count

    def first(self, key):
        """The first record of history ``key``."""
        return self.rows[key][0][0]

    def last(self, key):
        """The last record of history ``key``."""
        return self.rows[key][-1][-1]

    def history(self, key):
        """History ``key`` as one array."""
        blocks = self.rows[key]
        return np.concatenate(blocks) if blocks else np.zeros(0)

    def add(self, records, start, stop):
        """Append records ``start … stop − 1`` of a chunk (:class:`~skfem_flex.compiled.loop.Records`)."""
        if stop <= start:
            return
        sl = slice(start, stop)
        s, d = self.scene, records.derived[sl]
        q, v, lam = records.q[sl], records.v[sl], records.lam[sl]
        block = {"t": records.t[sl], "q": q, "v": v, "lam": lam, "kinetic": d[:, 0], "potential": d[:, 1],
                 "external_work": records.work[sl], "constraint_residual": d[:, 8],
                 "velocity_constraint_residual": d[:, 9], "newton_iterations": records.iterations[sl],
                 "prescribed_force": records.reaction[sl]}
        if self.with_momentum is None:
            self.with_momentum = s.linear_momentum(q[0], v[0]) is not None
        if self.with_momentum:
            if self.dim == 2:
                block.update(linear_momentum=d[:, 2:4], angular_momentum=d[:, 7])
            else:
                block.update(linear_momentum=d[:, 2:5], angular_momentum=d[:, 5:8])
        for k, val in block.items():
            self.rows[k].append(np.array(val))
        maps = self.packed.probe_names
        recorded = {name: (first, count, combine) for name, first, count, combine in maps}
        for k, fn in s.probes.items():
            if k in recorded:
                first, count, combine = recorded[k]
                r = records.probes[sl, first:first + count, :self.dim]
                self.probes[k].append(np.array(r[:, 0]) if combine is None else np.asarray(combine(r)))
            else:
                self.probes[k].append(np.array([np.asarray(fn(s, t, qi, vi), dtype=float)
                                                for t, qi, vi in zip(records.t[sl], q, v)]))
        self.count += stop - start

    def _catch_up_reactions(self):
        """Compute the reactions of the records since the last batch, from their q and λ."""
        if self.reactions_done >= self.count:
            return
        s = self.scene
        q = self.history("q")[self.reactions_done - self.count:]
        lam = self.history("lam")[self.reactions_done - self.count:]
        for name, c, (idx, rows) in zip(s.reaction_names, s.constraints, s.constraint_layout):
            self.reaction_rows[name].append(np.asarray(c.reaction_history(q[:, idx], lam[:, rows]), dtype=float))
        self.reactions_done = self.count

    def last_energy(self):
        """(kinetic energy, potential energy, work done) of the last record, J."""
        return tuple(float(self.last(k)) for k in ("kinetic", "potential", "external_work"))

    def result(self, **meta):
        """The :class:`~.result.Result` of the records so far, with ``meta`` (wall time, scheme, …)."""
        r = {k: np.asarray(self.history(k), dtype=float) for k in self.rows}
        r["newton_iterations"] = np.asarray(self.history("newton_iterations"), dtype=int)
        if not self.with_momentum:
            r["linear_momentum"] = None
            r["angular_momentum"] = None
        self._catch_up_reactions()
        reactions = {k: np.asarray(np.concatenate(val) if val else np.zeros(0), dtype=float)
                     for k, val in self.reaction_rows.items()}
        probes = {k: np.concatenate(val) if val else np.zeros(0) for k, val in self.probes.items()}
        return Result(total_energy=r["kinetic"] + r["potential"], probes=probes, reactions=reactions, **r, **meta)
