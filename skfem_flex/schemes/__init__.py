"""Time-stepping schemes: each an object that owns its step (one compiled kernel), its parameters and its
Newton settings."""
from .base import NewmarkState, NewtonSettings, Scheme, State
from .energy_momentum import EnergyMomentum
from .newmark import GeneralizedAlpha, Newmark, Trapezoidal

__all__ = ["Scheme", "State", "NewmarkState", "NewtonSettings", "EnergyMomentum", "Newmark", "Trapezoidal",
           "GeneralizedAlpha", "SCHEMES", "make_scheme"]

#: the schemes by name
SCHEMES = {
    "energy-momentum": EnergyMomentum,
    "trapezoidal": Trapezoidal,
    "generalized-alpha": GeneralizedAlpha,
}


def make_scheme(scheme, rho_inf=None, newton=None):
    """A scheme object from a name or an instance.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones), ρ∞ given to a scheme that has none, or
        settings given beside a scheme object (set them on the object).
    """
    if isinstance(scheme, Scheme):
        for name, value in (("rho_inf", rho_inf), ("newton", newton)):
            if value is not None:
                raise ValueError(f"{name}={value!r} given with the scheme object {type(scheme).__name__}; "
                                 f"set it on the object instead (e.g. GeneralizedAlpha(rho_inf=0.8, newton=...))")
        return scheme
    if not isinstance(scheme, str) or scheme not in SCHEMES:
        raise ValueError(f"unknown scheme {scheme!r}; choose one of {sorted(SCHEMES)}")
    if scheme == "generalized-alpha":
        return GeneralizedAlpha(0.9 if rho_inf is None else rho_inf, newton=newton)
    if rho_inf is not None:
        raise ValueError(f"rho_inf applies to generalized-alpha only, not to {scheme!r}")
    return SCHEMES[scheme](newton=newton)
