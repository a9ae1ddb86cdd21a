r"""A :class:`~skfem_flex.bodies.FloatingBeam`'s beam as an :class:`~skfem_flex.bodies.modal.body.ElasticModel`.

What model reduction (``reduction.py``) needs from the beam, on *all* its DOFs (u, w, φ per node,
no reference condition: reduction chooses its own): nodal mass and stiffness, the rigid fields
(translations, the undeformed positions, the rotary unit field on φ), the 90° turn Ê of the
displacement field, the interfaces ``"root"`` and ``"tip"`` (u, w, φ of the end nodes), the
Green–Lagrange axial strain with EA on the exact rule (its linear part is the axial part of the
beam stiffness) and the locate/output hooks of the reduced body.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from skfem import asm

from ...fem.forms import rotary_mass, translational_mass
from ..modal.body import ElasticModel, Interface
from ..modal.stiffening import GreenLagrange

__all__ = ["beam_elastic_model"]


def beam_elastic_model(body):
    """The :class:`~skfem_flex.bodies.modal.body.ElasticModel` of ``body.beam`` (module docstring).

    Parameters
    ----------
    body : FloatingBeam
        Gives the beam, its name and the shape functions at a point (the interfaces and
        ``locate``, which raises ValueError for a point off the axis).
    """
    beam, sec = body.beam, body.section
    n, nd = beam.n_dofs, beam.node_dofs
    trans = np.zeros((n, 2))
    trans[nd[:, 0], 0] = 1.0
    trans[nd[:, 1], 1] = 1.0
    pos = np.zeros(n)
    pos[nd[:, 0]] = beam.x_nodes
    unit = np.zeros(n)
    unit[nd[:, 2]] = 1.0
    turn = sps.csr_matrix((np.r_[-np.ones(len(nd)), np.ones(len(nd))],
                           (np.r_[nd[:, 0], nd[:, 1]], np.r_[nd[:, 1], nd[:, 0]])), shape=(n, n))
    qd = beam.quadrature
    nl, nel, nqp = qd.dNdx.shape
    rows = np.broadcast_to((np.arange(nel)[:, None] * nqp + np.arange(nqp))[None], (nl, nel, nqp))
    grads = [sps.csr_matrix((qd.dNdx.ravel(), (rows.ravel(), np.broadcast_to(
        beam.element_dofs[:, k::3].T[:, :, None], (nl, nel, nqp)).ravel())), shape=(nel * nqp, n))
        for k in (0, 1)]
    strain = GreenLagrange(grads, np.array([[1.0, 0.0]]), np.eye(2)[None], np.array([[sec.EA]]), qd.dx.ravel())
    itf = {}
    for label, x in (("root", body.x_min), ("tip", body.x_max)):
        itf[label] = Interface(label, np.array([x, 0.0]), sps.csr_matrix(body.full_shape_at(x)))
    order = np.argsort(beam.x_nodes)
    conn = np.stack([order[:-1], order[1:]], axis=1)

    def locate(X):
        if abs(X[1]) > 1e-9 * beam.length:
            raise ValueError(f"point {tuple(X)} is off the axis of beam {body.name!r} (y must be 0)")
        S = body.full_shape_at(X[0])
        return S[:2], S[2]

    def output(d):
        pts = np.stack([beam.x_nodes, np.zeros_like(beam.x_nodes)], axis=1)
        return pts, np.stack([d[nd[:, 0]], d[nd[:, 1]]], axis=1), [("line", conn)], {}

    return ElasticModel(mass=asm(translational_mass, beam.basis, rhoA=sec.rhoA).tocsr(),
                        stiffness=beam.stiffness(), translation=trans, position=pos, turn=turn,
                        interfaces=itf, rotary_mass=asm(rotary_mass, beam.basis, rhoI=sec.rhoI).tocsr(),
                        rotary_unit=unit, strain=strain, name=body.name, locate=locate, output=output)
