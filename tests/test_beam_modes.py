r"""Natural frequencies of a Timoshenko cantilever against the exact frequency equation.

Derivation of the frequency determinant used here (clamped at x = 0, free at
x = L; Huang 1961). With shear strain γ = w' − θ, bending moment EI θ' and
shear force kGA (w' − θ), harmonic motion at ω gives

    kGA (W'' − Θ') + ρA ω² W = 0,
    EI Θ'' + kGA (W' − Θ) + ρI ω² Θ = 0.

In ξ = x/L with b² = ρA ω² L⁴/EI, r² = I/(A L²) (= ρI/(ρA L²)) and
s² = EI/(kGA L²), W and Θ = e^{Λξ} solve Λ⁴ + b²(r² + s²)Λ² − b²(1 − b²r²s²) = 0,
so below the cut-off b²r²s² < 1 the roots are Λ = ±bβ, ±ibα with

    α, β = √((±(r² + s²) + √((r² − s²)² + 4/b²)) / 2),

    W  = C1 cosh bβξ + C2 sinh bβξ + C3 cos bαξ + C4 sin bαξ,
    LΘ = k_β (C1 sinh bβξ + C2 cosh bβξ) + k_α (−C3 sin bαξ + C4 cos bαξ),

with k_β = b(β² + s²)/β, k_α = b(α² − s²)/α from the first equation
(LΘ amplitude = (Λ + b²s²/Λ) × W amplitude). The clamp (W = Θ = 0) gives
C3 = −C1, C4 = −C2 k_β/k_α; zero moment Θ'(L) = 0 and zero shear
W'(L) − Θ(L) = 0 (divided by b s²) leave a 2×2 system whose determinant
vanishes at the natural frequencies.
"""
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import skfem

from skfem_flex.fem.beam import TimoshenkoBeam
from skfem_flex.fem.section import Section

E, NU, H, RHO, LENGTH, K_SHEAR = 210e9, 0.3, 0.1, 7850.0, 1.0, 5 / 6


def cantilever_determinant(b, r2, s2):
    """Clamped–free Timoshenko frequency determinant at frequency parameter b."""
    root = np.sqrt((r2 - s2) ** 2 + 4 / b**2)
    alpha, beta = np.sqrt((r2 + s2 + root) / 2), np.sqrt((root - r2 - s2) / 2)
    k_alpha, k_beta = b * (alpha**2 - s2) / alpha, b * (beta**2 + s2) / beta
    ba, bb = b * alpha, b * beta
    moment = [k_beta * bb * np.cosh(bb) + k_alpha * ba * np.cos(ba),
              k_beta * (bb * np.sinh(bb) + ba * np.sin(ba))]
    shear = [-np.sinh(bb) / beta + np.sin(ba) / alpha,
             -np.cosh(bb) / beta - k_beta / (k_alpha * alpha) * np.cos(ba)]
    return moment[0] * shear[1] - moment[1] * shear[0]


def shooting_determinant(b, r2, s2):
    """Same frequency condition from the transfer matrix of the ODE system.

    State (W, W', LΘ, LΘ') in ξ: W'' = LΘ' − b²s² W,
    LΘ'' = −b²r² LΘ − (W' − LΘ)/s². Independent of the closed form above.
    """
    system = np.array([[0, 1, 0, 0],
                       [-b**2 * s2, 0, 0, 1],
                       [0, 0, 0, 1],
                       [0, -1 / s2, 1 / s2 - b**2 * r2, 0]])
    transfer = scipy.linalg.expm(system)
    free_end = np.array([[0, 0, 0, 1], [0, 1, -1, 0]])  # Θ' = 0, W' − Θ = 0
    return np.linalg.det(free_end @ transfer[:, [1, 3]])  # clamp: W = Θ = 0


def frequency_roots(r2, s2, n_roots=3):
    """First roots b of the determinant, bracketed on a fine grid then brentq."""
    grid = np.linspace(0.5, 150.0, 6000)
    assert grid[-1] ** 2 * r2 * s2 < 1, "the real form holds below the cut-off frequency only"
    values = cantilever_determinant(grid, r2, s2)
    brackets = np.nonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0][:n_roots]
    return np.array([
        scipy.optimize.brentq(cantilever_determinant, grid[i], grid[i + 1], args=(r2, s2),
                              xtol=1e-13)
        for i in brackets
    ])


def section_parameters(slenderness):
    """r², s² of the square steel section at L/h = slenderness."""
    h = LENGTH / slenderness
    G = E / (2 * (1 + NU))
    A, I = h * h, h**4 / 12
    return I / (A * LENGTH**2), E * I / (K_SHEAR * G * A * LENGTH**2)


