"""Rotating floating-frame beams: the spin-up manoeuvre and the steadily rotating cantilever.

``spin_up_beam``
    Simo & Vu-Quoc (1986): a beam clamped to a hub whose angle follows
    :func:`~skfem_flex.elements.motion.spin_up_law` (docs/scenes.md). The hub frame is the body
    frame (clamped reference condition), R is held at the origin by constant laws.
``rotating_beam``
    A cantilever turning at constant ω, started in its stretched steady state.
``rotating_beam_frequencies``
    In-plane bending frequencies in the rotating frame, linearised about that state.
"""
from __future__ import annotations

import numpy as np

from ..fem.beam import TimoshenkoBeam, line_mesh
from ..bodies.floating.body import FloatingBeam
from ..elements.motion import MotionLaw, Prescribed, spin_up_law
from ..scene import Scene
from ..fem.section import Section
from ._registry import register

__all__ = ["spin_up_beam", "rotating_beam", "rotating_beam_frequencies", "hub_beam"]

_UNITS = dict(length="m", EA="N", EI="N m^2", kGA="N", rhoA="kg/m", rhoI="kg m", n_elements="-", order="-",
              strain="-")


def _constant(value):
    value = float(value)
    return MotionLaw(lambda t: value, lambda t: 0.0, lambda t: 0.0)


def hub_beam(length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4, n_elements=8, order=1,
             strain="green-lagrange", name="beam"):
    """A :class:`FloatingBeam` along [0, length] clamped to its body frame (the hub frame).

    Raises ``ValueError`` for a non-positive length or element count, or bad section values.
    """
    length = float(length)
    if not np.isfinite(length) or length <= 0:
        raise ValueError(f"length must be finite and positive, got {length!r}")
    if isinstance(n_elements, bool) or int(n_elements) != n_elements or n_elements < 1:
        raise ValueError(f"n_elements must be a positive integer, got {n_elements!r}")
    sec = Section(EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI)
    beam = TimoshenkoBeam(line_mesh(length, n_elements, order), sec, order=order)
    return FloatingBeam(beam, reference="clamped", strain=strain, name=name)


@register(t_end=30.0, dt=0.02, omega="rad/s", T="s", body="floating | exact | beam-modal", n_modes="-", **_UNITS)
def spin_up_beam(omega=4.0, T=15.0, length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
                 n_elements=8, order=1, strain="green-lagrange", body="floating", n_modes=3):
    """Spin-up of a flexible beam clamped to a hub (Simo & Vu-Quoc 1986).

    Hub angle θ(t) = (ω_s/T)(t²/2 + (T/2π)²(cos(2πt/T) − 1)) for t < T, ω_s(t − T/2) after;
    the hub centre R is held at the origin. The first bending frequency of the cantilever is
    3.516 √(EI/(ρA L⁴)) ≈ 3.80 rad/s for the default section, so ω_s = 4 and 10 rad/s spin
    faster than it: the linear axial strain (``strain="linear"``), which has no centrifugal
    stiffening, then diverges, while the Green–Lagrange strain stays bounded.

    ``body="exact"`` builds the same manoeuvre with a geometrically exact beam
    (:func:`~skfem_flex.scenes.exact_beams.exact_spin_up_beam`; ``strain`` does not apply).

    ``body="beam-modal"`` reduces the floating beam by Craig–Bampton with the root as interface
    (the hub frame is attached to it): ``n_modes`` fixed-interface modes and, for the
    Green–Lagrange strain, their static modal derivatives and the static response to the
    centrifugal load (3 + 6 + 1 = 10 coordinates for n_modes = 3), which carry the axial
    stretching and chord shortening that the stiffening needs.

    Probes: ``"tip"`` = tip displacement in the hub frame (axial, transverse), m.
    Reference (docs/energy_scheme.md): minimum transverse tip displacement ≈ −0.40 m near t = 6.95 s
    for ω_s = 4 rad/s.
    """
    if body == "exact":
        from .exact_beams import exact_spin_up_beam
        if strain != "green-lagrange":
            raise ValueError(f"strain={strain!r} applies to the floating-frame beam only; the exact beam's "
                             f"strains are always geometrically exact")
        return exact_spin_up_beam(omega, T, length, EA, EI, kGA, rhoA, rhoI, n_elements, order)
    if body not in ("floating", "beam-modal"):
        raise ValueError(f"body must be 'floating', 'exact' or 'beam-modal', got {body!r}")
    kind = body
    body = hub_beam(length, EA, EI, kGA, rhoA, rhoI, n_elements, order, strain)
    tip = body.displacement_probe()
    if kind == "beam-modal":
        if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
            raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
        body = body.reduced(int(n_modes), interfaces=("root",), centrifugal=strain == "green-lagrange")
        tip = body.displacement_probe("tip")
    pres = [Prescribed(body, "Rx", _constant(0.0)), Prescribed(body, "Ry", _constant(0.0)),
            Prescribed(body, "theta", spin_up_law(omega, T))]
    return Scene([body], prescribed=pres, name="spin_up_beam", probes={"tip": tip},
                 parameters=dict(omega=omega, T=T, length=length, EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, order=order, strain=strain, body=kind, n_modes=n_modes))


