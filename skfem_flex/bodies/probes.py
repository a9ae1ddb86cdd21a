"""Probes of one body's coordinates that the compiled loops can evaluate too.

A scene's probe is any callable ``(scene, t, q, v) -> value``. The first two classes here are
such callables with a ``compiled_map()`` (the position map forms of
:meth:`~skfem_flex.bodies.base.BodyPoint.compiled_map`): a compiled loop records them
itself instead of calling back into Python at every recorded step. A :class:`CombinedProbe`
computes a value from several of them; the loop records its parts and the combination is
applied once to a whole chunk of records.
"""
from __future__ import annotations

import numpy as np

__all__ = ["PointProbe", "LinearProbe", "CombinedProbe"]


class PointProbe:
    """The global position r (m) of a body point, shape (2,).

    Parameters
    ----------
    point : BodyPoint
        ``body.point(locator)``.
    """

    def __init__(self, point):
        self.point = point
        self.body = point.body

    def __call__(self, scene, t, q, v):
        return self.point.position(scene.coordinates(self.body, q))

    def compiled_map(self):
        """The point's position map (None if it has none)."""
        return self.point.compiled_map()


class LinearProbe:
    """A value linear in one body's coordinates: G q_b + c, shape (2,).

    Parameters
    ----------
    body : Body
    G : array_like (2, body.n_dofs)
    c : array_like (2,), optional
    """

    def __init__(self, body, G, c=None):
        self.body = body
        self.G = np.asarray(G, dtype=float).reshape(2, body.n_dofs)
        self.c = np.zeros(2) if c is None else np.asarray(c, dtype=float).reshape(2)

    def __call__(self, scene, t, q, v):
        return self.G @ scene.coordinates(self.body, q) + self.c

    def compiled_map(self):
        """("linear", G, c)."""
        return "linear", self.G, self.c


class CombinedProbe:
    """A value computed from several position probes: ``combine(r)``, r of shape (k, 2) the parts' values.

    Parameters
    ----------
    parts : sequence of PointProbe or LinearProbe
        The k probes whose values (2-vectors) are combined.
    combine : callable
        r (..., k, 2) -> value (...): must work on a stack of records (leading axes), e.g. the angle
        of the chord between two points, ``lambda r: np.arctan2(*(r[..., 1, ::-1] - r[..., 0, ::-1]))``.
    """

    def __init__(self, parts, combine):
        self.parts = tuple(parts)
        if not self.parts:
            raise ValueError("a CombinedProbe needs at least one part")
        self.combine = combine

    def __call__(self, scene, t, q, v):
        return self.combine(np.stack([np.asarray(p(scene, t, q, v), dtype=float) for p in self.parts]))
