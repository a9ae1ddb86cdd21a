"""Straight flexible links of a chosen kind, for the scenes' ``body=`` switch.

``"beam"``
    :class:`~skfem_flex.bodies.FloatingBeam` (nodal Timoshenko beam).
``"beam-modal"``
    That beam reduced by Craig–Bampton with interfaces at both ends (frame attached to the root).
``"plane-stress"``
    A plane-stress strip (Q2 quadrilaterals) with the same EA, EI, kGA (k = 5/6), ρA and ρI,
    unreduced; its root and tip cross-sections are rigid interfaces.
``"plane-stress-modal"``
    The strip reduced like the modal beam.

Reduced Green–Lagrange links carry the tip interface's three constraint modes, n_modes
fixed-interface modes and the six static modal derivatives of those constraint modes (the frame
sits at the root; docs/flexible_bodies.md §4): 3 + n_modes + 6 coordinates, 12 for n_modes = 3
(the beam drops the vanishing derivative of its axial constraint mode with itself, and dependent
ones); linear ones 3 + n_modes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem

from ..fem.beam import TimoshenkoBeam, line_mesh
from ..bodies.floating.body import FloatingBeam
from ..bodies.modal.plane_stress import PlaneStress, load_mesh
from ..numerics.resources import BYTES_PER_ELEMENT, check_fits
from ._registry import positive_count, positive_value

__all__ = ["LINK_KINDS", "Link", "link", "strip_material"]

LINK_KINDS = ("beam", "beam-modal", "plane-stress", "plane-stress-modal")


@dataclass
class Link:
    """A link body with its root, tip and mid-span points (BodyPoint) along the axis x ∈ [0, L]."""

    body: object
    root: object
    tip: object
    mid: object


def strip_material(section, length):
    """(E, ν, ρ, h) of a unit-thickness plane-stress strip with the section's EA, EI, kGA (k = 5/6), ρA.

    h = √(12 EI/EA), E = EA/h, G = kGA/(5/6 h), ν = E/(2G) − 1, ρ = ρA/h; the strip's rotary
    inertia is then ρA h²/12.

    Raises
    ------
    ValueError
        If ν falls outside (−1, 0.5) or the section's ρI differs from ρA h²/12 by more than 1e-6.
    """
    h = float(np.sqrt(12.0 * section.EI / section.EA))
    E = section.EA / h
    nu = E / (2.0 * section.kGA / (5.0 / 6.0 * h)) - 1.0
    if not -1.0 < nu < 0.5:
        raise ValueError(f"a plane-stress strip cannot have EA = {section.EA}, EI = {section.EI}, kGA = {section.kGA}: "
                         f"they give Poisson's ratio {nu:.4g} outside (-1, 0.5)")
    if abs(section.rhoI - section.rhoA * h * h / 12.0) > 1e-6 * section.rhoA * h * h / 12.0:
        raise ValueError(f"a plane-stress strip of height {h:.6g} m has rhoI = rhoA h²/12 = "
                         f"{section.rhoA * h * h / 12.0:.6g} kg m, not {section.rhoI!r}")
    return E, nu, section.rhoA / h, h


def _strip(length, E, nu, rho, height, thickness, n_elements, n_across, name):
    # refused at once, before its mesh is allocated (a hypothesis run asked for 10⁹ elements)
    check_fits(BYTES_PER_ELEMENT * n_elements * n_across, f"a plane-stress strip of {n_elements} × {n_across} elements")
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0.0, length, n_elements + 1),
                                      np.linspace(-0.5 * height, 0.5 * height, n_across + 1))
    tol = 1e-9 * length
    return PlaneStress(mesh, E, nu, rho, thickness=thickness, name=name,
                       interfaces={"root": lambda X: np.abs(X[0]) < tol, "tip": lambda X: np.abs(X[0] - length) < tol})


def link(kind, length, section, n_elements, n_modes=3, n_across=2, reference="clamped", strain="green-lagrange",
         material=None, mesh=None, name="beam", **state):
    """A straight link of ``kind`` (module docstring) along the body x axis from 0 to ``length``.

    Parameters
    ----------
    kind : str
        One of :data:`LINK_KINDS`.
    length : float
        m.
    section : Section
    n_elements : int
        Beam elements, or strip elements along the length.
    n_modes : int
        Fixed-interface modes of the reduced kinds.
    n_across : int
        Strip elements across the height.
    reference : str
        FloatingBeam reference condition (``"beam"`` only; the others attach the frame to the root).
    strain : {"green-lagrange", "linear"}
    material : (E, ν, ρ, height, thickness), optional
        Strip material and cross-section; default from :func:`strip_material` (unit thickness).
    mesh : str or Path, optional
        Plane-stress kinds: a mesh file (gmsh ``.msh``, read by meshio) instead of the strip, with
        physical groups ``big_end`` (root, at the origin) and ``small_end`` (tip, at (length, 0))
        around the two holes; ``n_elements``, ``n_across`` and the height do not apply.
    **state
        Initial frame state (position, angle, velocity, angular_velocity).

    Raises
    ------
    ValueError
        Unknown kind, bad counts, or a section no strip can have.
    """
    if kind not in LINK_KINDS:
        raise ValueError(f"body must be one of {LINK_KINDS}, got {kind!r}")
    length = positive_value("length", length)
    n = positive_count("n_elements", n_elements)
    if kind.startswith("beam"):
        tb = TimoshenkoBeam(line_mesh(length, n), section)       # checks that it fits in memory first
        beam = FloatingBeam(tb, reference=reference if kind == "beam" else "clamped", strain=strain, name=name,
                            **state)
        if mesh is not None:
            raise ValueError(f"mesh applies to the plane-stress kinds, not to body={kind!r}")
        if kind == "beam":
            return Link(beam, beam.point(0.0), beam.point(length), beam.point(0.5 * length))
        body = beam.reduced(positive_count("n_modes", n_modes), interfaces=("root", "tip"), strain=strain)
    else:
        if material is None:
            E, nu, rho, h = strip_material(section, length)
            material = (E, nu, rho, h, 1.0)
        E, nu, rho, h, t = material
        if mesh is None:
            strip = _strip(length, E, nu, rho, h, t, n, positive_count("n_across", n_across), name)
        else:
            strip = PlaneStress(load_mesh(mesh), E, nu, rho, thickness=t, name=name,
                                interfaces={"root": "big_end", "tip": "small_end"})
            ends = np.array([strip.interfaces["root"].position, strip.interfaces["tip"].position])
            if np.abs(ends - [[0.0, 0.0], [length, 0.0]]).max() > 1e-3 * length:
                raise ValueError(f"mesh {mesh!r}: hole centres {ends.tolist()} are not at (0, 0) and ({length}, 0)")
        if kind == "plane-stress":
            body = strip.body(strain="linear", name=name, **state)
        else:
            body = strip.reduced(positive_count("n_modes", n_modes), interfaces=["root", "tip"], strain=strain,
                                 name=name, **state)
    return Link(body, body.point("root"), body.point("tip"), body.point((0.5 * length, 0.0)))