def test_frequency_equation_tends_to_euler_bernoulli():
    euler_bernoulli = np.array([1.8751040687, 4.6940911330, 7.8547574382]) ** 2
    np.testing.assert_allclose(frequency_roots(*section_parameters(1e4)), euler_bernoulli, rtol=1e-6)
    # shear and rotary inertia lower the frequencies of a stocky beam
    assert np.all(frequency_roots(*section_parameters(10)) < euler_bernoulli)


def test_frequency_equation_agrees_with_transfer_matrix():
    r2, s2 = section_parameters(10)
    closed_form = frequency_roots(r2, s2)
    # bracket each root ±1 % (expm is too slow for the fine grid scan)
    shooting = [
        scipy.optimize.brentq(shooting_determinant, 0.99 * b, 1.01 * b, args=(r2, s2), xtol=1e-13)
        for b in closed_form
    ]
    np.testing.assert_allclose(closed_form, shooting, rtol=1e-10)


def bending_frequencies(n_elements, order=1, n_bending=3):
    """Lowest FE bending frequencies (rad/s) of the L/h = 10 steel cantilever."""
    section = Section.rectangle(E=E, nu=NU, b=H, h=H, rho=RHO, k=K_SHEAR)
    assert section.rhoI == pytest.approx(RHO * H**4 / 12)  # rotary inertia included
    beam = TimoshenkoBeam(skfem.MeshLine(np.linspace(0, LENGTH, n_elements + 1)), section,
                          order=order)
    omega, shapes = beam.modes(fixed=beam.dofs_at(0.0), n_modes=6)
    # The first axial mode, ω = (π/2)√(E/ρ)/L = 8124 rad/s, lies between
    # bending modes 2 and 3 here: keep the modes whose motion is transverse.
    axial = np.abs(shapes[beam.field_dofs[0]]).max(axis=0)
    transverse = np.abs(shapes[beam.field_dofs[1]]).max(axis=0)
    return omega[transverse > axial][:n_bending]


def exact_bending_frequencies():
    b = frequency_roots(*section_parameters(LENGTH / H))
    return b * np.sqrt(E * H**4 / 12 / (RHO * H * H)) / LENGTH**2


def test_cantilever_frequencies_p1():
    """First three bending frequencies within 1e-3 with 128 P1 elements.

    With 64 P1 elements (consistent mass, one-point shear) the relative
    errors are 3.0e-5, 5.6e-4 and 1.5e-3: mode 3 needs 128 elements
    (3.7e-4) for 1e-3, and the error falls by 4 per halving of the mesh.
    """
    exact = exact_bending_frequencies()
    error_64 = bending_frequencies(64) / exact - 1
    error_128 = bending_frequencies(128) / exact - 1
    assert np.all(np.abs(error_64[:2]) < 1e-3)
    assert np.all(np.abs(error_128) < 1e-3)
    np.testing.assert_allclose(error_64 / error_128, 4.0, rtol=0.01)


def test_cantilever_frequencies_p2():
    exact = exact_bending_frequencies()
    np.testing.assert_allclose(bending_frequencies(32, order=2), exact, rtol=1e-5)


def test_modes_are_mass_normalised_and_respect_supports():
    section = Section.rectangle(E=E, nu=NU, b=H, h=H, rho=RHO)
    beam = TimoshenkoBeam(skfem.MeshLine(np.linspace(0, LENGTH, 9)), section)
    fixed = beam.dofs_at(0.0)
    omega, shapes = beam.modes(fixed=fixed, n_modes=4)
    assert np.all(np.diff(omega) > 0)
    np.testing.assert_allclose(shapes.T @ beam.mass() @ shapes, np.eye(4), atol=1e-10)
    np.testing.assert_allclose(shapes.T @ beam.stiffness() @ shapes, np.diag(omega**2),
                               rtol=1e-9, atol=1e-6 * omega[-1] ** 2)
    assert np.all(shapes[fixed] == 0.0)
    # all modes of a tiny system go through the dense solver
    omega_all, _ = beam.modes(fixed=fixed, n_modes=beam.n_dofs - 3)
    np.testing.assert_allclose(omega_all[:4], omega, rtol=1e-9)


def test_free_beam_needs_a_shift_and_then_has_three_rigid_modes():
    section = Section.rectangle(E=E, nu=NU, b=H, h=H, rho=RHO)
    beam = TimoshenkoBeam(skfem.MeshLine(np.linspace(0, LENGTH, 9)), section)
    with pytest.raises(ValueError, match="sigma"):
        beam.modes(fixed=[], n_modes=4)
    omega, _ = beam.modes(fixed=[], n_modes=4, sigma=-1.0)
    assert np.all(omega[:3] < 1e-3 * omega[3])
    with pytest.raises(ValueError, match="n_modes"):
        beam.modes(fixed=[], n_modes=0, sigma=-1.0)
