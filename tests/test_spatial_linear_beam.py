"""The linear spatial Timoshenko beam on scikit-fem: a cantilever's static tip deflections in both principal
planes, its twist, and its first bending and torsion frequencies against the closed forms (P2, 8 elements)."""
import functools

import numpy as np
import pytest
import skfem

from skfem_flex.fem.spatial_beam import TimoshenkoBeam3D
from skfem_flex.fem.spatial_section import SpatialSection
from helpers import ROTATING_TABLE

L, P = 2.0, 1.0
SECTION = SpatialSection(EA=1e4, GA1=8e3, GA2=6e3, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=2.0, rhoI1=1e-2,
                         rhoI2=2e-2)


def cantilever(section=SECTION, order=2, n=8):
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, L, n + 1)), section, order)
    return beam, beam.dofs_at(0.0), beam.dofs_at(L)


@pytest.mark.parametrize("load, field, closed_form", [
    (dict(force=(P, 0.0, 0.0)), 0, P * L ** 3 / (3 * 300.0) + P * L / 8e3),     # along d₁: EI₂, kGA₁
    (dict(force=(0.0, P, 0.0)), 1, P * L ** 3 / (3 * 500.0) + P * L / 6e3),     # along d₂: EI₁, kGA₂
    (dict(force=(0.0, 0.0, P)), 2, P * L / 1e4),                                 # stretch
    (dict(moment=(0.0, 0.0, P)), 5, P * L / 400.0),                              # twist
])
def test_cantilever_statics_against_closed_forms(load, field, closed_form):
    beam, root, tip = cantilever()
    q = beam.solve_static(beam.point_load(L, **load), fixed=root)
    assert q[tip[field]] == pytest.approx(closed_form, rel=1e-3)


def test_uniform_load_deflection():
    """q L⁴/(8 EI₂) + q L²/(2 kGA₁) under a uniform load along d₁."""
    beam, root, tip = cantilever()
    q = beam.solve_static(beam.distributed_load(force=(P, 0.0, 0.0)), fixed=root)
    assert q[tip[0]] == pytest.approx(P * L ** 4 / (8 * 300.0) + P * L ** 2 / (2 * 8e3), rel=1e-3)


def test_first_bending_and_torsion_frequencies():
    """A slender section (shear and rotary inertia negligible): the Euler–Bernoulli cantilever's
    β₁² √(EI/(ρA L⁴)), β₁ L = 1.8751, in both planes, and the shaft's (π/2L) √(GJ/ρJ), ρJ = ρI₁ + ρI₂."""
    sec = SpatialSection(EA=1e4, GA1=1e12, GA2=1e12, GJ=400.0, EI1=500.0, EI2=300.0, rhoA=2.0, rhoI1=1e-3,
                         rhoI2=2e-3)
    beam, root, _ = cantilever(sec)
    omega, shapes = beam.modes(root, n_modes=10)
    beta = 1.8751040687119611 ** 2
    expected = sorted([beta * np.sqrt(300.0 / (2.0 * L ** 4)), beta * np.sqrt(500.0 / (2.0 * L ** 4)),
                       np.pi / (2 * L) * np.sqrt(400.0 / 3e-3)])
    found = [omega[0], omega[1], min(w for w, s in zip(omega, shapes.T) if np.abs(s[beam.node_dofs[:, 5]]).max()
                                        > 0.5 * np.abs(s).max())]
    assert sorted(found) == pytest.approx(expected, rel=1e-3)


def test_bad_input():
    with pytest.raises(ValueError, match="SpatialSection"):
        TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0, 1, 3)), object())
    with pytest.raises(ValueError, match="order"):
        TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0, 1, 3)), SECTION, order=3)
    beam, _, _ = cantilever()
    with pytest.raises(ValueError, match="finite 3-vectors"):
        beam.point_load(L, force=(np.nan, 0.0, 0.0))


@functools.lru_cache(maxsize=1)
def rotating_cantilever():
    """EI = ρA = L = 1, nearly Euler–Bernoulli (kGA = 1e5 EI/L², ρI = 1e-6 ρA L²), inextensible (u₃ held)."""
    sec = SpatialSection(EA=1e4, GA1=1e5, GA2=1e5, GJ=1.0, EI1=1.0, EI2=1.0, rhoA=1.0, rhoI1=1e-6, rhoI2=1e-6)
    beam = TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, 7)), sec, order=2)
    return beam, np.concatenate([beam.dofs_at(0.0), beam.node_dofs[:, 2]])


@pytest.mark.parametrize("lam, flap, lag", ROTATING_TABLE)
def test_rotating_cantilever_frequencies_against_the_classical_table(lam, flap, lag):
    beam, fixed = rotating_cantilever()
    modes = beam.rotating_modes(fixed, lam)
    (f, gf), (g, gg) = modes.first(True), modes.first(False)
    assert f == pytest.approx(flap, rel=5e-4) and g == pytest.approx(lag, rel=5e-4)
    assert max(gf, gg) <= 1e-6 * f
    assert g ** 2 == pytest.approx(f ** 2 - lam ** 2, rel=1e-3)


def test_linear_strain_lead_lag_diverges_beyond_the_first_frequency():
    """Without the centrifugal stiffening the lead-lag frequency is √(ω̄₀² − λ²) and the mode diverges
    for λ > ω̄₀ = 3.5160 (the spin-up failure of linear floating-frame models)."""
    beam, fixed = rotating_cantilever()
    for lam in (2.0, 3.4):
        g, growth = beam.rotating_modes(fixed, lam, stiffening=False).first(False)
        assert g == pytest.approx(np.sqrt(3.51602 ** 2 - lam ** 2), rel=1e-3) and growth <= 1e-6
    g, growth = beam.rotating_modes(fixed, 3.7, stiffening=False).first(False)
    assert g == 0.0 and growth == pytest.approx(np.sqrt(3.7 ** 2 - 3.51602 ** 2), rel=1e-3)
