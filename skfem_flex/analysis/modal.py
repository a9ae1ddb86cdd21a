r"""Modes of a linearized scene: :func:`modes` and its result :class:`Modes`.

The eigenvalues s of M z̈ + C ż + K z = 0 about the static equilibrium, the steady motion, the
initial state or any given state: the symmetric problem K φ = ω² M φ without velocity terms, the
quadratic one through its first-order form otherwise (docs/linearization.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from ..scene_initial import consistent_initial_state
from .balance import EquilibriumState
from .linearization import LinearSystem, linearize
from .matrix_tools import EPS, TINY, as_dense, inf_norm
from .statics import static_equilibrium

__all__ = ["Modes", "modes", "ABOUT"]

#: the states ``modes(about=...)`` accepts by name
ABOUT = ("static", "steady", "initial")


@dataclass
class Modes:
    r"""Modes of a linearized scene, lowest first.

    Each mode is one eigenvalue s of M z̈ + C ż + K z = 0 (solutions z = φ e^{st}): one of
    each complex-conjugate pair (Im s > 0), every real one (a conservative unstable pair
    ±σ gives two modes), s = 0 once per rigid-body or mechanism motion.

    Attributes
    ----------
    eigenvalues : ndarray of complex
        s, 1/s, ordered by abs(s) (of a real pair ±σ the growing one first).
    shapes : ndarray (n, n_modes)
        Shapes on all coordinates (real for undamped conservative systems, complex
        otherwise), scaled to largest entry 1 (phase of that entry 0).
    reduced_shapes : ndarray (n_z, n_modes)
        The same in the independent coordinates z.
    system : LinearSystem
        The linearized system (matrices and reference state).
    scene_name : str
    about : str
        What the reference state is ("static", "steady", "initial" or "given").
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    reduced_shapes: np.ndarray
    system: LinearSystem
    scene_name: str = "scene"
    about: str = "given"

    @property
    def omega(self):
        """Angular frequencies Im s, rad/s (0 for real eigenvalues)."""
        return np.abs(self.eigenvalues.imag)

    @property
    def frequency_hz(self):
        """Frequencies Im s / 2π, Hz."""
        return self.omega / (2.0 * np.pi)

    @property
    def natural_omega(self):
        """Undamped natural angular frequencies abs(s), rad/s."""
        return np.abs(self.eigenvalues)

    @property
    def growth_rate(self):
        """Re s, 1/s (positive: the mode grows, the state is unstable)."""
        return self.eigenvalues.real.copy()

    @property
    def damping_ratio(self):
        """ζ = −Re s / abs(s) (0 for s = 0; −1 for a real growing mode)."""
        mag = np.abs(self.eigenvalues)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(mag > 0, -self.eigenvalues.real / np.where(mag > 0, mag, 1.0), 0.0) + 0.0

    @property
    def period(self):
        """2π/ω, s (inf for ω = 0)."""
        with np.errstate(divide="ignore"):
            return np.where(self.omega > 0, 2.0 * np.pi / np.where(self.omega > 0, self.omega, 1.0), np.inf)

    @property
    def stable(self):
        """True when no mode grows (Re s ≤ 0 for all computed modes, to round-off)."""
        return bool(np.all(self.growth_rate <= 1e-9 * max(1.0, float(np.max(self.natural_omega, initial=0.0)))))

    def table(self):
        """[{mode, omega_rad_s, frequency_hz, damping_ratio, growth_rate_1_s}] one dict per mode."""
        return [dict(mode=i + 1, omega_rad_s=float(w), frequency_hz=float(f), damping_ratio=float(z),
                     growth_rate_1_s=float(g))
                for i, (w, f, z, g) in enumerate(zip(self.omega, self.frequency_hz, self.damping_ratio,
                                                      self.growth_rate))]


def _zero_tolerance(k, m):
    """|s|² below this is round-off of a zero eigenvalue: 1e3 ε ‖K‖/‖M‖."""
    nk = float(abs(k).sum(axis=1).max()) if k.shape[0] else 0.0
    nm = float(abs(m).sum(axis=1).max()) if m.shape[0] else 1.0
    return 1e3 * EPS * nk / max(nm, TINY)


def _symmetric(k, tol=1e-10):
    d = k - k.T
    big = inf_norm(k.data if sps.issparse(k) else k)
    return inf_norm(d.data if sps.issparse(d) else d) <= tol * max(big, TINY)


