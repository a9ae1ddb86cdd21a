"""Uniform gravity on bodies (:class:`Gravity`)."""
from __future__ import annotations

import copy

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps

from ...bodies.base import DENSE_LIMIT, check_finite_vector, keeps_methods
from .base import CONSERVATIVE, ForceElement

__all__ = ["Gravity"]


class Gravity(ForceElement):
    """Uniform gravity field acting on bodies.

    Parameters
    ----------
    g : array_like, shape (2,) or (3,)
        Acceleration of gravity in m/s², default (0, −9.81) (y up); spatial bodies need three
        components, e.g. (0, 0, −9.81) (z up).
    bodies : sequence of Body, optional
        Bodies it acts on; ``None`` (default) means every body of the scene.

    Notes
    -----
    V = −g · ∫ r dm, summed over the bodies; each body supplies its own
    :meth:`~skfem_flex.bodies.base.Body.gravity_potential`. For bodies whose
    positions are linear in q the gradient is constant and is built once.
    """

    conservative = True
    name = "gravity"

    def __init__(self, g=(0.0, -9.81), bodies=None):
        self.g = check_finite_vector("g", g)
        if self.g.size not in (2, 3):
            raise ValueError(f"g must have 2 (planar) or 3 (spatial) entries, got {self.g.size}: {g!r}")
        self.bodies = None if bodies is None else tuple(bodies)
        if self.bodies is None:
            return
        for b in self.bodies:
            dim = getattr(b, "dimension", 2)
            if dim != self.g.size:
                raise ValueError(f"gravity g = {tuple(self.g)} has {self.g.size} entries but body {b.name!r} "
                                 f"moves in {dim} dimensions: give g with {dim} entries")
        self._slices, self._const_grad, start = [], [], 0
        for b in self.bodies:
            self._slices.append(slice(start, start + b.n_dofs))
            start += b.n_dofs
            try:
                gam, _ = b.mass_moment()
                self._const_grad.append(-(self.g @ gam))
            except NotImplementedError:
                self._const_grad.append(None)
        self._n = start
        self._linear = all(c is not None for c in self._const_grad)

    def on(self, bodies):
        """The same field acting on ``bodies`` (used by the scene for ``bodies=None``); a subclass stays
        itself (a copy, set up again for ``bodies``)."""
        new = copy.copy(self)
        Gravity.__init__(new, self.g, bodies)
        return new

    def compiled_form(self):
        if not keeps_methods(self, Gravity, CONSERVATIVE):
            return None
        return "gravity", self.g

    def potential_energy(self, q):
        return sum(b.gravity_potential(q[s], self.g)[0] for b, s in zip(self.bodies, self._slices))

    def potential_gradient(self, q):
        out = np.empty(self._n)
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            out[s] = c if c is not None else b.gravity_potential(q[s], self.g)[1]
        return out

    def potential_hessian(self, q):
        if self._linear:
            return None
        return self._block_diagonal([None if c is not None else b.gravity_potential(q[s], self.g)[2]
                                     for b, s, c in zip(self.bodies, self._slices, self._const_grad)])

    def potential_discrete_gradient(self, q0, q1):
        if self._linear:
            return self.potential_gradient(q0), None
        g = np.empty(self._n)
        blocks = []
        for b, s, c in zip(self.bodies, self._slices, self._const_grad):
            if c is not None:
                g[s] = c
                blocks.append(None)
            else:
                gb, hb = b.gravity_discrete_gradient(q0[s], q1[s], self.g)
                g[s] = gb
                blocks.append(hb)
        return g, self._block_diagonal(blocks)

    def _block_diagonal(self, blocks):
        """Block diagonal of the bodies' blocks (None: zero block of that body's size).

        One body: its own block as it comes (dense stays dense, so that small scenes do no sparse
        work per Newton evaluation); several: dense if every block is and the total is small,
        sparse otherwise."""
        if len(blocks) == 1:
            return blocks[0]
        if self._n <= DENSE_LIMIT and not any(sps.issparse(blk) for blk in blocks):     # a small (dense) scene
            return sla.block_diag(*[np.zeros((b.n_dofs, b.n_dofs)) if blk is None else blk
                                    for b, blk in zip(self.bodies, blocks)])
        return sps.block_diag([sps.csr_matrix((b.n_dofs, b.n_dofs)) if blk is None else sps.csr_matrix(blk)
                               for b, blk in zip(self.bodies, blocks)], format="csr")
