"""Animations of modes: one VTK series per mode (:func:`write_mode_series`)."""
from __future__ import annotations

import math

import numpy as np

from .matrix_tools import TINY, inf_norm

__all__ = ["write_mode_series"]


def write_mode_series(scene, result, directory, frames=24, amplitude=0.1, prefix=None):
    """Write every mode as a VTK series that animates it (one ``.pvd`` per mode).

    Frame j of mode k shows q* + a Re(φ_k e^{iψ_j}), ψ_j = 2π j/frames; the series' time is
    the phase ψ/2π (one cycle from 0 to 1). ``a`` makes the largest displacement of the
    output geometry ``amplitude`` times the scene's size (``Scene.length_scale``).

    Returns
    -------
    list of Path
        The ``.pvd`` file of each mode.
    """
    from ..io.output import VTKSeries

    if isinstance(frames, bool) or int(frames) != frames or frames < 2:
        raise ValueError(f"frames must be an integer >= 2, got {frames!r}")
    amplitude = float(amplitude)
    if not math.isfinite(amplitude) or amplitude <= 0:
        raise ValueError(f"amplitude must be finite and positive, got {amplitude!r}")
    prefix = prefix or scene.name
    q0, v0 = result.system.q, result.system.v
    size = scene.length_scale
    paths = []
    for k in range(result.shapes.shape[1]):
        phi = result.shapes[:, k].astype(complex)
        a = amplitude * size / max(_geometry_gain(scene, q0, v0, phi.real) if np.any(phi.real) else 0.0,
                                   _geometry_gain(scene, q0, v0, phi.imag) if np.any(phi.imag) else 0.0,
                                   TINY)
        if not math.isfinite(a):
            a = amplitude
        sink = VTKSeries(directory, f"{prefix}_mode{k + 1:02d}")
        w = float(result.omega[k])
        for j in range(int(frames) + 1):
            psi = 2.0 * np.pi * j / int(frames)
            rot = np.exp(1j * psi)
            sink.write(scene, j / int(frames), q0 + a * (phi * rot).real, v0 + a * w * (1j * phi * rot).real)
        sink.close()
        paths.append(sink.pvd_path)
    return paths


def _geometry_gain(scene, q, v, direction):
    """max |Δx| of the output points per unit step along ``direction`` (finite difference)."""
    eps = 1e-6 * scene.length_scale / max(inf_norm(direction), TINY)

    def points(qq):
        return np.vstack([np.asarray(b.geometry(qq[scene.slice(b)], v[scene.slice(b)]).points, float)[:, :2]
                          for b in scene.bodies])
    try:
        d = points(q + eps * direction) - points(q)
    except (ValueError, NotImplementedError):
        return 0.0
    return float(np.abs(d).max()) / eps
