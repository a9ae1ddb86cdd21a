r"""Reference conditions of a :class:`~skfem_flex.bodies.FloatingBeam`: which beam DOFs become q_f.

The frame coordinates (R, θ) already describe every rigid motion of the beam, so the elastic
coordinates q_f must not: a reference condition eliminates beam DOFs until none of the three
infinitesimal rigid modes (translation x, translation y, rotation about the frame origin) is left
in q_f. ``"clamped"`` eliminates u, w, φ at the root node (the frame is tangent to the root),
``"pinned"`` eliminates u, w at the root and w at the tip (chord frame); an explicit sequence of
(x, field) pairs may name any three DOFs that do the same.

Everything the body builds on q_f (inertia integrals, stiffness, axial quadrature) is a beam
operator restricted to the DOFs kept here (:func:`restrict`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps

__all__ = ["ElasticCoordinates", "elastic_coordinates", "reference_dofs", "restrict", "check_stiffness",
           "FIELDS", "FIELD_NAMES"]

#: field names a reference condition may use -> index of the field in a node's (u, w, φ)
FIELDS = {"u": 0, "w": 1, "theta": 2, "th": 2, "phi": 2}
#: the field part of the elastic coordinate names ("u3", "w3", "th3")
FIELD_NAMES = ("u", "w", "th")


@dataclass(frozen=True, eq=False)
class ElasticCoordinates:
    """The elastic coordinates q_f a reference condition leaves.

    Attributes
    ----------
    free_dofs : ndarray of int (n_elastic,)
        Beam DOFs kept, node-major: (u, w, φ) per node, nodes in the beam's node order; entry i is
        the beam DOF of q_f[i].
    fixed_dofs : ndarray of int (3,)
        Beam DOFs eliminated, in the order the reference condition names them.
    names : tuple of str
        ``"u1", "w1", "th1", ...`` (field and node number) for each entry of q_f.
    """

    free_dofs: np.ndarray
    fixed_dofs: np.ndarray
    names: tuple


def reference_dofs(beam, reference):
    """Beam DOFs a reference condition eliminates.

    Parameters
    ----------
    beam : TimoshenkoBeam
    reference : {"clamped", "pinned"} or sequence of (x, field)
        x in m along the beam, field in {"u", "w", "theta"} (see the module docstring).

    Returns
    -------
    ndarray of int (3,)

    Raises
    ------
    ValueError
        On an unknown name or field, a DOF named twice, a condition that leaves a rigid mode in
        q_f (singular elastic stiffness) or one that eliminates more than three DOFs.
    """
    x_min, x_max = float(beam.x_nodes[0]), float(beam.x_nodes[-1])
    if isinstance(reference, str):
        if reference == "clamped":
            spec = [(x_min, "u"), (x_min, "w"), (x_min, "theta")]
        elif reference == "pinned":
            spec = [(x_min, "u"), (x_min, "w"), (x_max, "w")]
        else:
            raise ValueError(f"reference must be 'clamped', 'pinned' or a sequence of (x, field) pairs, "
                             f"got {reference!r}")
    else:
        try:
            spec = [(float(x), str(f)) for x, f in reference]
        except (TypeError, ValueError):
            raise ValueError(f"reference must be 'clamped', 'pinned' or a sequence of (x, field) pairs, "
                             f"got {reference!r}") from None
    fixed = []
    for x, f in spec:
        if f not in FIELDS:
            raise ValueError(f"reference field must be one of 'u', 'w', 'theta', got {f!r}")
        fixed.append(int(beam.dofs_at(x)[FIELDS[f]]))
    fixed = np.array(fixed, dtype=int)
    if np.unique(fixed).size != fixed.size:
        raise ValueError(f"reference condition {reference!r} names a DOF twice")
    # infinitesimal rigid modes of the beam: translation x, translation y, rotation
    rig = np.zeros((beam.n_dofs, 3))
    nd = beam.node_dofs
    rig[nd[:, 0], 0] = 1.0
    rig[nd[:, 1], 1] = 1.0
    rig[nd[:, 1], 2] = beam.x_nodes
    rig[nd[:, 2], 2] = 1.0
    rank = np.linalg.matrix_rank(rig[fixed])
    if rank < 3:
        raise ValueError(f"reference condition {reference!r} leaves {3 - rank} rigid-body mode(s) in the "
                         f"elastic coordinates (singular elastic stiffness); fix u, w, theta at the root "
                         f"('clamped') or u, w at the root and w at the tip ('pinned')")
    if fixed.size > 3:
        raise ValueError(f"reference condition {reference!r} over-constrains the beam: it fixes "
                         f"{fixed.size} elastic DOFs, but only the 3 rigid-body modes may be removed")
    return fixed


def elastic_coordinates(beam, reference):
    """The :class:`ElasticCoordinates` of ``beam`` under ``reference`` (see :func:`reference_dofs`)."""
    fixed = reference_dofs(beam, reference)
    node_major = beam.node_dofs.ravel()              # (u, w, θ) per node, nodes along x
    fixed_set = set(fixed.tolist())
    free = np.array([d for d in node_major if d not in fixed_set], dtype=int)
    node_of = {}
    for i, dofs in enumerate(beam.node_dofs):
        for k, d in enumerate(dofs):
            node_of[int(d)] = (i, k)
    names = []
    for d in free:
        i, k = node_of[int(d)]
        names.append(f"{FIELD_NAMES[k]}{i}")
    return ElasticCoordinates(free, fixed, tuple(names))


def restrict(mat, free):
    """The rows and columns ``free`` of a beam matrix, CSR (a beam operator on q_f)."""
    return sps.csr_matrix(mat)[free][:, free].tocsr()


def check_stiffness(beam, K):
    """Check that the linear elastic stiffness K (sparse, on q_f) is regular to double precision.

    Only bodies up to 600 elastic coordinates are checked (a dense eigenvalue problem).

    Raises
    ------
    ValueError
        If K is singular to double precision, naming the section's stiffnesses per element (N/m).
    """
    if K.shape[0] <= 600:
        ev = np.linalg.eigvalsh(K.toarray())
        if not np.all(np.isfinite(ev)) or ev[0] <= 1e-13 * ev[-1]:
            # the reference condition removed the rigid modes (reference_dofs), so a singular K
            # means stiffnesses too far apart (or zero) for double precision
            sec, h = beam.section, beam.length / max(beam.mesh.t.shape[1], 1)
            raise ValueError(
                f"the elastic stiffness is singular to double precision (smallest/largest eigenvalue "
                f"{ev[0] / ev[-1] if ev[-1] else 0.0:.2g}): the section's stiffnesses per element, "
                f"EA/h = {sec.EA / h:.3g} N/m, kGA/h = {sec.kGA / h:.3g} N/m and EI/h³ = {sec.EI / h ** 3:.3g} N/m "
                f"(h = {h:.3g} m), must lie within about 10¹³ of each other and be positive; "
                f"change EA, kGA, EI or the number of elements")
