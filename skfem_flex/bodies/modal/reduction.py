r"""Component-mode reduction of an :class:`~skfem_flex.bodies.modal.body.ElasticModel`.

Two bases, both computed once with scipy (shift-invert ``eigsh``, sparse LU):

* **Craig–Bampton** (:func:`craig_bampton`): the interface points are made explicit DOFs
  u_b (each interface's displacement and rotation, through its coupling P), the rest are
  interior DOFs d_o. The basis is the static constraint modes Ψ = −K_oo⁻¹ K_ob (one per interface
  DOF: unit motion of it, the other interfaces held) and the lowest fixed-interface normal modes
  K_oo φ = ω² M_oo φ. Joint reactions load a body only at its interfaces, so the constraint modes
  hold the quasi-static deformation exactly.
* **free-interface normal modes** (:func:`free_modes`): the lowest elastic modes of the free body.

Green–Lagrange stiffening needs the axial (membrane) response that bending couples to; a basis
of bending modes alone cannot shorten its chord and locks. :func:`reduce` therefore adds, for
Green–Lagrange bodies, static **modal derivatives** θ_ij = −K_oo⁻¹ ∂²f/∂η_i∂η_j (the second-order
static response, interfaces held) of every pair of a derivative set: the constraint modes of the
interfaces other than the one carrying the frame (they hold the large bending of a link jointed
at both ends), or, for a body held at its reference interface only, the lowest fixed-interface
modes; and on request the static response to a centrifugal load ρX.

The reduced body (:class:`~skfem_flex.bodies.modal.body.ModalBody`) needs a reference condition that
takes the rigid motion out of the basis:

* ``"interface"`` (default when the body has an interface with a rotation): the frame is attached
  to that interface, Φ ← Φ − R (P_k R)⁻¹ P_k Φ. Joints at that interface see no elastic
  coordinates at all and the basis keeps the constraint modes of the others — the natural choice
  for links in mechanisms.
* ``"mean-axes"`` (Tisserand/Buckens; default otherwise): Φ ← Φ − R (RᵀMR)⁻¹ RᵀMΦ, so ∫ρu = 0
  and ∫ρX × u = 0; the frame follows the mean motion (best for free-flying bodies).

The projected basis is finally made M-orthonormal and diagonalised (dependent columns dropped),
so η are the modal coordinates of the reduced body and ``body.frequencies`` its frequencies.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from .body import ElasticModel, ModalBody

__all__ = ["CraigBampton", "craig_bampton", "free_modes", "modal_derivatives", "reduce", "full_body"]

#: below this size eigenproblems are solved dense
DENSE_EIGEN = 200


def _count(name, value, low, high):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def _lowest_modes(K, M, k, sigma=0.0):
    """The k lowest (ω², φ) of K φ = ω² M φ (shift-invert eigsh, dense for small systems)."""
    n = K.shape[0]
    if n <= DENSE_EIGEN or k >= n - 1:
        lam, vec = sla.eigh(K.toarray() if sps.issparse(K) else K, M.toarray() if sps.issparse(M) else M)
    else:
        lam, vec = spla.eigsh(sps.csc_matrix(K), k=k, M=sps.csc_matrix(M), sigma=sigma, which="LM")
    order = np.argsort(lam)[:k]
    return lam[order], vec[:, order]


@dataclass
class CraigBampton:
    """A Craig–Bampton basis.

    Attributes
    ----------
    basis : ndarray (n_dofs, n_b + n_modes)
        Constraint modes (one per interface DOF, in interface order) then fixed-interface modes.
    n_boundary : int
    interfaces : list of str
    frequencies : ndarray (n_modes,)
        Fixed-interface natural frequencies, rad/s.
    interior : sparse (n_dofs, n_o)
        T_o: the interior DOFs in the full vector (interfaces held), for further static modes.
    solve_interior : callable
        f_o ↦ K_oo⁻¹ f_o (factorised once).
    """

    basis: np.ndarray
    n_boundary: int
    interfaces: list
    frequencies: np.ndarray
    interior: object
    solve_interior: object

    def boundary_columns(self, model, name):
        """(first column, count) of the constraint modes of interface ``name`` in :attr:`basis`."""
        start = 0
        for nm in self.interfaces:
            size = model.interface(nm).P.shape[0]
            if nm == name:
                return start, size
            start += size
        raise ValueError(f"interface {name!r} is not among the Craig–Bampton interfaces {self.interfaces}")

    def reduced_matrices(self, model):
        """(ΦᵀKΦ, ΦᵀMΦ) of the whole basis (M with rotary inertia)."""
        B = self.basis
        return B.T @ (model.stiffness @ B), B.T @ (model.total_mass() @ B)


def _coupling(model, names):
    """T = [T_o, T_b] with d = T_o d_o + T_b u_b: every interface's P-rows become explicit DOFs u_b.

    An averaging interface eliminates as many "slave" DOFs among those it couples as it has rows
    (QR with column pivoting picks a well-conditioned set): d_s = P_s⁻¹ (u_I − P_o d_o). A rigid
    interface eliminates its whole node set: d_s = rigid_map u_I."""
    n = model.n_dofs
    slaves, blocks = [], []
    for name in names:
        itf = model.interface(name)
        P = sps.csr_matrix(itf.P)
        r = P.shape[0]
        if itf.rigid_dofs is not None:
            s = np.asarray(itf.rigid_dofs, dtype=int)
        else:
            cols = np.unique(P.indices)
            _, R, piv = sla.qr(P[:, cols].toarray(), pivoting=True, mode="economic")
            if cols.size < r or abs(R[r - 1, r - 1]) <= 1e-12 * abs(R[0, 0]):
                raise ValueError(f"interface {name!r} of body {model.name!r} has a singular coupling "
                                 f"(its {r} rows are not independent)")
            s = cols[piv[:r]]
        if np.intersect1d(s, np.concatenate(slaves) if slaves else []).size:
            raise ValueError(f"interface {name!r} shares its DOFs with another interface of body {model.name!r}")
        slaves.append(s)
        blocks.append((itf, P, s))
    slave = np.concatenate(slaves) if slaves else np.zeros(0, dtype=int)
    other = np.setdiff1d(np.arange(n), slave)
    n_o, n_b = other.size, sum(P.shape[0] for _, P, _ in blocks)
    col_of = -np.ones(n, dtype=int)
    col_of[other] = np.arange(n_o)
    rows, cols, vals = [other], [np.arange(n_o)], [np.ones(n_o)]
    b0 = 0
    for itf, P, s in blocks:
        r = P.shape[0]
        if itf.rigid_dofs is not None:               # the whole set follows the interface rigidly
            rows.append(np.repeat(s, r)), cols.append(np.tile(n_o + b0 + np.arange(r), s.size))
            vals.append(np.asarray(itf.rigid_map, dtype=float)[:, :r].ravel())
            b0 += r
            continue
        Ps_inv = np.linalg.inv(P[:, s].toarray())
        Pc = P.tocoo()
        other_entry = ~np.isin(Pc.col, s)
        a, c, p = Pc.row[other_entry], Pc.col[other_entry], Pc.data[other_entry]
        if np.any(col_of[c] < 0):
            raise ValueError(f"interfaces of body {model.name!r} overlap (a coupling reads another's slave DOF)")
        # slave rows: −P_s⁻¹ P_o on the interior columns, P_s⁻¹ on this interface's master columns
        rows.append(np.repeat(s, a.size)), cols.append(np.tile(col_of[c], r))
        vals.append((-Ps_inv[:, a] * p).ravel())
        rows.append(np.repeat(s, r)), cols.append(np.tile(n_o + b0 + np.arange(r), r)), vals.append(Ps_inv.ravel())
        b0 += r
    T = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n_o + n_b))
    return T[:, :n_o].tocsc(), T[:, n_o:].tocsc()


def craig_bampton(model, interfaces, n_modes):
    """The Craig–Bampton basis of ``model`` for the named interfaces and ``n_modes`` fixed-interface modes.

    Raises
    ------
    ValueError
        Unknown interface, ``n_modes`` not in [0, interior DOFs], or interfaces that do not hold
        the body (K_oo singular).
    """
    if not isinstance(model, ElasticModel):
        raise ValueError(f"craig_bampton needs an ElasticModel, got {model!r}")
    names = list(interfaces)
    if not names:
        raise ValueError("craig_bampton needs at least one interface")
    To, Tb = _coupling(model, names)
    n_modes = _count("n_modes", n_modes, 0, To.shape[1] - 1)
    K, M = model.stiffness, model.total_mass()
    Koo = (To.T @ K @ To).tocsc()
    Kob = (To.T @ K @ Tb).toarray()
    lu = spla.splu(Koo)
    # one right-hand side at a time: SuperLU's multi-column solve was ~100× slower here (scipy 1.x)
    Psi = -np.column_stack([lu.solve(np.ascontiguousarray(Kob[:, j])) for j in range(Kob.shape[1])])
    if not np.all(np.isfinite(Psi)) or np.abs(Koo @ Psi + Kob).max() > 1e-6 * max(np.abs(Kob).max(), 1e-300):
        raise ValueError(f"interfaces {names} do not hold body {model.name!r} (K_oo is singular: a rigid motion "
                         f"leaves them fixed); give an interface with a rotation or two interfaces")
    freqs = np.zeros(0)
    cols = [To @ Psi + Tb.toarray()]
    if n_modes:
        lam, phi = _lowest_modes(Koo, (To.T @ M @ To).tocsc(), n_modes)
        freqs = np.sqrt(np.clip(lam, 0.0, None))
        cols.append(To @ phi)
    return CraigBampton(np.hstack(cols), Tb.shape[1], names, freqs, To, lu.solve)


def free_modes(model, n_modes):
    """(frequencies (rad/s), shapes (n_dofs, n_modes)) of the ``n_modes`` lowest elastic free–free modes.

    Solved about a small negative shift so that the three rigid modes stay regular; they are dropped.
    """
    n = model.n_dofs
    n_modes = _count("n_modes", n_modes, 1, n - 3)
    K, M = model.stiffness, model.total_mass()
    scale = abs(K.diagonal()).max() / abs(M.diagonal()).max()
    lam, vec = _lowest_modes(K, M, n_modes + 3, sigma=-1e-3 * scale)
    return np.sqrt(np.clip(lam[3:], 0.0, None)), vec[:, 3:]


def modal_derivatives(model, cb, n_modes, interfaces=()):
    """Static modal derivatives θ_ij = −K_oo⁻¹ ∂²f/∂η_i∂η_j of a set of Craig–Bampton basis vectors.

    The set is the ``n_modes`` lowest fixed-interface modes followed by the constraint modes of the
    named ``interfaces`` (all of each interface's DOFs); every pair i ≤ j of the set gives one
    derivative. ∂²f is the second derivative of the Green–Lagrange internal force at d = 0
    (:meth:`~skfem_flex.bodies.modal.stiffening.GreenLagrange.second_derivative`); the interfaces are held.
    A constraint mode is a meaningful strain field only if the frame sits at an interface that it
    holds (:func:`reduce` passes the interfaces other than the reference one).
    Returns (n_dofs, ≤ k(k+1)/2) for a set of k vectors: a derivative whose displacement gradients
    stay below 1e-8 of the product of its pair's is round-off of a vanishing second-order force (a
    beam's axial constraint mode with itself) and is left out, since the basis scaling would blow
    it up to a spurious field."""
    if model.strain is None:
        raise ValueError(f"model {model.name!r} has no Green–Lagrange strain data for modal derivatives")
    cols = list(range(cb.n_boundary, cb.n_boundary + n_modes))
    for name in interfaces:
        if name not in cb.interfaces:
            raise ValueError(f"interface {name!r} is not among the Craig–Bampton interfaces {cb.interfaces}")
        start, count = cb.boundary_columns(model, name)
        cols.extend(range(start, start + count))
    phi = cb.basis[:, cols]
    G = model.strain.gradients

    def size(d):                                      # largest displacement gradient of the field d
        return max(np.abs(Gk @ d).max() for Gk in G)
    sizes = [size(phi[:, i]) for i in range(phi.shape[1])]
    out = []
    for i in range(phi.shape[1]):
        for j in range(i, phi.shape[1]):
            f = model.strain.second_derivative(phi[:, i], phi[:, j])
            theta = cb.interior @ (-cb.solve_interior(cb.interior.T @ f))
            if size(theta) > 1e-8 * sizes[i] * sizes[j]:
                out.append(theta)
    return np.column_stack(out) if out else np.zeros((model.n_dofs, 0))


def _reference_interface(model, reference, interfaces):
    """The interface that carries the frame (None for mean axes) for a ``reference`` argument of :func:`reduce`."""
    if reference is None:
        reference = "interface" if any(model.interface(n).has_rotation for n in interfaces) else "mean-axes"
    if reference == "mean-axes":
        return None
    if reference == "interface":
        name = next((n for n in interfaces if model.interface(n).has_rotation), None)
        if name is None:
            raise ValueError(f"reference='interface' needs an interface with a rotation; body {model.name!r} has "
                             f"{list(interfaces)}")
        return name
    if isinstance(reference, str) and reference in model.interfaces:
        if not model.interface(reference).has_rotation:
            raise ValueError(f"interface {reference!r} has no rotation and cannot carry the body frame")
        return reference
    raise ValueError(f"reference must be 'interface', 'mean-axes' or an interface name of body {model.name!r} "
                     f"{sorted(model.interfaces)}, got {reference!r}")


def _reference(model, B, reference, interfaces):
    """Remove the rigid motion from the columns of B; returns (projected B, reference name)."""
    R = model.rigid_modes()
    name = _reference_interface(model, reference, interfaces)
    if name is None:
        MR = model.total_mass() @ R
        return B - R @ np.linalg.solve(R.T @ MR, MR.T @ B), "mean-axes"
    P = model.interface(name).P
    return B - R @ np.linalg.solve(np.asarray(P @ R), np.asarray(P @ B)), f"interface {name}"


def _derivative_interfaces(selection, strain, frame, names):
    """Interfaces whose constraint modes join the modal-derivative set (see :func:`reduce`)."""
    others = [n for n in names if n != frame]
    if selection is None:
        return others if strain == "green-lagrange" and frame in names else []
    if selection is False:
        return []
    if frame not in names:
        raise ValueError("interface_derivatives needs the body frame attached to one of the reduction's interfaces "
                         f"(reference='interface' or the name of one of {names}); the frame is "
                         f"{'mean axes' if frame is None else repr(frame)}")
    if selection is True:
        return others
    if isinstance(selection, str):
        selection = [selection]
    chosen = list(selection)
    for nm in chosen:
        if nm not in others:
            raise ValueError(f"interface_derivatives must name interfaces of the reduction other than the reference "
                             f"{frame!r}: one of {others}, got {nm!r}")
    if len(set(chosen)) != len(chosen):
        raise ValueError(f"interface_derivatives names an interface twice: {chosen}")
    return chosen


def _modal_form(model, B, expected=None):
    """M-orthonormal modes (ascending frequency) spanning the columns of B, dependent columns dropped."""
    K, M = model.stiffness, model.total_mass()
    Mr = B.T @ (M @ B)
    Mr = 0.5 * (Mr + Mr.T)
    mu, V = np.linalg.eigh(Mr)
    keep = mu > 1e-10 * mu.max()
    W = V[:, keep] / np.sqrt(mu[keep])
    Kr = W.T @ (B.T @ (K @ B)) @ W
    lam, Z = np.linalg.eigh(0.5 * (Kr + Kr.T))
    Phi = B @ (W @ Z)
    big = np.argmax(np.abs(Phi), axis=0)
    Phi *= np.sign(Phi[big, np.arange(Phi.shape[1])])
    return Phi, np.sqrt(np.clip(lam, 0.0, None))


def reduce(model, n_modes, interfaces=None, method=None, reference=None, strain="green-lagrange",
           n_derivatives=None, centrifugal=False, interface_derivatives=None, **body_kwargs):
    """A reduced :class:`~skfem_flex.bodies.modal.body.ModalBody` of ``model``.

    Parameters
    ----------
    model : ElasticModel
    n_modes : int
        Fixed-interface modes (Craig–Bampton) or free-interface elastic modes.
    interfaces : sequence of str, optional
        Interfaces to keep exact (default: all of the model's, in order).
    method : {"craig-bampton", "free"}, optional
        Default "craig-bampton" when there are interfaces, else "free".
    reference : {"interface", "mean-axes"} or interface name, optional
        Reference condition (module docstring); default "interface" if an interface has a rotation.
    strain : {"green-lagrange", "linear"}
    interface_derivatives : bool or sequence of str, optional
        Interfaces whose constraint modes join the modal-derivative set (Craig–Bampton with the frame
        at one of the ``interfaces`` only). Default: for Green–Lagrange bodies every interface other
        than the reference one, for linear ones none; ``True``/``False``: all of those / none.
    n_derivatives : int, optional
        Number of lowest fixed-interface modes in the modal-derivative set (Craig–Bampton only).
        Default: for Green–Lagrange bodies all n_modes if the set has no constraint modes (a body held
        at its reference interface only, e.g. a clamped blade), else 0; 0 for linear bodies.
        The derivatives of every pair of the set join the basis, k(k + 1)/2 for a set of k: a link
        with joints at both ends (3 modes, frame at one end) gets the 6 of the other end's three
        constraint modes, 12 coordinates in all; ``interface_derivatives=False`` gives the 6 of the
        3 modes instead; ``n_derivatives=3`` with the defaults all 21 (docs/flexible_bodies.md §4).
    centrifugal : bool
        Add the static response to the centrifugal load ρX (interfaces held; Craig–Bampton only).
    **body_kwargs
        Initial state and name, passed to :class:`ModalBody`.

    Raises
    ------
    ValueError
        n_modes larger than the available DOFs, unknown interfaces or method, a basis that cannot
        hold the body (see :func:`craig_bampton`), interface derivatives without the frame at an
        interface or naming the reference interface.
    """
    if not isinstance(model, ElasticModel):
        raise ValueError(f"reduce needs an ElasticModel, got {model!r}")
    names = list(model.interfaces) if interfaces is None else list(interfaces)
    for nm in names:
        model.interface(nm)
    method = method or ("craig-bampton" if names else "free")
    if method == "craig-bampton":
        cb = craig_bampton(model, names, n_modes)
        parts = [cb.basis]
        frame = _reference_interface(model, reference, names)
        itf = _derivative_interfaces(interface_derivatives, strain, frame, names)
        if n_derivatives is None:
            n_derivatives = n_modes if strain == "green-lagrange" and not itf else 0
        nd = _count("n_derivatives", n_derivatives, 0, n_modes)
        if nd or itf:
            parts.append(modal_derivatives(model, cb, nd, itf))
        if centrifugal:
            f = model.mass @ model.position
            parts.append((cb.interior @ cb.solve_interior(cb.interior.T @ f))[:, None])
        B = np.hstack(parts)
    elif method == "free":
        if n_derivatives or interface_derivatives or centrifugal:
            raise ValueError("modal derivatives and centrifugal static modes need method='craig-bampton'")
        _, B = free_modes(model, n_modes)
    else:
        raise ValueError(f"method must be 'craig-bampton' or 'free', got {method!r}")
    B = B / np.maximum(np.abs(B).max(axis=0), 1e-300)
    B, ref = _reference(model, B, reference, names)
    Phi, freqs = _modal_form(model, B)
    return ModalBody(model, Phi, strain=strain, reference=ref, frequencies=freqs, **body_kwargs)


#: most DOFs of an unreduced (dense) floating-frame body made by :func:`full_body`
UNREDUCED_LIMIT = 4000


def full_body(model, reference=None, strain="linear", **body_kwargs):
    """The unreduced :class:`ModalBody` of ``model`` (Φ spans every DOF; only the reference condition applied).

    ``reference="interface"`` (default when an interface has a rotation) eliminates that interface's
    DOFs by its coupling, ``"mean-axes"`` projects the rigid motion out in the mass metric.

    The unreduced body is dense (its floating-frame invariants couple every DOF), so it is
    refused above :data:`UNREDUCED_LIMIT` DOFs, with a ``ValueError`` that says so, before
    anything of size n × n is allocated: such meshes are what :func:`reduce` is for."""
    if model.n_dofs > UNREDUCED_LIMIT:
        raise ValueError(f"an unreduced floating-frame body is dense (n × n invariants): body {model.name!r} has "
                         f"{model.n_dofs} DOFs, more than {UNREDUCED_LIMIT}; reduce it (body.reduced(n_modes=...), "
                         f"or body='plane-stress-modal' in the catalogue scenes) or use a coarser mesh")
    names = list(model.interfaces)
    name = _reference_interface(model, reference, names)
    if name is None:                                  # mean axes
        B, ref = _reference(model, np.eye(model.n_dofs), "mean-axes", names)
        Phi, freqs = _modal_form(model, B)
        return ModalBody(model, Phi, strain=strain, reference=ref, frequencies=freqs, **body_kwargs)
    To, _ = _coupling(model, [name])
    return ModalBody(model, To, strain=strain, reference=f"interface {name}", **body_kwargs)