def _solve_symmetric(sysm, n_modes, zero_tol):
    """Eigenpairs of K φ = ω² M φ: eigenvalues s = √(−ω²) with shapes."""
    k, m = sysm.stiffness, sysm.mass
    n = sysm.n
    if sps.issparse(k) and n_modes < n - 1:
        trace = float(k.diagonal().sum()) / max(float(m.diagonal().sum()), TINY)
        shift = -max(1e-6 * abs(trace), 1e3 * zero_tol, TINY)
        lam, vec = spla.eigsh(sps.csc_matrix(k), k=min(n_modes + 2, n - 1), M=sps.csc_matrix(m), sigma=shift,
                              which="LM")
    else:
        try:
            lam, vec = sla.eigh(as_dense(k), as_dense(m), subset_by_index=[0, min(n_modes + 1, n - 1)])
        except np.linalg.LinAlgError:
            raise ValueError("the mass matrix of the independent coordinates is not positive definite: a "
                             "coordinate has no inertia (zero density or rotary inertia rhoI = 0?)") from None
    lam = np.where(np.abs(lam) <= zero_tol, 0.0, lam)
    s, shapes = [], []
    for li, phi in zip(lam, vec.T):
        if li >= 0:
            s.append(1j * math.sqrt(li))
            shapes.append(phi)
        else:                              # a conservative unstable pair ±σ, both modes of motion
            sig = math.sqrt(-li)
            s += [sig + 0j, -sig + 0j]
            shapes += [phi, phi]
    return np.array(s, dtype=complex), np.array(shapes).T


