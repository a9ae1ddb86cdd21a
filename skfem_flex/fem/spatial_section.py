r"""Cross-section data of a spatial beam.

A :class:`SpatialSection` holds the resultant properties of a section whose principal axes are the
directors d₁, d₂ and whose normal is d₃ (SI units throughout). With the strains of the section
(shear Γ₁, Γ₂ and stretch Γ₃; bending curvatures K₁, K₂ about d₁, d₂ and twist K₃) the energies per
unit length are

.. math::

    W = ½ (kGA₁ Γ₁² + kGA₂ Γ₂² + EA Γ₃² + EI₁ K₁² + EI₂ K₂² + GJ K₃²),

    T = ½ (ρA ‖\dot φ‖² + ρI₂ ‖\dot d₁‖² + ρI₁ ‖\dot d₂‖²),

where ρI₁ = ∫ρ ξ₂² dA and ρI₂ = ∫ρ ξ₁² dA are the section's mass moments of inertia about d₁ and d₂
(ξ₁, ξ₂ the section coordinates along d₁, d₂): a material point ξ₁ d₁ + ξ₂ d₂ of the section moves with
ξ₁ ḋ₁ + ξ₂ ḋ₂, so the polar inertia about d₃ is ρI₁ + ρI₂.
"""
from __future__ import annotations

from dataclasses import dataclass

from .section import non_negative_number, positive_number

__all__ = ["SpatialSection"]


@dataclass(frozen=True)
class SpatialSection:
    """Resultant stiffness and inertia of a spatial beam's cross-section (module docstring).

    Parameters
    ----------
    EA : float
        Axial stiffness, N.
    GA1, GA2 : float
        Shear stiffnesses k G A along d₁ and d₂ (shear correction included), N.
    GJ : float
        Torsional stiffness, N m².
    EI1, EI2 : float
        Bending stiffnesses about d₁ and d₂, N m².
    rhoA : float
        Mass per length, kg/m (≥ 0; zero only for statics).
    rhoI1, rhoI2 : float
        Mass moments of inertia per length about d₁ and d₂, kg m (≥ 0; the polar one is their sum).

    Raises
    ------
    ValueError
        For a stiffness that is not finite and positive, or a mass property that is negative or not finite.

    Examples
    --------
    >>> sec = SpatialSection.rectangle(E=1e7, G=5e6, width=1.0, height=1.0, rho=1.0)
    >>> round(sec.EI1, 1), round(sec.GJ, 1)
    (833333.3, 704166.7)
    """

    EA: float
    GA1: float
    GA2: float
    GJ: float
    EI1: float
    EI2: float
    rhoA: float = 0.0
    rhoI1: float = 0.0
    rhoI2: float = 0.0

    def __post_init__(self):
        for name in ("EA", "GA1", "GA2", "GJ", "EI1", "EI2"):
            object.__setattr__(self, name, positive_number(name, getattr(self, name)))
        for name in ("rhoA", "rhoI1", "rhoI2"):
            object.__setattr__(self, name, non_negative_number(name, getattr(self, name)))

    @property
    def stiffness(self):
        """The diagonal (kGA₁, kGA₂, EA, EI₁, EI₂, GJ) of the section's elasticity, strains in the order
        (Γ₁, Γ₂, Γ₃, K₁, K₂, K₃)."""
        return (self.GA1, self.GA2, self.EA, self.EI1, self.EI2, self.GJ)

    @classmethod
    def rectangle(cls, E, G, width, height, rho=0.0, shear_factor=5.0 / 6.0):
        """A solid rectangle, ``width`` along d₁ and ``height`` along d₂ (m), of Young's modulus E and
        shear modulus G (Pa) and density ρ (kg/m³).

        I₁ = w h³/12 about d₁, I₂ = h w³/12 about d₂; the torsion constant of the rectangle
        J = a b³ (1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴))) (a ≥ b the sides; Roark's approximation,
        within 0.5 % for every aspect ratio).
        """
        E, G = positive_number("E", E), positive_number("G", G)
        w, h = positive_number("width", width), positive_number("height", height)
        rho = non_negative_number("rho", rho)
        k = positive_number("shear_factor", shear_factor)
        area = w * h
        i1, i2 = w * h ** 3 / 12.0, h * w ** 3 / 12.0
        a, b = max(w, h), min(w, h)
        j = a * b ** 3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b ** 4 / (12.0 * a ** 4)))
        return cls(EA=E * area, GA1=k * G * area, GA2=k * G * area, GJ=G * j, EI1=E * i1, EI2=E * i2,
                   rhoA=rho * area, rhoI1=rho * i1, rhoI2=rho * i2)