@register(t_end=10.0, dt=0.01, omega="rad/s", perturbation="m", **_UNITS)
def rotating_beam(omega=4.0, length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4, n_elements=8,
                  order=1, strain="green-lagrange", perturbation=0.01):
    """Cantilever turning at constant ω about its clamped root (θ = ω t, R fixed).

    Starts in the stretched steady state (:meth:`FloatingBeam.centrifugal_equilibrium`) plus
    a transverse perturbation: the shape of the lowest in-plane bending mode, scaled to a tip
    deflection of ``perturbation`` m, so that the beam vibrates at the frequency
    :func:`rotating_beam_frequencies` predicts.

    Probes: ``"tip"`` = tip displacement in the rotating frame (axial, transverse), m.
    """
    for name, value in (("omega", omega), ("perturbation", perturbation)):
        if not np.isfinite(float(value)):
            raise ValueError(f"{name} must be finite, got {value!r}")
    body = hub_beam(length, EA, EI, kGA, rhoA, rhoI, n_elements, order, strain)
    om = float(omega)
    qf = body.centrifugal_equilibrium(om)
    if perturbation:
        _, shapes = body.rotating_modes(om, 1)
        S, _ = body.shape_at(body.x_max)
        mode = shapes[:, 0] / float(S[1] @ shapes[:, 0])
        qf = qf + float(perturbation) * mode
    body.q0[3:] = qf
    body.v0[2] = om
    pres = [Prescribed(body, "Rx", _constant(0.0)), Prescribed(body, "Ry", _constant(0.0)),
            Prescribed(body, "theta", MotionLaw.constant_rate(om))]
    return Scene([body], prescribed=pres, name="rotating_beam", probes={"tip": body.displacement_probe()},
                 parameters=dict(omega=omega, length=length, EA=EA, EI=EI, kGA=kGA, rhoA=rhoA, rhoI=rhoI,
                                 n_elements=n_elements, order=order, strain=strain, perturbation=perturbation))


def rotating_beam_frequencies(omega, length=10.0, EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4,
                              n_elements=8, order=1, strain="green-lagrange", n_modes=3):
    """First in-plane bending frequencies (rad/s) of the cantilever turning at ω, in the rotating frame.

    Linearised about the stretched steady state: solves the nonlinear static centrifugal
    equilibrium ∇V(q_f) = ω²(c + M_A q_f), then M_ff δq̈ + 2ωH δq̇ + (K_T − ω² M_A) δq = 0, which
    includes the tangent stiffness with its geometric (centrifugal-stiffening) part, the
    centrifugal softening −ω² M_A (the "−1" of in-plane bending) and the Coriolis coupling 2ωH
    between axial and transverse motion (see :meth:`FloatingBeam.rotating_modes`).

    For a slender uniform cantilever without hub radius ω₁² ≈ ω₁,₀² + (S − 1) ω², S ≈ 1.193 at
    small ω (Southwell); with ``strain="linear"`` the stiffening is missing and ω₁ falls with ω.
    """
    body = hub_beam(length, EA, EI, kGA, rhoA, rhoI, n_elements, order, strain)
    return body.rotating_modes(omega, n_modes)[0]