def _solve_first_order(sysm, n_modes, zero_tol):
    """Eigenpairs of the quadratic problem (s² M + s C + K) φ = 0 via the first-order form."""
    k, m, c = sysm.stiffness, sysm.mass, sysm.damping
    n = sysm.n
    if c is None:
        c = sps.csr_matrix((n, n)) if sps.issparse(k) else np.zeros((n, n))
    if sps.issparse(k) and 2 * n_modes + 4 < 2 * n - 1:
        eye = sps.identity(n, format="csr")
        a = sps.bmat([[None, eye], [-k, -c]], format="csc")
        b = sps.bmat([[eye, None], [None, m]], format="csc")
        trace = float(k.diagonal().sum()) / max(float(m.diagonal().sum()), TINY)
        shift = -math.sqrt(max(1e-6 * abs(trace), 1e3 * zero_tol, TINY))
        lam, vec = spla.eigs(a, k=min(2 * n_modes + 4, 2 * n - 2), M=b, sigma=shift, which="LM")
    else:
        kd, md, cd = as_dense(k), as_dense(m), as_dense(c)
        eye, zero = np.eye(n), np.zeros((n, n))
        lam, vec = sla.eig(np.block([[zero, eye], [-kd, -cd]]), np.block([[eye, zero], [zero, md]]))
    ok = np.isfinite(lam)
    lam, vec = lam[ok], vec[:n, ok]
    mag = np.abs(lam)
    scale = max(float(mag.max(initial=0.0)), TINY)
    lam = np.where(mag ** 2 <= zero_tol, 0.0, lam)
    real = np.abs(lam.imag) <= 1e-9 * np.maximum(np.abs(lam), 1e-12 * scale)
    lam = np.where(real, lam.real + 0j, lam)
    keep = real | (lam.imag > 0)
    zeros = np.flatnonzero(keep & (lam == 0))
    # s = 0 of a motion without stiffness is a double root of det(s²M + sC + K) with one shape:
    # the first-order form returns it twice, one mode is kept per pair
    keep[zeros[(zeros.size + 1) // 2:]] = False
    return lam[keep], vec[:, keep]


def _normalize(shapes, reduced):
    """Both scaled column by column so that the largest entry of ``shapes`` is 1 (real when they are)."""
    if shapes.size == 0:
        return shapes, reduced
    idx = np.argmax(np.abs(shapes), axis=0)
    piv = shapes[idx, np.arange(shapes.shape[1])]
    piv = np.where(np.abs(piv) > 0, piv, 1.0)
    out, red = shapes / piv, reduced / piv
    if np.iscomplexobj(out) and np.all(np.abs(out.imag) <= 1e-12 * np.maximum(np.abs(out).max(axis=0), TINY)):
        out, red = out.real, red.real
    return out, red


def _reference(scene, about, t, newton):
    if isinstance(about, EquilibriumState):
        return about.q, about.v, about.t, about.lam, about.acc, "steady" if about.steady else "static"
    if isinstance(about, str):
        if about not in ABOUT:
            raise ValueError(f"about must be one of {', '.join(ABOUT)} or a state, got {about!r}")
        if about in ("static", "steady"):
            st = static_equilibrium(scene, t, steady=(about == "steady"), newton=newton)
            return st.q, st.v, st.t, st.lam, st.acc, about
        q, v = scene.initial_state()
        q, v = consistent_initial_state(scene, q, v, 0.0)
        return q, v, 0.0, None, None, "initial"
    if isinstance(about, tuple) and len(about) == 2:
        return np.asarray(about[0], float), np.asarray(about[1], float), t, None, None, "given"
    q, v = getattr(about, "q", None), getattr(about, "v", None)
    if q is None or v is None:
        raise ValueError(f"about must be one of {', '.join(ABOUT)}, an EquilibriumState, a (q, v) pair or an "
                         f"object with q and v, got {about!r}")
    return (np.asarray(q, float), np.asarray(v, float), float(getattr(about, "t", t)), getattr(about, "lam", None),
            getattr(about, "acc", None), "given")


def modes(scene, about="static", n_modes=6, t=0.0, solver="auto", newton=None):
    r"""Lowest modes of a scene linearized about a state.

    Parameters
    ----------
    scene : Scene
    about : {"static", "steady", "initial"}, EquilibriumState, (q, v) or an object with q, v
        ``"static"``: the equilibrium at rest (:func:`~skfem_flex.analysis.statics.static_equilibrium`); ``"steady"``:
        the relative equilibrium under the scene's prescribed steady motion (e.g. a
        constant spin; frequencies are then those seen in the moving frame);
        ``"initial"``: the scene's initial state (frozen linearization of a moving state).
    n_modes : int
        How many modes (lowest abs(s) first); fewer when the system has fewer.
    t : float
        Time of the static/steady state, s.
    solver : {"auto", "symmetric", "first-order"}
        ``"auto"``: the real symmetric generalized problem K φ = ω² M φ when there are no
        velocity terms and K is symmetric, otherwise the quadratic problem through its
        first-order form. Dense LAPACK up to :data:`~skfem_flex.scene.DENSE_LIMIT` independent
        coordinates, else scipy's ARPACK in shift-invert mode near zero.
    newton : NewtonSettings, optional
        For the static/steady solve.

    Returns
    -------
    Modes
        Zero modes (a free body's rigid motions, a mechanism's free motion) come out as
        s = 0, not as an error.
    """
    if isinstance(n_modes, bool) or int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
    if solver not in ("auto", "symmetric", "first-order"):
        raise ValueError(f"solver must be 'auto', 'symmetric' or 'first-order', got {solver!r}")
    q, v, t_ref, lam, acc, label = _reference(scene, about, float(t), newton)
    sysm = linearize(scene, q, v, t_ref, lam=lam, acc=acc)
    n_modes = int(n_modes)
    if sysm.n == 0:
        empty = np.zeros(0, dtype=complex)
        return Modes(empty, np.zeros((scene.n, 0)), np.zeros((0, 0)), sysm, scene.name, label)
    zero_tol = _zero_tolerance(sysm.stiffness, sysm.mass)
    symmetric = sysm.damping is None and _symmetric(sysm.stiffness)
    if solver == "symmetric" and not symmetric:
        raise ValueError("solver='symmetric' needs a system without velocity terms and with a symmetric "
                         "stiffness matrix; use 'first-order' or 'auto'")
    if solver == "symmetric" or (solver == "auto" and symmetric):
        s, z = _solve_symmetric(sysm, n_modes, zero_tol)
    else:
        s, z = _solve_first_order(sysm, n_modes, zero_tol)
    mag = np.abs(s)
    # by |s|; of a pair ±σ (equal |s| to round-off) the growing mode first
    order = np.lexsort((-s.real, np.round(mag / max(float(mag.max(initial=0.0)), TINY), 10)))[:n_modes]
    s, z = s[order], z[:, order]
    shapes, z = _normalize(sysm.basis @ z, z)
    return Modes(s, shapes, z, sysm, scene.name, label)
