r"""Floating frame of reference (FFR): a Timoshenko beam in large overall motion.

A :class:`FloatingBeam` carries the coordinates of a body frame, q_r = (R_x, R_y, θ),
and elastic coordinates q_f of a :class:`~skfem_flex.beam.TimoshenkoBeam` measured in that
frame. A material point of the axis at x is at (Liu & Yun, eqs. 10–11, 31–33)

.. math::

    r(x) = R + A(θ)\,(x_0 + S(x)\,q_f),\qquad x_0 = (x, 0),

where S(x) = [N_u; N_w] maps q_f to the axial and transverse displacement (u, w); the
cross-section turns by θ + N_φ(x) q_f. Reference conditions remove the rigid-body modes
from q_f: ``"clamped"`` eliminates u, w, φ at the root node (the frame is tangent to the
root), ``"pinned"`` eliminates u, w at the root and w at the tip (chord frame).

Kinetic energy T = ½ ∫ ρA |ṙ|² + ρI (θ̇ + φ̇)² dx = ½ q̇ᵀ M(q) q̇ (eqs. 14–17) with

.. math::

    M = \begin{bmatrix} m I & A E \bar s & A \bar S \\
                        \cdot & J(q_f) & a(q_f)^T \\
                        \cdot & \cdot & M_{ff} \end{bmatrix},\quad
    \begin{aligned}
    \bar s &= S_0 + \bar S q_f, &  J &= I_{00} + J_r + 2 c^T q_f + q_f^T M_A q_f,\\
    a &= k_0 + n_φ + H q_f, & M_{ff} &= M_A + M_I,
    \end{aligned}

E = [[0, −1], [1, 0]], built from inertia shape integrals that scikit-fem assembles once:
m = ∫ρA, S_0 = ∫ρA x_0, I_00 = ∫ρA x², S̄ = ∫ρA S, c = ∫ρA Sᵀx_0, k_0 = ∫ρA SᵀE x_0,
M_A = ∫ρA SᵀS, H = ∫ρA SᵀE S (skew), J_r = ∫ρI, n_φ = ∫ρI N_φ, M_I = ∫ρI N_φᵀN_φ.
Only the reference rows and columns depend on q; M_ff is constant.

Quadratic-velocity force (eq. 26, Q_v = ∂T/∂q − Ṁ q̇), with ω = θ̇, f = q̇_f and
c_m = c + M_A q_f::

    Q_R = A (ω² s̄ − 2 ω E S̄ f),   Q_θ = −2 ω c_m · f,   Q_f = ω² c_m − 2 ω H f

(centrifugal ω² c_m, Coriolis −2ωHf; no term depends on Ṙ).

Strain energy: bending EI κ², κ = φ', and shear kGA γ², γ = w' − φ, as in the linear beam
(constant matrices from scikit-fem); axial EA ε² with the Green–Lagrange strain
ε = u' + ½(u'² + w'²) (``strain="green-lagrange"``, default) or ε = u' (``strain="linear"``,
which misses the centrifugal stiffening). The nonlinear axial kernel is vectorised over
elements on the beam's precomputed quadrature arrays; nothing is assembled in the time loop.

Discrete gradients for the energy-conserving scheme (``docs/energy_scheme.md``) are
exact closed forms: stress at the mean strain for V, and for G(q) = ½ v₀ᵀ M(q) v₁ the identities
A(θ₁) − A(θ₀) = sinc(Δθ/2) A(θ_m) E Δθ and (A(θ₀) + A(θ₁))/2 = cos(Δθ/2) A(θ_m). Energy and
linear momentum are then conserved to round-off; angular momentum only to O(Δt²) (bounded, about
1e-6 relative at Δt = 1e-3 s): the frozen-velocity G is not invariant under rotations of the whole
system. The analytic tangents include the derivatives of sinc and cos.

Choice of frame: the clamped (root-tangent) frame has a stiff "frame turns, root counter-turns"
mode of little inertia; a free-flying body integrates with fewer Newton iterations and larger steps
in the chord frame (``reference="pinned"``).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla
from skfem import BilinearForm, LinearForm, asm

from ..beam import TimoshenkoBeam
from ..forces import ForceElement
from ..forms import bending, shear, translational_mass, rotary_mass
from . import floating_kernel as _kernel
from .base import DENSE_LIMIT, BodyGeometry, check_finite_vector, to_dense
from .ffr import FloatingFrame, FramePoint
from .rigid import E_MATRIX as E2, rotation as _rot

__all__ = ["FloatingBeam", "DistributedLoad"]

_FIELDS = {"u": 0, "w": 1, "theta": 2, "th": 2, "phi": 2}
_FIELD_NAMES = ("u", "w", "th")


# ---------------------------------------------------------------- scikit-fem forms (assembled once)
@BilinearForm
def skew_inertia(u, w, th, du, dw, dth, prm):
    """ρA (δu, δw)·E(u, w) = ρA (δw u − δu w): the skew coupling H = ∫ρA SᵀE S (parameter ``rhoA``)."""
    return prm.rhoA * (dw * u - du * w)


@LinearForm
def axis_moments(du, dw, dth, prm):
    """∫ (a_u δu + a_w δw + a_θ δθ) with a_k = α_k + β_k x (parameters ``au, bu, aw, bw, at``).

    Gives ∫ρA N (β = 0), ∫ρA x N (α = 0) and ∫ρI N_φ."""
    x = prm.x[0]
    return (prm.au + prm.bu * x) * du + (prm.aw + prm.bw * x) * dw + prm.at * dth


def _restrict(mat, free):
    return sps.csr_matrix(mat)[free][:, free].tocsr()


class FloatingBeam(FloatingFrame):
    """A Timoshenko beam in the floating frame of reference.

    Coordinates q = (R_x, R_y, θ, q_f), named ``"Rx", "Ry", "theta"`` and then
    ``"u1", "w1", "th1", ...`` (field and node number, nodes counted from the
    root along the beam) for the elastic DOFs left after the reference condition.

    Parameters
    ----------
    beam : TimoshenkoBeam
        Straight beam along the body x axis (its mesh coordinates are x).
    reference : {"clamped", "pinned"} or sequence of (x, field)
        Elastic DOFs eliminated to remove the rigid-body modes. ``"clamped"``:
        u, w, φ at the root (the node of smallest x); ``"pinned"``: u, w at the
        root and w at the tip. A sequence of (x, field) pairs, field in
        {"u", "w", "theta"}, gives them explicitly; it must remove exactly the
        three rigid modes.
    strain : {"green-lagrange", "linear"}
        Axial strain measure (see module docstring).
    position : array_like (2,)
        Initial R, m.
    angle : float
        Initial θ, rad.
    velocity : array_like (2,)
        Initial Ṙ, m/s.
    angular_velocity : float
        Initial θ̇, rad/s.
    elastic, elastic_velocity : array_like, optional
        Initial q_f and q̇_f (length ``n_elastic``; see :meth:`elastic_vector`).
    name : str
    sparse : bool, optional
        Matrix format; default: sparse when the body has more than
        :data:`~skfem_flex.bodies.base.DENSE_LIMIT` coordinates.

    Raises
    ------
    ValueError
        On a reference condition that leaves rigid modes (singular elastic
        stiffness) or over-constrains the beam, an unknown strain measure, or
        non-finite / wrongly sized initial data.
    """

    constant_mass = False
    has_potential = True

    def __init__(self, beam, reference="clamped", strain="green-lagrange", position=(0.0, 0.0), angle=0.0,
                 velocity=(0.0, 0.0), angular_velocity=0.0, elastic=None, elastic_velocity=None, name="beam",
                 sparse=None):
        if not isinstance(beam, TimoshenkoBeam):
            raise ValueError(f"FloatingBeam needs a TimoshenkoBeam, got {beam!r}")
        if strain not in ("green-lagrange", "linear"):
            raise ValueError(f"strain must be 'green-lagrange' or 'linear', got {strain!r}")
        self.beam, self.strain, self.name = beam, strain, name
        self.section = sec = beam.section
        self.reference = reference
        self.x_min, self.x_max = float(beam.x_nodes[0]), float(beam.x_nodes[-1])

        # ------------------------------------------------ reference condition -> free elastic DOFs
        fixed = self._reference_dofs(reference)
        n_full = beam.n_dofs
        node_major = beam.node_dofs.ravel()              # (u, w, θ) per node, nodes along x
        fixed_set = set(fixed.tolist())
        self.free_dofs = np.array([d for d in node_major if d not in fixed_set], dtype=int)
        self.fixed_dofs = fixed
        self.n_elastic = nf = self.free_dofs.size
        self.n_dofs = n = 3 + nf
        self.sparse = (n > DENSE_LIMIT) if sparse is None else bool(sparse)
        red = -np.ones(n_full, dtype=int)
        red[self.free_dofs] = np.arange(nf)
        self._red = red
        names = []
        node_of = {}
        for i, dofs in enumerate(beam.node_dofs):
            for k, d in enumerate(dofs):
                node_of[int(d)] = (i, k)
        for d in self.free_dofs:
            i, k = node_of[int(d)]
            names.append(f"{_FIELD_NAMES[k]}{i}")
        self._names = ("Rx", "Ry", "theta") + tuple(names)

        # ------------------------------------------------ inertia shape integrals (scikit-fem, once)
        b = beam.basis
        free = self.free_dofs
        MA = _restrict(asm(translational_mass, b, rhoA=sec.rhoA), free)
        MI = _restrict(asm(rotary_mass, b, rhoI=sec.rhoI), free)
        H = _restrict(asm(skew_inertia, b, rhoA=sec.rhoA), free)
        zero = dict(au=0.0, bu=0.0, aw=0.0, bw=0.0, at=0.0)
        lin = lambda **kw: asm(axis_moments, b, **{**zero, **kw})[free]   # noqa: E731
        Nu, Nw = lin(au=sec.rhoA), lin(aw=sec.rhoA)
        k0 = lin(bw=sec.rhoA)                             # ∫ρA Sᵀ E x0 = ∫ρA x N_w
        nphi = lin(at=sec.rhoI)                           # ∫ρI N_φ
        qd = beam.quadrature
        self._I00 = float(np.sum(sec.rhoA * qd.x ** 2 * qd.dx))
        self._Jr = float(np.sum(sec.rhoI * qd.dx))
        dense = (lambda m: m) if self.sparse else (lambda m: m.toarray())   # noqa: E731
        mass, s0x, c = float(np.sum(sec.rhoA * qd.dx)), float(np.sum(sec.rhoA * qd.x * qd.dx)), lin(bu=sec.rhoA)
        if not all(np.isfinite([mass, s0x, self._I00 + self._Jr])) or not np.all(np.isfinite(c)):
            raise ValueError(f"the beam's mass and inertia overflow double precision (length {beam.length:g} m, "
                             f"rhoA = {sec.rhoA:g} kg/m, rhoI = {sec.rhoI:g} kg m): give SI values of a physical size")
        self._set_invariants(mass=mass, S0=np.array([s0x, 0.0]), I0=self._I00 + self._Jr, Sbar=np.vstack([Nu, Nw]),
                             c=c, k0n=k0 + nphi, MA=dense(MA), H=dense(H), Mff=dense((MA + MI).tocsr()))
        self._pcache = (None, None)                       # ((q, v) bytes, M(q) v) of the last momentum

        # ------------------------------------------------ stiffness
        if strain == "linear":
            K = _restrict(beam.stiffness(), free)
        else:
            K = _restrict(asm(bending, b, EI=sec.EI) + asm(shear, beam.shear_basis, kGA=sec.kGA), free)
        self._K = K if self.sparse else K.toarray()
        self._check_stiffness(_restrict(beam.stiffness(), free))
        # quadrature arrays of the axial kernel and of the output strains
        ed = beam.element_dofs
        self._eu, self._ew, self._eth = ed[:, 0::3], ed[:, 1::3], ed[:, 2::3]
        self._dN, self._dx = qd.dNdx, qd.dx
        if np.allclose(qd.dNdx, qd.dNdx[:, :, :1]):     # P1: u', w' constant per element, one point is exact
            self._dN, self._dx = qd.dNdx[:, :, :1].copy(), qd.dx.sum(axis=1, keepdims=True)
        self._gl_cache = {}
        self._N = qd.N
        self._sq = beam.shear_quadrature
        self._EA = sec.EA
        # D = [D_u; D_w] maps q_f to (u', w') at the quadrature points, so that the axial kernel is a
        # few matrix products: dε = diag(1 + u') D_u + diag(w') D_w, ∇V_ax = dεᵀ (EA ε dx), ...
        nel, nqp = self._dx.shape
        nq = nel * nqp
        self._nq = nq
        blocks = []
        for e_dofs in (self._eu, self._ew):
            loc = red[e_dofs]                                            # (nel, nl)
            rows = np.broadcast_to((np.arange(nel)[:, None] * nqp + np.arange(nqp)[None, :])[:, :, None],
                                   (nel, nqp, loc.shape[1]))
            cols = np.broadcast_to(loc[:, None, :], rows.shape)
            vals = self._dN.transpose(1, 2, 0)
            keep = cols >= 0
            blocks.append(sps.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(nq, nf)))
        D = sps.vstack(blocks).tocsr()
        self._D = D if self.sparse else D.toarray()
        self._DT = self._D.T.tocsr() if self.sparse else np.ascontiguousarray(self._D.T)
        self._wq = (sec.EA * self._dx).ravel()                           # EA dx per point
        self._dNt = np.ascontiguousarray(self._dN.transpose(1, 2, 0))     # (nel, nqp, nl)
        self._loc = red[np.concatenate([self._eu, self._ew], axis=1)]     # (nel, 2 nl), −1 = eliminated
        if self.sparse:
            self._build_pattern()
        else:
            self._ffd = dict(MA=self._MA, H=self._H, Mff=self._Mff, K=self._K)
            # element matrices of the axial kernel -> flat (n_elastic²) positions of the elastic block
            lr = np.broadcast_to(self._loc[:, :, None], (self._loc.shape[0],) + (self._loc.shape[1],) * 2)
            lc = np.broadcast_to(self._loc[:, None, :], lr.shape)
            self._loc_mask = (lr >= 0) & (lc >= 0)
            self._loc_flat = lr[self._loc_mask] * nf + lc[self._loc_mask]
        self._kd = self._kernel_data()

        # ------------------------------------------------ initial state
        qf0 = np.zeros(nf) if elastic is None else check_finite_vector("elastic", elastic, nf)
        vf0 = np.zeros(nf) if elastic_velocity is None else check_finite_vector("elastic_velocity",
                                                                                elastic_velocity, nf)
        pos = check_finite_vector("position", position, 2)
        vel = check_finite_vector("velocity", velocity, 2)
        ang = check_finite_vector("angle", angle, 1)
        om = check_finite_vector("angular_velocity", angular_velocity, 1)
        self.q0 = np.concatenate([pos, ang, qf0])
        self.v0 = np.concatenate([vel, om, vf0])

    # ================================================================ setup helpers
    def _reference_dofs(self, reference):
        beam = self.beam
        if isinstance(reference, str):
            if reference == "clamped":
                spec = [(self.x_min, "u"), (self.x_min, "w"), (self.x_min, "theta")]
            elif reference == "pinned":
                spec = [(self.x_min, "u"), (self.x_min, "w"), (self.x_max, "w")]
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
            if f not in _FIELDS:
                raise ValueError(f"reference field must be one of 'u', 'w', 'theta', got {f!r}")
            fixed.append(int(beam.dofs_at(x)[_FIELDS[f]]))
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

    def _check_stiffness(self, K):
        """The linear elastic stiffness on q_f must be regular (no rigid modes left)."""
        if K.shape[0] <= 600:
            ev = np.linalg.eigvalsh(K.toarray())
            if not np.all(np.isfinite(ev)) or ev[0] <= 1e-13 * ev[-1]:
                # the reference condition removed the rigid modes (checked above), so a singular K
                # means stiffnesses too far apart (or zero) for double precision
                sec, h = self.beam.section, self.beam.length / max(self.beam.mesh.t.shape[1], 1)
                raise ValueError(
                    f"the elastic stiffness is singular to double precision (smallest/largest eigenvalue "
                    f"{ev[0] / ev[-1] if ev[-1] else 0.0:.2g}): the section's stiffnesses per element, "
                    f"EA/h = {sec.EA / h:.3g} N/m, kGA/h = {sec.kGA / h:.3g} N/m and EI/h³ = {sec.EI / h ** 3:.3g} N/m "
                    f"(h = {h:.3g} m), must lie within about 10¹³ of each other and be positive; "
                    f"change EA, kGA, EI or the number of elements")

    @property
    def coordinate_names(self):
        return self._names

    def elastic_vector(self, u=None, w=None, theta=None):
        """q_f from nodal fields: callables of x (m) or arrays over ``beam.x_nodes``.

        Raises ``ValueError`` if a value at an eliminated DOF is not zero.
        """
        full = np.zeros(self.beam.n_dofs)
        x = self.beam.x_nodes
        for k, fld in enumerate((u, w, theta)):
            if fld is None:
                continue
            vals = np.asarray(fld(x) if callable(fld) else fld, dtype=float)
            vals = np.broadcast_to(vals, x.shape)
            if not np.all(np.isfinite(vals)):
                raise ValueError(f"elastic field {_FIELD_NAMES[k]} is not finite")
            full[self.beam.node_dofs[:, k]] = vals
        bad = np.abs(full[self.fixed_dofs])
        if bad.size and bad.max() > 1e-12 * max(1.0, np.abs(full).max()):
            raise ValueError(f"elastic fields are not zero at the DOFs the reference condition "
                             f"{self.reference!r} eliminates: {full[self.fixed_dofs]}")
        return full[self.free_dofs].copy()

    def full_elastic(self, q):
        """Beam DOF vector (u, w, φ per node, scikit-fem numbering) of the body coordinates q."""
        d = np.zeros(self.beam.n_dofs)
        d[self.free_dofs] = q[3:]
        return d

    def nodal_fields(self, q):
        """(x, u, w, φ) at the nodes along the beam, in the body frame (m, m, m, rad)."""
        d = self.full_elastic(q)
        nd = self.beam.node_dofs
        return self.beam.x_nodes.copy(), d[nd[:, 0]], d[nd[:, 1]], d[nd[:, 2]]

    # ================================================================ matrix composition
    def _compose(self, top, left, terms=(), extra=None, loc=None):
        """n × n matrix from its reference rows ``top`` (3, n), the block ``left`` (nf, 3) below
        them and an elastic block Σ coef · X[key] for ``terms`` = [(coef, key)], key in
        {"MA", "H", "Mff", "K"}, plus ``extra`` (dense (nf, nf), dense bodies) or ``loc``
        (element matrices of the axial kernel, sparse bodies). ``top``/``left`` None mean zero.

        Sparse bodies fill one fixed CSR pattern through precomputed index maps (no sorting or
        COO conversion per call)."""
        n = self.n_dofs
        if not self.sparse:
            return super()._compose(top, left, terms, extra)
        data = np.zeros(self._pat_nnz)
        if top is not None:
            data[self._map_top] = top.ravel()
        if left is not None:
            data[self._map_left] = left.ravel()
        for coef, key in terms:
            data[self._map_ff[key]] += coef * self._ffs_data[key]
        if loc is not None:
            data += np.bincount(self._map_loc, weights=loc[self._loc_mask], minlength=self._pat_nnz)
        return sps.csr_matrix((data, self._pat_indices, self._pat_indptr), shape=(n, n))

    def _build_pattern(self):
        """The CSR pattern of every sparse body matrix and the maps into it."""
        n, nf = self.n_dofs, self.n_elastic
        rows, cols = [], []
        r, c = np.divmod(np.arange(3 * n), n)
        rows.append(r), cols.append(c)
        r, c = np.divmod(np.arange(nf * 3), 3)
        rows.append(r + 3), cols.append(c)
        self._ffs_data = {}
        ff_keys = {}
        for key in ("MA", "H", "Mff", "K"):
            X = sps.csr_matrix(getattr(self, "_" + key), copy=True)
            X.sum_duplicates()
            X.sort_indices()
            xc = X.tocoo()
            self._ffs_data[key] = X.data.copy()
            # flat keys row·n + col exceed int32 (scipy's index type) beyond 46 340 coordinates
            xr, xcol = xc.row.astype(np.int64), xc.col.astype(np.int64)
            ff_keys[key] = (xr + 3) * n + xcol + 3
            rows.append(xr + 3), cols.append(xcol + 3)
        lr = np.broadcast_to(self._loc[:, :, None], (self._loc.shape[0],) + (self._loc.shape[1],) * 2)
        lc = np.broadcast_to(self._loc[:, None, :], lr.shape)
        self._loc_mask = (lr >= 0) & (lc >= 0)
        loc_keys = (lr[self._loc_mask].astype(np.int64) + 3) * n + lc[self._loc_mask] + 3
        keys = np.unique(np.concatenate([np.asarray(r) * n + np.asarray(c) for r, c in zip(rows, cols)]
                                        + [loc_keys]))
        prow, pcol = np.divmod(keys, n)
        self._pat_nnz = keys.size
        self._pat_indices = pcol.astype(np.int32)
        self._pat_indptr = np.searchsorted(prow, np.arange(n + 1)).astype(np.int32)
        self._map_top = np.searchsorted(keys, np.arange(3 * n))
        r, c = np.divmod(np.arange(nf * 3), 3)
        self._map_left = np.searchsorted(keys, (r + 3) * n + c)
        self._map_ff = {k: np.searchsorted(keys, v) for k, v in ff_keys.items()}
        self._map_loc = np.searchsorted(keys, loc_keys)

    def _kernel_data(self):
        """The plain arrays the compiled kernels (:mod:`.floating_kernel`) work on, built once.

        The tangent is written into the data array of one CSR pattern: the body's fixed sparse
        pattern, or for dense bodies the full n × n pattern (so that the data reshapes to the
        dense matrix). Every term gets its positions in that pattern here."""
        n, nf = self.n_dofs, self.n_elastic
        if self.sparse:
            ptr, idx = self._pat_indptr, self._pat_indices
        else:
            ptr, idx = np.arange(0, n * n + 1, n), np.tile(np.arange(n), n)
        keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(ptr)) * n + idx   # row-major keys of the pattern

        def at(flat):
            pos = np.searchsorted(keys, flat)
            if flat.size and not np.array_equal(keys[np.minimum(pos, keys.size - 1)], flat):
                raise RuntimeError("FloatingBeam: a kernel term lies outside the matrix pattern")
            return pos
        blocks = dict(MA=self._MA, H=self._H, Mff=self._Mff, K=self._K)
        maps = {"top": at(np.arange(3 * n))}
        r, c = np.divmod(np.arange(nf * 3), 3)
        maps["left"] = at((r + 3) * n + c)
        for key, mat in blocks.items():
            ptr_b, idx_b, _ = _kernel._csr_parts(mat)
            rows_b = np.repeat(np.arange(nf, dtype=np.int64), np.diff(ptr_b))
            maps[key] = at((rows_b + 3) * n + idx_b + 3)
        loc = self._loc
        lr = np.broadcast_to(loc[:, :, None], (loc.shape[0],) + (loc.shape[1],) * 2)
        lc = np.broadcast_to(loc[:, None, :], lr.shape)
        keep = (lr >= 0) & (lc >= 0)
        map_loc = -np.ones(lr.shape, dtype=np.int64)
        map_loc[keep] = at((lr[keep].astype(np.int64) + 3) * n + lc[keep] + 3)
        return _kernel.pack(n, nf, self.strain == "green-lagrange", self.mass_total, self._S0, self._I0,
                            self._Sbar, self._c, self._k0n, blocks, (ptr, idx), maps, self._dNt, loc,
                            self._wq, map_loc)

    def compiled_kernel_data(self):
        """The packed arrays of the compiled kernels (:mod:`.floating_kernel`), built once at construction."""
        return self._kd

    # ================================================================ kinetic
    def momentum(self, q, v):
        """p = M(q) v (compiled kernel :func:`.floating_kernel.momentum`; cached for the last (q, v))."""
        q, v = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float)
        key = (q.tobytes(), v.tobytes())
        if self._pcache[0] != key:
            self._pcache = (key, _kernel.momentum(self._kd, q, v))
        return self._pcache[1].copy()

    def kinetic_energy(self, q, v):
        return 0.5 * float(v @ self.momentum(q, v))

    def _axial(self, qf):
        """u', w' at the quadrature points (flattened, length n_q) of the elastic vector qf."""
        y = self._D @ qf
        return y[:self._nq], y[self._nq:]

    def _axial_tangent(self, w, a, b, weps):
        """Σ_k w_k dε_k(a)ᵀ dε_k(b) + Σ_k weps_k d²ε_k, d²ε = D_uᵀD_u + D_wᵀD_w, for the strain states
        a = (u', w') and b: ``dict(extra=...)`` (dense) or ``dict(loc=...)`` (element matrices, sparse)."""
        out = self._axial_loc(w, a, b, weps)
        if not self.sparse:
            # element matrices scattered into the elastic block: O(n) work, not the O(n³) of dense dεᵀ dε
            nf = self.n_elastic
            return dict(extra=np.bincount(self._loc_flat, weights=out[self._loc_mask],
                                          minlength=nf * nf).reshape(nf, nf))
        return dict(loc=out)

    def _axial_loc(self, w, a, b, weps):
        """Element matrices (n_el, 2 n_l, 2 n_l) of :meth:`_axial_tangent` on the local (u, w) DOFs."""
        nel, nqp = self._dx.shape
        sh = (nel, nqp, 1)
        dn = self._dNt                                                   # (nel, nqp, nl)
        de_a = np.concatenate([(1.0 + a[0]).reshape(sh) * dn, a[1].reshape(sh) * dn], axis=2)
        de_b = np.concatenate([(1.0 + b[0]).reshape(sh) * dn, b[1].reshape(sh) * dn], axis=2)
        out = np.matmul((de_a * w.reshape(sh)).transpose(0, 2, 1), de_b)
        blk = np.matmul((dn * weps.reshape(sh)).transpose(0, 2, 1), dn)
        nl = dn.shape[2]
        out[:, :nl, :nl] += blk
        out[:, nl:, nl:] += blk
        return out

    def _gl(self, qf):
        """(u', w', ε) at the quadrature points; two-entry cache (q0 is reused through a step)."""
        key = qf.tobytes()
        hit = self._gl_cache.get(key)
        if hit is not None:
            return hit
        up, wp = self._axial(qf)
        val = (up, wp, up + 0.5 * (up * up + wp * wp))
        if len(self._gl_cache) >= 2:
            self._gl_cache.pop(next(iter(self._gl_cache)))
        self._gl_cache[key] = val
        return val

    def potential_energy(self, q):
        """Strain energy V(q_f) = ½ q_fᵀ K q_f + ½ Σ EA dx ε², J (compiled kernel)."""
        return float(_kernel.potential_energy(self._kd, np.ascontiguousarray(q, dtype=float)))

    def potential_gradient(self, q):
        qf = q[3:]
        g = np.zeros(self.n_dofs)
        g[3:] = self._K @ qf
        if self.strain == "green-lagrange":
            up, wp, eps = self._gl(qf)
            t = self._wq * eps
            g[3:] += self._DT @ np.concatenate([t * (1.0 + up), t * wp])
        return g

    def potential_hessian(self, q):
        qf = q[3:]
        if self.strain == "linear":
            return self._compose(None, None, [(1.0, "K")])
        up, wp, eps = self._gl(qf)
        return self._compose(None, None, [(1.0, "K")], **self._axial_tangent(self._wq, (up, wp), (up, wp),
                                                                             self._wq * eps))

    def potential_discrete_gradient(self, q0, q1):
        """Stress at the mean strain: g · (q1 − q0) = V(q1) − V(q0) exactly; with ∂g/∂q1.

        Axial part (ε quadratic in q_f, so ε(q1) − ε(q0) = dε(q_m)·Δq exactly)::

            g = Σ_k EA dx ½(ε_k(q0) + ε_k(q1)) dε_k(q_m)
            ∂g/∂q1 = ½ Σ_k EA dx [dε_k(q_m)ᵀ dε_k(q1) + ½(ε_k(q0) + ε_k(q1)) d²ε_k]
        """
        qm = 0.5 * (q0[3:] + q1[3:])
        g = np.zeros(self.n_dofs)
        g[3:] = self._K @ qm
        if self.strain == "linear":
            return g, self._compose(None, None, [(0.5, "K")])
        up0, wp0, e0 = self._gl(q0[3:])
        up1, wp1, e1 = self._gl(q1[3:])
        upm, wpm = 0.5 * (up0 + up1), 0.5 * (wp0 + wp1)
        t = self._wq * (0.5 * (e0 + e1))
        g[3:] += self._DT @ np.concatenate([t * (1.0 + upm), t * wpm])
        return g, self._compose(None, None, [(0.5, "K")], **self._axial_tangent(0.5 * self._wq, (upm, wpm),
                                                                                (up1, wp1), 0.5 * t))

    def energy_momentum_terms(self, q0, q1, v0, v1, dt):
        """Everything one Newton evaluation of the energy-momentum scheme needs, in one call.

        Optional fused form of the body contract (the scene uses it when present): the same
        numbers as :meth:`momentum`, :meth:`mass_matrix`, :meth:`momentum_jacobian`,
        :meth:`kinetic_discrete_gradient` and :meth:`potential_discrete_gradient` (to round-off).
        Computed by the compiled kernel :func:`.floating_kernel.energy_momentum_terms`; the
        contract methods, in numpy, are its reference (tests/test_floating_kernel.py).

        Returns
        -------
        p1 : ndarray (n,)
            M(q1) v1.
        g_kin, g_pot : ndarray (n,)
            Discrete gradients of G(q) = ½ v0ᵀ M(q) v1 and of the strain energy V.
        jac : ndarray or csr_matrix (n, n)
            (2/Δt) M(q1) + B(q1, v1) − Δt ∂g_kin/∂q1 − 2 ∂g_kin/∂v1 + Δt ∂g_pot/∂q1
            (dense for dense bodies, CSR in the body's fixed pattern for sparse ones).
        floor : ndarray (n,)
            Δt |∂g_pot/∂q1| (|q0| + |q1|): round-off floor of the internal forces.
        """
        n = self.n_dofs
        q0, q1, v0, v1 = (np.ascontiguousarray(x, dtype=float) for x in (q0, q1, v0, v1))
        p, gk, gp, data, floor = _kernel.energy_momentum_terms(self._kd, q0, q1, v0, v1, float(dt))
        self._pcache = ((q1.tobytes(), v1.tobytes()), p.copy())
        if self.sparse:
            jac = sps.csr_matrix((data, self._pat_indices, self._pat_indptr), shape=(n, n))
        else:
            jac = data.reshape(n, n)
        return p, gk, gp, jac, floor

    def strains(self, q):
        """Axial strain ε and force N (exact rule), curvature κ and moment M (exact rule), shear strain
        γ and force (shear rule), each of shape (n_elements, n_points)."""
        d = self.full_elastic(q)
        up = np.einsum("el,lek->ek", d[self._eu], self._dN)
        wp = np.einsum("el,lek->ek", d[self._ew], self._dN)
        eps = up + 0.5 * (up * up + wp * wp) if self.strain == "green-lagrange" else up
        kap = np.einsum("el,lek->ek", d[self._eth], self._dN)
        sq = self._sq
        gam = (np.einsum("el,lek->ek", d[self._ew], sq.dNdx) - np.einsum("el,lek->ek", d[self._eth], sq.N))
        s = self.section
        return dict(axial_strain=eps, axial_force=s.EA * eps, curvature=kap, bending_moment=s.EI * kap,
                    shear_strain=gam, shear_force=s.kGA * gam)

    def element_strain_energy(self, q):
        """Strain energy of each element, J (sums to :meth:`potential_energy`)."""
        st = self.strains(q)
        s = self.section
        return (0.5 * np.sum((s.EA * st["axial_strain"] ** 2 + s.EI * st["curvature"] ** 2) * self._dx, axis=1)
                + 0.5 * s.kGA * np.sum(st["shear_strain"] ** 2 * self._sq.dx, axis=1))

    # ================================================================ points, probes, output
    def _check_x(self, x, what="point"):
        if isinstance(x, bool) or not np.isscalar(x) or not np.isfinite(x):
            raise ValueError(f"{what}: axial coordinate x must be a finite number, got {x!r}")
        tol = 1e-9 * self.beam.length
        if not self.x_min - tol <= x <= self.x_max + tol:
            raise ValueError(f"{what}: x = {x!r} lies outside beam {self.name!r} [{self.x_min}, {self.x_max}]")
        return float(np.clip(x, self.x_min, self.x_max))

    def _full_shape_at(self, x):
        """(u, w, φ) at axial coordinate x per beam DOF, (3, beam.n_dofs)."""
        x = self._check_x(x)
        beam = self.beam
        pr = beam.field_basis.probes(np.array([[x]])).tocsr()
        S = np.zeros((3, beam.n_dofs))
        for k in range(3):
            S[k, beam.field_dofs[k][pr.indices]] = pr.data
        return S

    def shape_at(self, x):
        """(S(x) (2, n_elastic), N_φ(x) (n_elastic,)) at axial coordinate x (m)."""
        S = self._full_shape_at(x)[:, self.free_dofs]
        return S[:2].copy(), S[2].copy()

    # ================================================================ reduction
    def elastic_model(self):
        """The beam as an :class:`~skfem_flex.bodies.modal.ElasticModel` on all its DOFs (u, w, φ per node).

        Interfaces ``"root"`` and ``"tip"`` (u, w, φ of the end nodes); Green–Lagrange data: the axial
        strain ε = u' + ½(u'² + w'²) with EA on the exact rule (its linear part is the axial part of
        the beam stiffness). Built once per body."""
        if getattr(self, "_model", None) is not None:
            return self._model
        from .modal import ElasticModel, Interface
        from .stiffening import GreenLagrange
        beam, sec = self.beam, self.section
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
            self.beam.element_dofs[:, k::3].T[:, :, None], (nl, nel, nqp)).ravel())), shape=(nel * nqp, n))
            for k in (0, 1)]
        strain = GreenLagrange(grads, np.array([[1.0, 0.0]]), np.eye(2)[None], np.array([[sec.EA]]), qd.dx.ravel())
        itf = {}
        for label, x in (("root", self.x_min), ("tip", self.x_max)):
            itf[label] = Interface(label, np.array([x, 0.0]), sps.csr_matrix(self._full_shape_at(x)))
        order = np.argsort(beam.x_nodes)
        conn = np.stack([order[:-1], order[1:]], axis=1)

        def locate(X):
            if abs(X[1]) > 1e-9 * beam.length:
                raise ValueError(f"point {tuple(X)} is off the axis of beam {self.name!r} (y must be 0)")
            S = self._full_shape_at(X[0])
            return S[:2], S[2]

        def output(d):
            pts = np.stack([beam.x_nodes, np.zeros_like(beam.x_nodes)], axis=1)
            return pts, np.stack([d[nd[:, 0]], d[nd[:, 1]]], axis=1), [("line", conn)], {}

        self._model = ElasticModel(mass=asm(translational_mass, beam.basis, rhoA=sec.rhoA).tocsr(),
                                   stiffness=beam.stiffness(), translation=trans, position=pos, turn=turn,
                                   interfaces=itf, rotary_mass=asm(rotary_mass, beam.basis, rhoI=sec.rhoI).tocsr(),
                                   rotary_unit=unit, strain=strain, name=self.name, locate=locate, output=output)
        return self._model

    def reduced(self, n_modes, interfaces=("root", "tip"), **kwargs):
        """This beam reduced to a :class:`~skfem_flex.bodies.modal.ModalBody` (same initial frame state).

        ``n_modes`` fixed-interface (Craig–Bampton) or free-interface modes; interfaces ``"root"``,
        ``"tip"``; further keywords go to :func:`~skfem_flex.bodies.reduction.reduce` (``method``,
        ``reference``, ``strain`` (default: this beam's), ``n_derivatives``, ``interface_derivatives``,
        ``centrifugal``, ``name``).
        The beam's elastic initial state is not carried over (η starts at 0)."""
        from .reduction import reduce
        state = dict(position=self.q0[:2], angle=self.q0[2], velocity=self.v0[:2], angular_velocity=self.v0[2],
                     strain=self.strain, name=self.name)
        state.update(kwargs)
        return reduce(self.elastic_model(), n_modes, interfaces=list(interfaces), **state)

    def point(self, locator=None):
        """The material point of the axis at x = ``locator`` (m; default the tip)."""
        x = self.x_max if locator is None else locator
        x = self._check_x(x)
        S, Nphi = self.shape_at(x)
        return FramePoint(self, (x, 0.0), S, Nphi)

    def displacement(self, q, x=None):
        """Elastic displacement (u, w) of the axis at x in the body frame, m (default: tip)."""
        S, _ = self.shape_at(self.x_max if x is None else x)
        return S @ q[3:]

    def displacement_probe(self, x=None):
        """Probe ``(scene, t, q, v) -> (u, w)`` of the body-frame displacement at x (default: tip).

        Raises ``ValueError`` if x lies outside the beam."""
        S, _ = self.shape_at(self.x_max if x is None else x)
        body = self

        def probe(scene, t, q, v):
            return S @ scene.coordinates(body, q)[3:]
        return probe

    def geometry(self, q, v):
        """Nodes in the global frame as line cells, with displacement, velocity, angle and section forces."""
        x, u, w, ph = self.nodal_fields(q)
        dv = self.full_elastic(v)
        nd = self.beam.node_dofs
        du, dw = dv[nd[:, 0]], dv[nd[:, 1]]
        A = _rot(q[2])
        s = np.stack([x + u, w], axis=1)
        pts = q[:2] + s @ A.T
        ref = self.q0[:2] + np.stack([x, np.zeros_like(x)], axis=1) @ _rot(self.q0[2]).T
        om = v[2]
        vel = v[:2] + (om * (s @ E2.T) + np.stack([du, dw], axis=1)) @ A.T
        node_of_u = np.empty(self.beam.n_dofs, dtype=int)
        node_of_u[nd[:, 0]] = np.arange(nd.shape[0])
        conn = node_of_u[self._eu]
        cell = "line" if conn.shape[1] == 2 else "line3"
        st = self.strains(q)
        h = self.beam.element_lengths
        cd = {"axial_force": [st["axial_force"].mean(axis=1)],
              "shear_force": [st["shear_force"].mean(axis=1)],
              "bending_moment": [st["bending_moment"].mean(axis=1)],
              "strain_energy_density": [self.element_strain_energy(q) / h]}
        pd = {"displacement": pts - ref, "velocity": vel, "angle": q[2] + ph}
        return BodyGeometry(pts, [(cell, conn)], pd, cd)

    # ================================================================ steady rotation
    def centrifugal_equilibrium(self, omega, tol=1e-12, max_iterations=50):
        """Static elastic state q_f of the beam turning at constant ω (rad/s) with R fixed.

        Solves ∇V(q_f) = ω² (c + M_A q_f) (centrifugal load, eq. 26) by Newton with the
        tangent K_T(q_f) − ω² M_A.

        Raises
        ------
        ValueError
            If ω is not finite or Newton does not converge (e.g. beyond a divergence speed).
        """
        om = float(omega)
        if not np.isfinite(om):
            raise ValueError(f"omega must be finite, got {omega!r}")
        q = self.q0.copy()
        q[3:] = 0.0
        MA = self._MA
        for _ in range(max_iterations):
            r = self.potential_gradient(q)[3:] - om * om * (self._c + MA @ q[3:])
            K = self.potential_hessian(q)[3:, 3:] - om * om * MA
            scale = max(np.abs(om * om * self._c).max(), 1e-300)
            if np.abs(r).max() <= tol * scale:
                return q[3:].copy()
            dq = spla.spsolve(sps.csc_matrix(K), r) if sps.issparse(K) else np.linalg.solve(K, r)
            q[3:] -= dq
        raise ValueError(f"centrifugal equilibrium at omega = {om} did not converge")

    def rotating_modes(self, omega, n_modes=3, bending_only=True):
        """Natural frequencies (rad/s) in the frame turning at constant ω, about the stretched state.

        Linearisation of the elastic equations (R fixed, θ̇ = ω)::

            M_ff δq̈ + 2ω H δq̇ + (K_T(q_f*) − ω² M_A) δq = 0

        with K_T the tangent stiffness at the centrifugal equilibrium q_f* (for the
        Green–Lagrange strain it holds the geometric stiffness N δw'² — the centrifugal
        stiffening), −ω² M_A the centrifugal softening (its transverse part is the "−1" of
        in-plane bending) and 2ωH the Coriolis (gyroscopic) coupling of axial and transverse
        motion. Solved as a first-order eigenproblem; frequencies are the positive imaginary
        parts. With ``bending_only`` modes whose kinetic energy is mostly axial are skipped.

        Returns
        -------
        omega_n : ndarray (n_modes,)
            Frequencies in rad/s, ascending.
        shapes : ndarray (n_elastic, n_modes)
            Real parts of the displacement eigenvectors (normalised to unit max).
        """
        om = float(omega)
        qf = self.centrifugal_equilibrium(om)
        q = self.q0.copy()
        q[3:] = qf
        K = self.potential_hessian(q)[3:, 3:]
        K = (K.toarray() if sps.issparse(K) else K) - om * om * to_dense(self._MA)
        M = to_dense(self._Mff)
        G = 2.0 * om * to_dense(self._H)
        nf = self.n_elastic
        I = np.eye(nf)
        Z = np.zeros((nf, nf))
        a = np.block([[Z, I], [-K, -G]])
        bm = np.block([[I, Z], [Z, M]])
        lam, vec = sla.eig(a, bm)
        finite = np.isfinite(lam)                   # ρI = 0 leaves infinite eigenvalues
        lam, vec = lam[finite], vec[:, finite]
        keep = lam.imag > 1e-9 * max(1.0, np.abs(lam).max())
        lam, vec = lam[keep], vec[:nf, keep]
        order = np.argsort(lam.imag)
        lam, vec = lam[order], vec[:, order]
        if bending_only:
            d = np.zeros((self.beam.n_dofs, vec.shape[1]), dtype=complex)
            d[self.free_dofs] = vec
            ax = np.sum(np.abs(d[self.beam.node_dofs[:, 0]]) ** 2, axis=0)
            tr = np.sum(np.abs(d[self.beam.node_dofs[:, 1]]) ** 2, axis=0)
            sel = tr > ax
            lam, vec = lam[sel], vec[:, sel]
        if lam.size < n_modes:
            raise ValueError(f"only {lam.size} modes available, asked for {n_modes}")
        shapes = np.real(vec[:, :n_modes] * np.exp(-1j * np.angle(vec[np.argmax(np.abs(vec[:, :n_modes]), axis=0),
                                                                        np.arange(n_modes)])))
        shapes /= np.abs(shapes).max(axis=0)
        return lam.imag[:n_modes].copy(), shapes


class DistributedLoad(ForceElement):
    """Loads of eq. (43) on a :class:`FloatingBeam`, in the body frame or in the global frame.

    Generalized force Q = ∫ (∂r/∂q)ᵀ F dx (+ point terms), i.e. Q_R = ∫F, Q_θ = moment about the
    frame origin, Q_f = ∫Sᵀ F_body (eq. 43); eq. (44) rotates global loads into the body frame.
    All integrals are assembled once with ``TimoshenkoBeam.load``.

    Parameters
    ----------
    body : FloatingBeam
    f, p : float or callable of x, optional
        Distributed load, N/m. ``frame="body"``: axial f and transverse p along the body-frame
        axes (they turn with the frame). ``frame="global"``: f along global x, p along global y.
    h, Q : (x, value) or sequence of (x, value), optional
        Point forces, N, in the same components as (f, p).
    M : (x, value) or sequence of (x, value), optional
        Point moments, N m (frame-independent in the plane).
    frame : {"body", "global"}
    time_function : callable t -> float, optional
        Scales the load in time (default 1).
    name : str

    Notes
    -----
    Body frame: Q_R = A F̄, Q_θ = m_0 + g_θᵀ q_f, Q_f = L. Global frame, (c, s) = (cos θ, sin θ):
    Q_R = F̄, Q_f = L_M + c L_1 + s L_2, Q_θ = ΣM + c (m_y + L_2·q_f) − s (m_x + L_1·q_f).
    The element is non-conservative; its work enters ``Result.external_work``.
    """

    conservative = False

    def __init__(self, body, f=None, p=None, h=None, Q=None, M=None, frame="body", time_function=None,
                 name="distributed load"):
        if not isinstance(body, FloatingBeam):
            raise ValueError(f"DistributedLoad needs a FloatingBeam, got {body!r}")
        if frame not in ("body", "global"):
            raise ValueError(f"frame must be 'body' or 'global', got {frame!r}")
        if time_function is not None and not callable(time_function):
            raise ValueError(f"time_function must be callable, got {time_function!r}")
        self.body, self.bodies, self.frame, self.name = body, (body,), frame, name
        self.time_function = time_function
        beam, free = body.beam, body.free_dofs
        qd = beam.quadrature
        pairs = {k: beam._pairs(k, v) for k, v in (("h", h), ("Q", Q), ("M", M))}
        for k, arr in pairs.items():
            for x, _ in arr:
                body._check_x(x, f"point load {k}")

        def field(load):
            if load is None:
                return np.zeros_like(qd.x)
            val = load(qd.x) if callable(load) else load
            val = np.broadcast_to(np.asarray(val, dtype=float), qd.x.shape)
            if not np.all(np.isfinite(val)):
                raise ValueError(f"distributed load must be finite, got {load!r}")
            return val

        fx, px = field(f), field(p)
        hh, QQ, MM = pairs["h"], pairs["Q"], pairs["M"]
        self._Fbar = np.array([np.sum(fx * qd.dx) + hh[:, 1].sum(), np.sum(px * qd.dx) + QQ[:, 1].sum()])
        self._mx = float(np.sum(qd.x * fx * qd.dx) + np.sum(hh[:, 0] * hh[:, 1]))
        self._my = float(np.sum(qd.x * px * qd.dx) + np.sum(QQ[:, 0] * QQ[:, 1]))
        self._M = float(MM[:, 1].sum())

        def neg(load):
            if load is None:
                return None
            return (lambda x: -np.asarray(load(x), dtype=float)) if callable(load) else -float(load)

        swap = lambda arr: None if arr.size == 0 else [(x, -v) for x, v in arr]  # noqa: E731
        self._L1 = beam.load(f=f, p=p, h=hh if hh.size else None, Q=QQ if QQ.size else None)[free]
        self._L2 = beam.load(f=p, p=neg(f), h=QQ if QQ.size else None, Q=swap(hh))[free]
        self._LM = beam.load(M=MM if MM.size else None)[free]

    def _scale(self, t):
        if self.time_function is None:
            return 1.0
        s = float(self.time_function(t))
        if not np.isfinite(s):
            raise ValueError(f"time_function({t}) is not finite: {s!r}")
        return s

    def generalized_force(self, q, v, t):
        body = self.body
        k = self._scale(t)
        n = body.n_dofs
        qf = q[3:]
        c, s = math.cos(q[2]), math.sin(q[2])
        out = np.empty(n)
        top = np.zeros((3, n))
        left = np.zeros((body.n_elastic, 3))
        if self.frame == "body":
            A = _rot(q[2])
            out[:2] = A @ self._Fbar
            out[2] = self._my + self._M + float(self._L2 @ qf)
            out[3:] = self._LM + self._L1
            top[:2, 2] = A @ (E2 @ self._Fbar)
            top[2, 3:] = self._L2
        else:
            a2, a1 = self._my + float(self._L2 @ qf), self._mx + float(self._L1 @ qf)
            out[:2] = self._Fbar
            out[2] = self._M + c * a2 - s * a1
            out[3:] = self._LM + c * self._L1 + s * self._L2
            top[2, 2] = -s * a2 - c * a1
            top[2, 3:] = c * self._L2 - s * self._L1
            left[:, 2] = -s * self._L1 + c * self._L2
        return k * out, k * body._compose(top, left), None
