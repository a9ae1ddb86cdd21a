"""Node sets of a meshed body, for its interfaces: one rule for the planar and the spatial solids."""
from __future__ import annotations

import numpy as np

__all__ = ["select_nodes"]


def select_nodes(spec, positions, boundaries, boundary_nodes, body):
    """Node indices of a node-set spec.

    Parameters
    ----------
    spec : str, callable or array_like of int
        A named boundary of the mesh, a predicate ``X (dim, n) -> bool mask`` on the node positions, or node
        indices.
    positions : ndarray (n_nodes, dim)
        The node positions, m.
    boundaries : dict
        The mesh's named boundaries (``mesh.boundaries`` or an empty dict).
    boundary_nodes : callable
        ``facets -> node indices`` of one named boundary.
    body : str
        The body's name, for messages.

    Raises
    ------
    ValueError
        For an unknown boundary name, indices out of range or an empty set.
    """
    if isinstance(spec, str):
        if spec not in boundaries:
            raise ValueError(f"mesh of body {body!r} has no boundary {spec!r}; it has {sorted(boundaries)}")
        nodes = np.unique(boundary_nodes(boundaries[spec]))
    elif callable(spec):
        nodes = np.flatnonzero(np.asarray(spec(positions.T), dtype=bool))
    else:
        nodes = np.unique(np.asarray(spec, dtype=int).ravel())
        if nodes.size and (nodes.min() < 0 or nodes.max() >= positions.shape[0]):
            raise ValueError(f"node indices {spec!r} outside 0..{positions.shape[0] - 1}")
    if nodes.size == 0:
        raise ValueError(f"node set {spec!r} selects no nodes of body {body!r}")
    return nodes
