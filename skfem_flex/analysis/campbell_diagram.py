"""Campbell diagrams: modes of a scene against one parameter of its factory (:func:`campbell`)."""
from __future__ import annotations

import inspect
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .modal import modes

__all__ = ["CampbellDiagram", "campbell"]


@dataclass
class CampbellDiagram:
    """Modes of a scene against one parameter.

    Attributes
    ----------
    parameter : str
    values : ndarray (p,)
    omega : ndarray (p, n_modes)
        Frequencies Im s, rad/s, lowest first at every value (NaN where fewer modes).
    damping_ratio, growth_rate : ndarray (p, n_modes)
    about : str
    scene_name : str
    unit : str
        Unit of the parameter (from the factory's ``units``, when it has them).
    """

    parameter: str
    values: np.ndarray
    omega: np.ndarray
    damping_ratio: np.ndarray
    growth_rate: np.ndarray
    about: str = "steady"
    scene_name: str = "scene"
    unit: str = ""

    @property
    def frequency_hz(self):
        """Frequencies in Hz."""
        return self.omega / (2.0 * np.pi)

    def rows(self):
        """One dict per (value, mode): parameter value, mode, omega, Hz, damping ratio, growth rate."""
        out = []
        for i, val in enumerate(self.values):
            for k in range(self.omega.shape[1]):
                if np.isfinite(self.omega[i, k]):
                    out.append({self.parameter: float(val), "mode": k + 1, "omega_rad_s": float(self.omega[i, k]),
                                "frequency_hz": float(self.frequency_hz[i, k]),
                                "damping_ratio": float(self.damping_ratio[i, k]),
                                "growth_rate_1_s": float(self.growth_rate[i, k])})
        return out

    def write_table(self, stem):
        """Write ``STEM.csv`` and ``STEM.md`` (frequencies in Hz, one column per mode); returns both paths."""
        stem = Path(stem)
        stem.parent.mkdir(parents=True, exist_ok=True)
        nm = self.omega.shape[1]
        head = [self.parameter] + [f"f{k + 1}_hz" for k in range(nm)] + [f"zeta{k + 1}" for k in range(nm)]
        lines = [",".join(head)]
        md = ["| " + " | ".join([f"{self.parameter} ({self.unit})" if self.unit else self.parameter]
                                 + [f"f{k + 1} (Hz)" for k in range(nm)]) + " |",
              "|" + "---|" * (nm + 1)]
        for i, val in enumerate(self.values):
            f = self.frequency_hz[i]
            lines.append(",".join([repr(float(val))] + [repr(float(x)) for x in f]
                                  + [repr(float(x)) for x in self.damping_ratio[i]]))
            md.append("| " + " | ".join([f"{val:.6g}"] + [f"{x:.6g}" for x in f]) + " |")
        csv_path, md_path = stem.with_suffix(".csv"), stem.with_suffix(".md")
        csv_path.write_text("\n".join(lines) + "\n")
        md_path.write_text("\n".join(md) + "\n")
        return csv_path, md_path

    def plot(self, path=None, orders=None):
        """Frequencies against the parameter (:func:`skfem_flex.io.plots.plot_campbell`)."""
        from ..io.plots import plot_campbell

        return plot_campbell(self, path, orders)


def campbell(build, parameter, values, n_modes=6, about="steady", t=0.0, **fixed):
    """Frequencies of a scene against one parameter, each point linearized about its own state.

    Parameters
    ----------
    build : callable
        A factory ``build(**params) -> Scene``, e.g. ``sf.scenes.rotating_beam`` or
        ``sf.scenes.get("rotating_beam")``; its ``__name__`` names the diagram and its ``units``
        (a catalogue scene's units, when it has them) give the parameter's unit.
    parameter : str
        The factory's keyword varied (e.g. ``"omega"``).
    values : sequence of float
    n_modes : int
    about : {"steady", "static", "initial"}
    t : float
    **fixed
        Other keywords of the factory.

    Returns
    -------
    CampbellDiagram
        Modes are sorted by frequency at every value (not tracked by shape).

    Raises
    ------
    TypeError
        If ``build`` is not callable (a catalogue name: pass ``sf.scenes.get(name)``).
    ValueError
        For a parameter the factory does not take.
    """
    if not callable(build):
        raise TypeError(f"campbell: build must be a function that builds the scene, e.g. "
                        f"sf.scenes.get('rotating_beam'), got {build!r}")
    factory, name = build, getattr(build, "__name__", "scene")
    unit = getattr(factory, "units", {}).get(parameter, "")
    params = inspect.signature(factory).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    for key in [parameter, *fixed]:
        if key not in params and not takes_any:
            raise ValueError(f"scene {name!r} has no parameter {key!r}; it has: {', '.join(params) or 'none'}")
    values = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"values must be a non-empty list of finite numbers, got {values!r}")
    n_modes = int(n_modes)
    om = np.full((values.size, n_modes), np.nan)
    zeta, grow = om.copy(), om.copy()
    for i, val in enumerate(values):
        res = modes(factory(**{**fixed, parameter: float(val)}), about=about, n_modes=n_modes, t=t)
        k = res.eigenvalues.size
        om[i, :k], zeta[i, :k], grow[i, :k] = res.omega, res.damping_ratio, res.growth_rate
    label = about if isinstance(about, str) else "given"
    return CampbellDiagram(parameter, values, om, zeta, grow, label, name, unit)
