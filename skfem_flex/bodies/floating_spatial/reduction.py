r"""Modal reduction of a :class:`~skfem_flex.bodies.floating_spatial.body.FloatingBeam3D`: y = Φ η.

A basis Φ (n_elastic × m) of the elastic coordinates turns every term of the body into the same term of the
reduced body, exactly: the invariants become S̄Φ, PΦ and ΦᵀN_ikΦ, the stiffness ΦᵀKΦ, the strain
points' derivative rows A_kΦ, a point's shape functions SΦ. Nothing is approximated beyond the choice of
Φ, so the reduced body conserves what the full one conserves.

The basis (:func:`reduction_basis`) is, by the body's reference condition:

- ``"clamped"`` — **Craig–Bampton** with the root as the interface (the frame is the root section, so the
  root's DOFs are already gone): the lowest fixed-interface (cantilever) modes, plus with ``"tip"`` among
  the ``interfaces`` the six static constraint modes of the tip's DOFs and fixed-interface modes with the
  tip held too;
- ``"chord"`` — **free-interface** modes of the beam in its chord frame.

With the Green–Lagrange axis two kinds of vectors join it, since bending modes alone cannot stretch or
shorten the axis, and a tension that cannot build up stiffens nothing:

- **stiffening derivatives** of the lowest ``n_derivatives`` modes: θ_ij = −K⁻¹ ∂³V[φ_i, φ_j, ·] at y = 0,
  the axial shortening that the quadratic strain couples to bending (the gradient of V is cubic in y,
  so the second difference (∇V(hφ) − 2∇V(0) + ∇V(−hφ))/h² is exact and gives ∂³V[φ, φ, ·]; the mixed
  terms come from φ_i ± φ_j);
- the **centrifugal shapes**: the static response K⁻¹ f to the inertia load f of a unit spin about each
  section axis d₁, d₂ (the stretch of a spinning blade).

The modes come M-orthonormal from ``eigh``; the other columns are made M-orthogonal to them and M-orthonormal
among themselves (:func:`m_complement`), the ones already spanned dropped.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["reduction_basis", "m_complement"]


def _count(name, value, low, high):
    if isinstance(value, bool) or int(value) != value or not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def _modes(K, M, keep, n):
    """The n lowest modes of (K, M) on the index set ``keep`` (others held at zero), as full columns.

    Coordinates without mass (a beam's section rotations with ρI = 0) are condensed out statically, exact when
    they carry no inertia: the modes of K_aa − K_ab K_bb⁻¹ K_ba with M_aa, each completed by −K_bb⁻¹ K_ba φ_a."""
    Kk, Mk = K[np.ix_(keep, keep)], M[np.ix_(keep, keep)]
    massless = ~np.any(Mk != 0.0, axis=1)
    if not massless.any():
        vecs = scipy.linalg.eigh(Kk, Mk, subset_by_index=(0, n - 1))[1]
    else:
        a, b = np.flatnonzero(~massless), np.flatnonzero(massless)
        if n > a.size:
            raise ValueError(f"{n} modes asked of a body with {a.size} coordinates that carry mass")
        recover = -scipy.linalg.solve(Kk[np.ix_(b, b)], Kk[np.ix_(b, a)], assume_a="sym")
        condensed = Kk[np.ix_(a, a)] + Kk[np.ix_(a, b)] @ recover
        va = scipy.linalg.eigh(0.5 * (condensed + condensed.T), Mk[np.ix_(a, a)], subset_by_index=(0, n - 1))[1]
        vecs = np.zeros((len(keep), n))
        vecs[a], vecs[b] = va, recover @ va
    out = np.zeros((K.shape[0], n))
    out[keep] = vecs
    return out


def _stiffening_derivatives(body, K, modes):
    """−K⁻¹ ∂³V[φ_i, φ_j, ·] for every pair of ``modes`` (module docstring)."""
    strain = body.strain_energy
    if not strain.nonlinear or modes.shape[1] == 0:
        return np.zeros((K.shape[0], 0))
    zero = np.zeros(K.shape[0])
    g0 = strain.gradient(zero)

    def second(phi):
        h = 1.0 / max(float(np.abs(phi).max()), 1e-300)
        return (strain.gradient(h * phi) - 2.0 * g0 + strain.gradient(-h * phi)) / (h * h)

    thirds = []
    k = modes.shape[1]
    for i in range(k):
        for j in range(i, k):
            if i == j:
                thirds.append(second(modes[:, i]))
            else:
                thirds.append(0.25 * (second(modes[:, i] + modes[:, j]) - second(modes[:, i] - modes[:, j])))
    # modes bending in different planes do not couple (u₁'u₂' is not in ε): their third derivative is round-off,
    # and scaled to unit length it would add a direction of noise
    size = np.array([np.abs(t).max() for t in thirds])
    kept = [t for t, n in zip(thirds, size) if n > 1e-8 * size.max()]
    return np.column_stack([-scipy.linalg.solve(K, t, assume_a="sym") for t in kept])


def _centrifugal_shapes(body, K):
    """K⁻¹ f of the inertia load of a unit spin about d₁ and about d₂ (module docstring)."""
    from .rotation import elastic_load_of_spin
    return np.column_stack([scipy.linalg.solve(K, -elastic_load_of_spin(body, axis), assume_a="sym")
                            for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))])


def m_complement(vectors, kept, mass, rtol=1e-10):
    """Columns spanning what ``vectors`` add to the span of ``kept``: M-orthogonal to ``kept`` and M-orthonormal
    among themselves, the ones already spanned dropped. A basis [kept, m_complement(...)] keeps every shape it
    was given and stays well conditioned; with M-orthonormal ``kept`` it is M-orthonormal as a whole."""
    if vectors.shape[1] == 0:
        return np.zeros((vectors.shape[0], 0))
    size = np.abs(vectors).max(axis=0)
    vectors = vectors / np.where(size > 0, size, 1.0)       # derivatives and static shapes differ by decades
    q, _ = np.linalg.qr(kept)
    vectors = vectors - q @ (q.T @ vectors)                  # in the Euclidean sense first: removes the bulk
    Mk = mass @ kept
    for _ in range(2):                                       # twice: once leaves round-off of the bulk behind
        vectors = vectors - kept @ np.linalg.solve(kept.T @ Mk, Mk.T @ vectors)
    gram = vectors.T @ (mass @ vectors)
    vals, vecs = np.linalg.eigh(0.5 * (gram + gram.T))
    keep = vals > rtol * vals.max()
    return vectors @ (vecs[:, keep] / np.sqrt(vals[keep]))


def reduction_basis(body, n_modes, interfaces=("root",), n_derivatives=None, centrifugal=None):
    """The basis Φ (n_elastic × m) of a reduced :class:`FloatingBeam3D` (module docstring).

    Parameters
    ----------
    body : FloatingBeam3D
        The full body (no basis of its own).
    n_modes : int
        Fixed-interface (clamped) or free-interface (chord) modes.
    interfaces : sequence of {"root", "tip"}
        Craig–Bampton interfaces: the root always (it is the frame); "tip" adds its constraint modes.
    n_derivatives : int, optional
        How many of the lowest modes give stiffening derivatives (every pair of them); default: all
        ``n_modes`` with the Green–Lagrange axis, none with the linear one.
    centrifugal : bool, optional
        Add the centrifugal shapes; default: with the Green–Lagrange axis.

    Raises
    ------
    ValueError
        For counts out of range or unknown interfaces.
    """
    if body.basis is not None:
        raise ValueError(f"body {body.name!r} is already reduced: reduce the full body")
    nonlinear = body.strain_energy.nonlinear
    nf = body.n_elastic
    n_modes = _count("n_modes", n_modes, 1, nf - 6)
    n_derivatives = _count("n_derivatives", (n_modes if nonlinear else 0) if n_derivatives is None else n_derivatives,
                           0, n_modes)
    centrifugal = nonlinear if centrifugal is None else bool(centrifugal)
    unknown = set(interfaces) - {"root", "tip"}
    if unknown:
        raise ValueError(f"interfaces must be among 'root', 'tip', got {sorted(unknown)}")
    K = body.strain_energy.hessian(np.zeros(nf))
    M = body.mass_matrix(body.q0)[12:, 12:]
    cols = []
    keep = np.arange(nf)
    if body.reference == "clamped" and "tip" in interfaces:
        tip = np.flatnonzero(np.isin(body.free_dofs, body.beam.node_dofs[-1]))
        inner = np.setdiff1d(keep, tip)
        static = np.zeros((nf, tip.size))
        static[tip] = np.eye(tip.size)
        static[inner] = -scipy.linalg.solve(K[np.ix_(inner, inner)], K[np.ix_(inner, tip)], assume_a="sym")
        cols.append(static)
        keep = inner
    elif body.reference == "chord" and tuple(interfaces) != ("root",):
        raise ValueError("the chord frame reduces by free-interface modes: give no interfaces beyond 'root'")
    modes = _modes(K, M, keep, n_modes)                       # M-orthonormal (eigh)
    if n_derivatives:
        cols.append(_stiffening_derivatives(body, K, modes[:, :n_derivatives]))
    if centrifugal:
        cols.append(_centrifugal_shapes(body, K))
    extra = np.column_stack(cols) if cols else np.zeros((nf, 0))
    return np.hstack([modes, m_complement(extra, modes, M)])
