"""Cross-section data of a planar Timoshenko beam.

A :class:`Section` holds the five resultant properties the beam energies
need (SI units throughout)::

    strain energy   V = ½ ∫ (EA u'² + EI θ'² + kGA (w' − θ)²) dx
    kinetic energy  T = ½ ∫ (ρA (u̇² + ẇ²) + ρI θ̇²) dx

It can be given directly or built from material and geometry with
:meth:`Section.rectangle` or :meth:`Section.from_material`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

__all__ = ["Section"]


def _finite_float(name, value):
    """Return ``value`` as a finite float or raise ``ValueError`` naming it."""
    # bool is an int subclass and strings convert with float(); neither is a
    # physical quantity, so reject them instead of reading True as 1.0.
    if isinstance(value, (bool, str, bytes)):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return number


def positive_number(name, value):
    number = _finite_float(name, value)
    if number <= 0.0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    return number


def non_negative_number(name, value):
    number = _finite_float(name, value)
    if number < 0.0:
        raise ValueError(f"{name} must be zero or positive, got {value!r}")
    return number


@dataclass(frozen=True)
class Section:
    """Resultant stiffness and inertia of a beam cross-section.

    Parameters
    ----------
    EA : float
        Axial stiffness E·A in N.
    EI : float
        Bending stiffness E·I in N·m².
    kGA : float
        Shear stiffness k·G·A in N (k is the shear correction factor).
    rhoA : float
        Mass per unit length ρ·A in kg/m.
    rhoI : float
        Rotary inertia per unit length ρ·I in kg·m. May be zero (no rotary
        inertia); the other four must be positive.

    Raises
    ------
    ValueError
        If a value is not a finite real number, or is not positive (rhoI:
        negative). The message names the field and the value.

    Examples
    --------
    >>> Section(EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4)
    Section(EA=28000000.0, EI=14000.0, kGA=10000000.0, rhoA=1.2, rhoI=0.0006)
    """

    EA: float
    EI: float
    kGA: float
    rhoA: float
    rhoI: float

    def __post_init__(self):
        for spec in fields(self):
            value = getattr(self, spec.name)
            check = non_negative_number if spec.name == "rhoI" else positive_number
            # frozen dataclass: store the validated float through object
            object.__setattr__(self, spec.name, check(spec.name, value))

    @classmethod
    def from_material(cls, E, G, A, I, rho, k=5 / 6):
        """Section from material constants and section geometry.

        EA = E·A, EI = E·I, kGA = k·G·A, ρA = ρ·A, ρI = ρ·I.

        Parameters
        ----------
        E : float
            Young's modulus in Pa.
        G : float
            Shear modulus in Pa.
        A : float
            Cross-section area in m².
        I : float
            Second moment of area about the bending axis in m⁴.
        rho : float
            Density in kg/m³.
        k : float, optional
            Shear correction factor (dimensionless), 5/6 for a rectangle.

        Returns
        -------
        Section

        Raises
        ------
        ValueError
            If any input is not finite and positive.
        """
        E = positive_number("E", E)
        G = positive_number("G", G)
        A = positive_number("A", A)
        I = positive_number("I", I)
        rho = positive_number("rho", rho)
        k = positive_number("k", k)
        return cls(EA=E * A, EI=E * I, kGA=k * G * A, rhoA=rho * A, rhoI=rho * I)

    @classmethod
    def rectangle(cls, E, nu, b, h, rho, k=5 / 6):
        """Section of a solid rectangle of width b and height h.

        A = b·h, I = b·h³/12 (bending in the plane of h), G = E/(2(1 + ν)).

        Parameters
        ----------
        E : float
            Young's modulus in Pa.
        nu : float
            Poisson's ratio, in the open interval (−1, 0.5).
        b : float
            Width (out of the plane of bending) in m.
        h : float
            Height (in the plane of bending) in m.
        rho : float
            Density in kg/m³.
        k : float, optional
            Shear correction factor (dimensionless), 5/6 by default.

        Returns
        -------
        Section

        Raises
        ------
        ValueError
            If nu is outside (−1, 0.5) or another input is not finite and
            positive.

        Examples
        --------
        >>> s = Section.rectangle(E=210e9, nu=0.3, b=0.1, h=0.1, rho=7850)
        >>> round(s.EI)
        1750000
        """
        nu = _finite_float("nu", nu)
        if not -1.0 < nu < 0.5:
            raise ValueError(f"nu must lie in the open interval (-1, 0.5), got {nu!r}")
        E = positive_number("E", E)
        b = positive_number("b", b)
        h = positive_number("h", h)
        return cls.from_material(
            E=E, G=E / (2.0 * (1.0 + nu)), A=b * h, I=b * h**3 / 12.0, rho=rho, k=k
        )
