r"""Floating-frame bodies with a linear elastic field u = Φ η over any finite-element model.

An :class:`ElasticModel` is what a reduction needs to know about a linear elastic body in its
undeformed state: mass and stiffness on its nodal vector d (assembled once with scikit-fem),
the nodal vectors of rigid motions, interface points where joints attach, and, optionally,
the Green–Lagrange strain at its quadrature points. :class:`~skfem_flex.bodies.PlaneStress`
and :meth:`FloatingBeam.elastic_model <skfem_flex.bodies.FloatingBeam.elastic_model>` make them.

A :class:`ModalBody` puts such a model in a floating frame with d = Φ η: coordinates
(R_x, R_y, θ, η). Its inertia invariants (:mod:`.ffr`) are products of Φ with the model's mass
matrices, exact because the element interpolates the rigid fields (X, EX) exactly:

    m = t_xᵀ M t_x,  S_0 = T ᵀ M x,  I_0 = xᵀ M x + J_r,  S̄ = Tᵀ M Φ,  c = Φᵀ M x,
    k_0n = Φᵀ M Ê x + Φᵀ M_r 1_φ,  M_A = Φᵀ M Φ,  H = Φᵀ M Ê Φ,  M_ff = M_A + Φᵀ M_r Φ

(M the translational mass, M_r the rotary mass of beams, T = [t_x t_y] the unit translations,
x the position field, Ê the nodal 90° turn). Strain energy: ½ ηᵀ ΦᵀKΦ η (``strain="linear"``)
or the quartic Green–Lagrange energy of :mod:`.stiffening`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps

from ..base import COMPILED_SIZE_LIMIT, BodyGeometry, check_finite_vector
from ..floating import kernel as fk
from ..ffr import FloatingFrame, FramePoint
from .kernel import pack_quartic
from ..rigid import E_MATRIX as E2, rotation as _rot
from .stiffening import QUARTIC_LIMIT, QuarticEnergy

__all__ = ["ElasticModel", "Interface", "ModalBody"]


@dataclass
class Interface:
    """A point of a body where joints and loads attach.

    Its displacement is u_I = P[:2] d and, when P has three rows, its rotation φ_I = P[2] d:
    for a node, P picks the node's DOFs; for a node set around a hole, P is the averaging
    coupling (mean displacement, least-squares rotation of the set about its centre). A rigid
    coupling also ties the set to that motion: d[rigid_dofs] = rigid_map (u_I, φ_I).

    Attributes
    ----------
    name : str
    position : ndarray (2,)
        Undeformed position in the body frame, m (the centre of a node set).
    P : scipy.sparse matrix (2 or 3, n_dofs)
    rigid_dofs : ndarray of int, optional
        DOFs slaved rigidly to the interface (None: averaging coupling, the set deforms freely).
    rigid_map : ndarray (len(rigid_dofs), 3), optional
        Their values per unit (u_x, u_y, φ) of the interface.
    """

    name: str
    position: np.ndarray
    P: object
    rigid_dofs: np.ndarray = None
    rigid_map: np.ndarray = None

    @property
    def has_rotation(self):
        return self.P.shape[0] == 3


@dataclass
class ElasticModel:
    """A linear elastic body, undeformed, on its nodal vector d (length ``n_dofs``).

    Attributes
    ----------
    mass : sparse (n, n)
        Translational mass ∫ρ Nᵀ N, kg.
    stiffness : sparse (n, n)
        Linear stiffness, N/m.
    translation : ndarray (n, 2)
        Nodal vectors of unit translations along x and y.
    position : ndarray (n,)
        Nodal vector of the displacement field u = X (the undeformed positions).
    turn : sparse (n, n)
        Ê with (Ê d) the nodal vector of the field E u (90° turn of every displacement).
    interfaces : dict of str to Interface
    rotary_mass : sparse (n, n), optional
        Rotary inertia ∫ρI N_φᵀN_φ of a beam's cross-sections, kg m².
    rotary_unit : ndarray (n,), optional
        Nodal vector of the unit cross-section rotation.
    strain : GreenLagrange, optional
    name : str
    locate : callable X -> (S (2, n), N_φ (n,) or None), optional
        Displacement (and rotation) of the material point X per nodal DOF; ``ValueError`` outside.
    output : callable d -> (points (n_p, 2), displacement (n_p, 2), cells, cell_data), optional
        Undeformed output points, their displacement, meshio cells and cell data.
    stress_operators : list of sparse (n_cells, n), optional
        Cell-mean displacement gradients (u_x,X, u_x,Y, u_y,X, u_y,Y) per DOF, for stress output.
    stresses : callable g (n_cells, 4) -> dict of str to (n_cells,) arrays, optional
        Stress components (Pa) from those gradients.
    """

    mass: object
    stiffness: object
    translation: np.ndarray
    position: np.ndarray
    turn: object
    interfaces: dict = field(default_factory=dict)
    rotary_mass: object = None
    rotary_unit: np.ndarray = None
    strain: object = None
    name: str = "body"
    locate: object = None
    output: object = None
    stress_operators: list = None
    stresses: object = None

    @property
    def n_dofs(self):
        return self.mass.shape[0]

    def total_mass(self):
        """M + M_r (kg, kg m²): the mass of the eigenproblems."""
        return self.mass if self.rotary_mass is None else (self.mass + self.rotary_mass).tocsr()

    def rigid_modes(self):
        """(n, 3): unit translations x, y and the unit infinitesimal rotation about the origin."""
        rot = self.turn @ self.position
        if self.rotary_unit is not None:
            rot = rot + self.rotary_unit
        return np.column_stack([self.translation, rot])

    def interface(self, name):
        """The :class:`Interface` called ``name``; ``ValueError`` naming the known ones otherwise."""
        if not isinstance(name, str) or name not in self.interfaces:
            raise ValueError(f"body {self.name!r} has no interface {name!r}; it has {sorted(self.interfaces)}")
        return self.interfaces[name]


class ModalBody(FloatingFrame):
    """A floating-frame body whose elastic displacement is d = Φ η on an :class:`ElasticModel`.

    Coordinates q = (R_x, R_y, θ, η_1 … η_m), named ``"Rx", "Ry", "theta", "eta1", …``.
    Usually made by :func:`~skfem_flex.bodies.modal.reduction.reduce` (``body.reduced(...)``).

    Parameters
    ----------
    model : ElasticModel
    basis : ndarray or sparse (n_dofs, m)
        Φ; its columns must be free of rigid motion (a reference condition).
    strain : {"green-lagrange", "linear"}
        Strain measure; Green–Lagrange needs ``model.strain`` and m ≤ 60.
    reference : str
        Name of the reference condition (for messages and output).
    position, angle, velocity, angular_velocity : initial frame state (m, rad, m/s, rad/s)
    elastic, elastic_velocity : array_like (m,), optional
        Initial η and η̇.
    frequencies : ndarray, optional
        Natural frequencies of the basis (rad/s), for information.
    name : str

    Raises
    ------
    ValueError
        Unknown strain measure, Green–Lagrange without strain data or with too many coordinates,
        a basis of the wrong shape or with rigid-body content (singular ΦᵀKΦ), bad initial data.
    """

    has_potential = True

    def __init__(self, model, basis, strain="green-lagrange", reference="interface", position=(0.0, 0.0), angle=0.0,
                 velocity=(0.0, 0.0), angular_velocity=0.0, elastic=None, elastic_velocity=None, frequencies=None,
                 name=None):
        if not isinstance(model, ElasticModel):
            raise ValueError(f"ModalBody needs an ElasticModel, got {model!r}")
        if strain not in ("green-lagrange", "linear"):
            raise ValueError(f"strain must be 'green-lagrange' or 'linear', got {strain!r}")
        Phi = basis.toarray() if sps.issparse(basis) else np.asarray(basis, dtype=float)
        if Phi.ndim != 2 or Phi.shape[0] != model.n_dofs or Phi.shape[1] < 1:
            raise ValueError(f"basis must have shape ({model.n_dofs}, m ≥ 1), got {Phi.shape}")
        if strain == "green-lagrange":
            if model.strain is None:
                raise ValueError(f"model {model.name!r} has no Green–Lagrange strain data; use strain='linear'")
            if Phi.shape[1] > QUARTIC_LIMIT:
                raise ValueError(f"strain='green-lagrange' needs a reduced basis (at most {QUARTIC_LIMIT} "
                                 f"coordinates, got {Phi.shape[1]}: its quartic energy has m⁴ terms); reduce the "
                                 f"body or use strain='linear'")
        self.model, self.Phi, self.strain, self.reference = model, Phi, strain, reference
        self.name = model.name if name is None else name
        self.n_elastic = nf = Phi.shape[1]
        self.n_dofs = 3 + nf
        self.frequencies = None if frequencies is None else np.asarray(frequencies, dtype=float)
        self._names = ("Rx", "Ry", "theta") + tuple(f"eta{i + 1}" for i in range(nf))

        M, x, T = model.mass, model.position, model.translation
        MPhi = M @ Phi
        Mx = M @ x
        MA = Phi.T @ MPhi
        Mff = MA.copy()
        I0 = float(x @ Mx)
        k0n = Phi.T @ (M @ (model.turn @ x))
        if model.rotary_mass is not None:
            Mff += Phi.T @ (model.rotary_mass @ Phi)
            ru = model.rotary_unit
            I0 += float(ru @ (model.rotary_mass @ ru))
            k0n += Phi.T @ (model.rotary_mass @ ru)
        self.set_invariants(mass=float(T[:, 0] @ (M @ T[:, 0])), S0=T.T @ Mx, I0=I0, Sbar=T.T @ MPhi,
                             c=Phi.T @ Mx, k0n=k0n, MA=MA, H=Phi.T @ (M @ (model.turn @ Phi)), Mff=Mff)
        K = Phi.T @ (model.stiffness @ Phi)
        K = 0.5 * (K + K.T)
        ev = np.linalg.eigvalsh(K)
        if ev[0] <= 1e-10 * max(ev[-1], 1e-300):
            raise ValueError(f"basis of body {self.name!r} carries rigid-body motion (ΦᵀKΦ is singular, smallest "
                             f"eigenvalue {ev[0]:.3g} of {ev[-1]:.3g}); apply a reference condition")
        self.energy = model.strain.reduced(Phi, K) if strain == "green-lagrange" else QuarticEnergy(K)
        inv = self.invariants
        self.elastic_blocks = dict(MA=inv.MA, H=inv.H, Mff=inv.Mff, K=K)
        self._kd = None                                  # packed on first request (compiled_kernel_data)
        # modal stress fields: cell-mean displacement gradients of every basis vector, (n_cells, 4, m)
        self._modal_gradients = (None if model.stress_operators is None
                                 else np.stack([G @ Phi for G in model.stress_operators], axis=1))

        qf0 = np.zeros(nf) if elastic is None else check_finite_vector("elastic", elastic, nf)
        vf0 = np.zeros(nf) if elastic_velocity is None else check_finite_vector("elastic_velocity",
                                                                                elastic_velocity, nf)
        self.q0 = np.concatenate([check_finite_vector("position", position, 2), check_finite_vector("angle", angle, 1),
                                  qf0])
        self.v0 = np.concatenate([check_finite_vector("velocity", velocity, 2),
                                  check_finite_vector("angular_velocity", angular_velocity, 1), vf0])

    @property
    def coordinate_names(self):
        return self._names

    def displacement_field(self, q):
        """Nodal displacement vector d = Φ η of the model (body frame), m."""
        return self.Phi @ np.asarray(q)[3:]

    def elastic_vector(self, d):
        """η whose Φ η is closest to the nodal vector d in the mass norm (for initial states)."""
        d = check_finite_vector("d", d, self.model.n_dofs)
        M = self.model.total_mass()
        return np.linalg.solve(self.Phi.T @ (M @ self.Phi), self.Phi.T @ (M @ d))

    # ================================================================ strain energy
    def potential_energy(self, q):
        """V(η) (J): quadratic, or the quartic Green–Lagrange energy."""
        return self.energy.energy(np.asarray(q)[3:])

    def potential_gradient(self, q):
        g = np.zeros(self.n_dofs)
        g[3:] = self.energy.gradient(np.asarray(q)[3:])
        return g

    def potential_hessian(self, q):
        return self.compose_matrix(None, None, extra=self.energy.hessian(np.asarray(q)[3:]))

    def potential_discrete_gradient(self, q0, q1):
        """Exact discrete gradient of V (stress at the mean strain) with ∂/∂q1."""
        g = np.zeros(self.n_dofs)
        ge, dge = self.energy.discrete_gradient(np.asarray(q0)[3:], np.asarray(q1)[3:])
        g[3:] = ge
        return g, self.compose_matrix(None, None, extra=dge)

    # ================================================================ compiled kernels
    def compiled_kernel_data(self):
        """The packed arrays on which the compiled floating-frame kernels (:mod:`.floating_kernel`, with the
        quartic energy of :mod:`.modal_kernel`) evaluate this body; built on the first call. None above
        ``COMPILED_SIZE_LIMIT`` coordinates (an unreduced body: its dense n × n tangent is no band).

        The tangent goes into the full n × n pattern (the data reshapes to the dense matrix). This
        body's own methods stay in numpy: they are the kernels' reference (tests/test_modal_kernel.py),
        and the floating-frame family (:mod:`skfem_flex.compiled.families.floating_frame`) runs the kernels."""
        if self.n_dofs > COMPILED_SIZE_LIMIT:
            return None
        if self._kd is None:
            n, nf = self.n_dofs, self.n_elastic
            ptr, idx = np.arange(0, n * n + 1, n), np.tile(np.arange(n), n)
            r, c = np.divmod(np.arange(nf * 3), 3)
            maps = {"top": np.arange(3 * n), "left": (r + 3) * n + c}
            for key, mat in self.elastic_blocks.items():           # MA, H, Mff, K: their canonical CSR entries
                ptr_b, idx_b, _ = fk.csr_parts(mat)
                maps[key] = (np.repeat(np.arange(nf), np.diff(ptr_b)) + 3) * n + idx_b + 3
            r, c = np.divmod(np.arange(nf * nf), nf)
            maps["ee"] = (r + 3) * n + c + 3
            quartic = None if self.energy.linear else pack_quartic(self.energy.K3, self.energy.K4)
            inv = self.invariants
            self._kd = fk.pack(n, nf, False, inv.mass, inv.S0, inv.I0, inv.Sbar, inv.c, inv.k0n,
                               self.elastic_blocks, (ptr, idx), maps, quartic=quartic)
        return self._kd

    # ================================================================ points and output
    def point(self, locator=None):
        """A material point: an interface name (default: the first interface) or body-frame (X, Y) in m.

        An interface point with a rotation DOF also has an angle (for welds and moments).

        Raises
        ------
        ValueError
            Unknown interface name, or a point (X, Y) outside the body.
        """
        model = self.model
        if locator is None:
            if not model.interfaces:
                raise ValueError(f"body {self.name!r} has no interfaces; give a point (X, Y)")
            locator = next(iter(model.interfaces))
        if isinstance(locator, str):
            itf = model.interface(locator)
            P = itf.P
            S = np.asarray(P[:2] @ self.Phi)
            Nphi = np.asarray(P[2] @ self.Phi).ravel() if itf.has_rotation else None
            return FramePoint(self, itf.position, S, Nphi)
        X = check_finite_vector("point", locator, 2)
        if model.locate is None:
            raise ValueError(f"body {self.name!r} can only give interface points {sorted(model.interfaces)}")
        S, Nphi = model.locate(X)
        return FramePoint(self, X, np.asarray(S @ self.Phi), None if Nphi is None else np.asarray(Nphi @ self.Phi))

    def displacement_probe(self, locator=None):
        """Probe ``(scene, t, q, v) -> u`` of the elastic displacement (body frame, m) at a point."""
        S = self.point(locator).S
        body = self

        def probe(scene, t, q, v):
            return S @ scene.coordinates(body, q)[3:]
        return probe

    def stresses(self, q):
        """Cell stresses (Pa) from the modal gradient fields: {} if the model has no stress recovery.

        g = Σ_i η_i ḡ_i (cell-mean displacement gradients of the basis, precomputed), then the
        model's stress law (plane stress: S = C E(g), σxx, σyy, σxy, von Mises)."""
        if self._modal_gradients is None:
            return {}
        return self.model.stresses(self._modal_gradients @ np.asarray(q, dtype=float)[3:])

    def geometry(self, q, v):
        """The model's output mesh deformed and placed in the global frame, with its cell data.

        Point data: ``displacement`` (from the initial placement) and ``velocity``; cell data from
        the model (for plane-stress bodies the stresses σxx, σyy, σxy and von Mises, Pa)."""
        if self.model.output is None:
            raise ValueError(f"model {self.model.name!r} has no output mesh")
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        X, u, cells, cell_data = self.model.output(self.Phi @ q[3:])
        _, du, _, _ = self.model.output(self.Phi @ v[3:])
        cell_data = dict(cell_data)
        for key, val in self.stresses(q).items():
            cell_data[key] = [val]
        A = _rot(q[2])
        s = X + u
        pts = q[:2] + s @ A.T
        ref = self.q0[:2] + X @ _rot(self.q0[2]).T
        vel = v[:2] + (v[2] * (s @ E2.T) + du) @ A.T
        return BodyGeometry(pts, cells, {"displacement": pts - ref, "velocity": vel}, cell_data)

