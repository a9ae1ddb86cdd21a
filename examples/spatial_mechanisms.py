"""Bricard's mechanism and the spatial slider–crank under the three schemes, against their references.

Scenes ``skfem_flex.scenes.bricard()`` (10 s; its redundant hinge equation dropped, said once) and
``spatial_slider_crank()`` (5 s), Δt = 1e-3 s, under energy-momentum, the trapezoidal rule and
generalized-α: the largest error at the reference times (:data:`~skfem_flex.scenes.spatial.BRICARD_REFERENCE`,
:data:`~skfem_flex.scenes.spatial.SLIDER_CRANK_REFERENCE`) and the largest relative change of the energy
(Bricard: relative to the largest kinetic energy; it starts at rest). The IFToMM library's "high precision"
level is 1e-3 on the reported quantities.

Run ``python examples/spatial_mechanisms.py``. Importing the module computes the results. Quick mode
(``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): 1 s of each.
"""
import os
import warnings

import numpy as np

import skfem_flex as sf
from skfem_flex.scenes.spatial import BRICARD_REFERENCE, SLIDER_CRANK_REFERENCE

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
T_BRICARD, T_CRANK, DT = (1.0, 1.0, 1e-3) if QUICK else (10.0, 5.0, 1e-3)
SCHEMES = ("energy-momentum", "trapezoidal", "generalized-alpha")


def at(result, t):
    return int(np.argmin(np.abs(result.t - t)))


with warnings.catch_warnings():
    warnings.simplefilter("ignore")               # the dropped hinge equation is said once per scene
    bricard_scene = sf.scenes.bricard()
bricard, crank = {}, {}
for scheme in SCHEMES:
    r = sf.simulate(bricard_scene, T_BRICARD, DT, scheme=scheme)
    err = max(float(np.abs(r.probes["P3"][at(r, t)] - p).max()) for t, p in BRICARD_REFERENCE.items() if t <= T_BRICARD)
    bricard[scheme] = (err, float(np.abs(r.total_energy - r.total_energy[0]).max() / r.kinetic.max()), r.wall_time)
    r = sf.simulate(sf.scenes.spatial_slider_crank(), T_CRANK, DT, scheme=scheme)
    theta = np.unwrap(r.probes["crank angle"])
    ref = [(t, x, th) for t, (x, th) in SLIDER_CRANK_REFERENCE.items() if t <= T_CRANK]
    crank[scheme] = (max(abs(r.probes["slider"][at(r, t)] - x) for t, x, _ in ref),
                     max(abs(theta[at(r, t)] - th) for t, _, th in ref),
                     float(np.abs(r.total_energy - r.total_energy[0]).max() / r.total_energy[0]), r.wall_time)


def summary():
    lines = [f"Δt = {DT:g} s; Bricard {T_BRICARD:g} s, slider–crank {T_CRANK:g} s", "",
             "| scene | scheme | error at the reference times | energy change | wall (s) |", "|---|---|---|---|---|"]
    for s, (e, de, w) in bricard.items():
        lines.append(f"| bricard | {s} | P3 {e:.1e} m | {de:.1e} | {w:.2f} |")
    for s, (ex, eth, de, w) in crank.items():
        lines.append(f"| spatial_slider_crank | {s} | x_C {ex:.1e} m, θ {eth:.1e} rad | {de:.1e} | {w:.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(summary())
