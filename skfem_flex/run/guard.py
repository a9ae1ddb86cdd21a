"""The divergence rule: a run stops, with a DivergenceError, when its state leaves every sane bound."""
from __future__ import annotations

import math

import numpy as np

from ..errors import DivergenceError

__all__ = ["DivergenceGuard", "DIVERGENCE_FACTOR", "SCALE_RECORDS"]


#: a run is diverged when a coordinate exceeds this many times the scene's size, or the energy this
#: many times its initial scale plus the work done
DIVERGENCE_FACTOR = 1e6
#: recorded states over which the energy scale of the divergence rule is taken
SCALE_RECORDS = 10


class DivergenceGuard:
    """Stops runs whose solution left every sane bound (DivergenceError, "diverged at t = …").

    * a coordinate or velocity is not finite;
    * a coordinate exceeds 10⁶ × max(scene size, largest initial coordinate, 1) — lengths in m,
      angles in rad (a body spinning at 10 rad/s needs 10⁵ s to reach it);
    * a coordinate exceeds its body's own bound (``body.divergence_bounds()``, where a body gives one:
      a floating-frame body's elastic coordinates beyond 10 × its length are no small deformation),
      checked at every recorded state;
    * |T + V| exceeds 10⁶ × (E_s + max |W|), W the work done so far and E_s the largest |T| + |V|
      of the first :data:`SCALE_RECORDS` recorded states (the scale a run released from rest
      establishes in its first steps; energy-conserving schemes keep T + V = E₀ + W, so this
      catches the others).
    """

    def __init__(self, scene, q0, kinetic, potential, work):
        """``q0``: the first recorded coordinates; ``kinetic``, ``potential``, ``work``: the records so far
        (J; at least one)."""
        q0 = np.asarray(q0, dtype=float)
        size = max(float(scene.length_scale), float(np.max(np.abs(q0), initial=0.0)), 1.0)
        self.q_bound = DIVERGENCE_FACTOR * size
        kinetic, potential = np.asarray(kinetic, dtype=float), np.asarray(potential, dtype=float)
        self.e_scale = float(np.max(np.abs(kinetic[:SCALE_RECORDS]) + np.abs(potential[:SCALE_RECORDS])))
        self.w_max = float(np.max(np.abs(np.asarray(work, dtype=float)), initial=0.0))
        self.count = kinetic.size
        bounds = np.full(scene.n, np.inf)
        self.owner = {}
        for body in scene.bodies:
            own = getattr(body, "divergence_bounds", None)
            own = own() if callable(own) else None
            if own is not None:
                sl = scene.slice(body)
                bounds[sl] = np.minimum(bounds[sl], np.asarray(own, dtype=float))
                self.owner.update({i: body for i in range(sl.start, sl.stop)})
        self.bounds = bounds if np.isfinite(bounds).any() else None

    def first_bound_violation(self, t, q):
        """(index, DivergenceError) of the first recorded state beyond a body's own bound, or None: times
        ``t`` (s), coordinates ``q`` (records, n)."""
        if self.bounds is None or not t.size:
            return None
        over = np.abs(q) > self.bounds
        if not over.any():
            return None
        k, i = np.unravel_index(int(np.argmax(over)), over.shape)
        body = self.owner[i]
        local = i - self._start(body)
        names = getattr(body, "coordinate_names", None)
        label = f"{names[local]!r}" if names is not None and local < len(names) else f"{local}"
        return int(k), DivergenceError(
            f"diverged at t = {t[k]:.6g} s: coordinate {label} of body {body.name!r} reached {q[k, i]:.3g}, "
            f"beyond the body's bound {self.bounds[i]:.3g} (no small deformation any more)")

    def _start(self, body):
        return min(i for i, b in self.owner.items() if b is body)

    def check_state(self, t, q, v):
        """Raise a DivergenceError if the state (q, v) at time t (s) is not finite or beyond the scene's size."""
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            raise DivergenceError(f"diverged at t = {t:.6g} s: the state is not finite")
        big = float(np.max(np.abs(q), initial=0.0))
        if big > self.q_bound:
            raise DivergenceError(f"diverged at t = {t:.6g} s: a coordinate reached {big:.3g}, more than "
                                  f"{DIVERGENCE_FACTOR:.0e} times the scene's size ({self.q_bound / DIVERGENCE_FACTOR:.3g})")

    def first_energy_violation(self, t, kinetic, potential, work):
        """Index of the first record of a compiled block (not yet stored) at which :meth:`check_energy`
        would stop the run, or None; the guard's energy scale and work bound advance over the
        records before it (then store the block up to that record and call :meth:`check_energy`)."""
        first = self.count                                     # index of the block's first record
        n_early = min(t.size, max(0, SCALE_RECORDS - first))  # these still set the scale: in order
        for i in range(n_early):
            w_max = max(self.w_max, abs(work[i]))
            e_scale = max(self.e_scale, abs(kinetic[i]) + abs(potential[i]))
            if self._violated(kinetic[i] + potential[i], e_scale + w_max):
                return i
            self.w_max, self.e_scale = w_max, e_scale
            self.count += 1
        if n_early == t.size:
            return None
        w_max = np.maximum.accumulate(np.fmax(np.abs(work[n_early:]), self.w_max))
        energy = kinetic[n_early:] + potential[n_early:]
        scale = self.e_scale + w_max
        bad = ~np.isfinite(energy) | ((scale > 0) & (np.abs(energy) > DIVERGENCE_FACTOR * scale))
        if bad.any():
            i = int(np.argmax(bad))
            if i:
                self.w_max = float(w_max[i - 1])
            self.count += i
            return n_early + i
        self.w_max = float(w_max[-1])
        self.count += t.size - n_early
        return None

    @staticmethod
    def _violated(energy, scale):
        return not math.isfinite(energy) or (scale > 0 and abs(energy) > DIVERGENCE_FACTOR * scale)

    def check_energy(self, t, kinetic, potential, work):
        """The energy rule at the next record: time ``t`` (s), kinetic and potential energy and the
        work done so far (J)."""
        self.count += 1
        self.w_max = max(self.w_max, abs(work))
        energy = kinetic + potential
        if self.count <= SCALE_RECORDS:
            self.e_scale = max(self.e_scale, abs(kinetic) + abs(potential))
        scale = self.e_scale + self.w_max
        if self._violated(energy, scale):
            raise DivergenceError(f"diverged at t = {t:.6g} s: energy {energy:.3g} J against an initial energy "
                                  f"scale plus work done of {scale:.3g} J")
