"""Slider–crank with a meshed connecting rod: Craig–Bampton reduction, Green–Lagrange stiffening, stress series.

The rod is ``examples/meshes/conrod.msh`` (made by ``examples/meshes/make_conrod.py``: a planar
rod with a big-end and a small-end hole, 8 mm thick steel), read by meshio; the node sets around
the holes (physical groups ``big_end``, ``small_end``) are the interfaces where the crank pin and
the wrist pin attach. The rod is reduced to 3 fixed-interface modes, the small end's constraint
modes and the modal derivatives of those constraint modes (12 coordinates), and runs in Simeon's slider–crank (crank 0.15 m at 150 rad/s).
The run writes a ParaView series (``meshed_rod.pvd``) whose cells carry σxx, σyy, σxy and von Mises
(Pa) in the rod, prints the peak von Mises stress and the energy balance, and draws the rod's von
Mises field at the instant of peak stress (``meshed_rod.png``: the mechanism in the global frame,
the rod's deformation magnified).

Before the timed run, a run of a few steps of the same scene compiles the Numba kernels (or loads
them from numba's cache); its wall time is printed apart as "compile and start-up".

Run ``python examples/meshed_rod.py [OUT_DIR] [--revolutions 1]`` (default ``examples/output/meshed_rod``).

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): a coarse rod (element size 8 mm instead
of 3 mm, about 1 800 DOFs instead of 12 576) written by ``make_conrod.py`` into OUT_DIR, and
0.1 revolution by default.
"""
import argparse
import os
import time
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.output import VTKSeries
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
HERE = Path(__file__).resolve().parent
MESH = HERE / "meshes" / "conrod.msh"
OMEGA = 150.0
QUICK_SIZE = 0.008          # m, element size of the quick mode's coarse rod


def make_scene(mesh=MESH, n_modes=3, size=0.003):
    """The slider–crank with the meshed rod; a missing mesh file is written first by ``make_conrod.py``
    with element size ``size`` (m)."""
    if not Path(mesh).exists():
        from meshes.make_conrod import write
        Path(mesh).parent.mkdir(parents=True, exist_ok=True)
        write(mesh, size)
    return sf.scenes.slider_crank(body="plane-stress-modal", mesh=str(mesh), n_modes=n_modes, omega=OMEGA)


def warm_up(scene, dt=1e-4, steps=3):
    """Wall time (s) of a few steps of ``scene``: the one-off compile (or cache load) of its kernels."""
    start = time.perf_counter()
    sf.simulate(scene, steps * dt, dt)
    return time.perf_counter() - start


def run(out_dir, t_end, dt=1e-4, record_every=10, n_modes=3, scene=None):
    """Simulate and write the VTK series; returns (result, scene). ``scene``: one of :func:`make_scene` (else
    built here)."""
    if scene is None:
        scene = make_scene(n_modes=n_modes)
    sink = VTKSeries(out_dir, name="meshed_rod")
    res = sf.simulate(scene, t_end, dt, output=[sink], record_every=record_every)
    return res, scene


def peak_von_mises(scene, res):
    """Largest cell von Mises stress (Pa) of the rod at each recorded step."""
    rod = scene.bodies[1]
    return np.array([rod.stresses(scene.coordinates(rod, q))["von_mises"].max() for q in res.q])


def plot_peak(scene, res, path, magnify=200.0):
    """Von Mises stress of the rod (MPa) on its deformed mesh (displacement × ``magnify``) at peak stress."""
    plt, out = pyplot_for(Path(path).parent)
    rod = scene.bodies[1]
    vm = peak_von_mises(scene, res)
    k = int(np.argmax(vm))
    q = scene.coordinates(rod, res.q[k])
    qm = q.copy()
    qm[3:] *= magnify
    geo = rod.geometry(qm, np.zeros_like(q))
    tri = geo.cells[0][1]
    fig, ax = plt.subplots(figsize=(8.0, 2.6), layout="constrained")
    pc = ax.tripcolor(geo.points[:, 0], geo.points[:, 1], tri, facecolors=rod.stresses(q)["von_mises"] / 1e6,
                      cmap="viridis")
    crank = scene.coordinates(scene.bodies[0], res.q[k])
    tip = crank[:2] + 0.5 * 0.15 * np.array([np.cos(crank[2]), np.sin(crank[2])])
    ax.plot([0.0, tip[0]], [0.0, tip[1]], "k-", lw=3, label="crank")
    ax.set_aspect("equal")
    ax.set_title(f"von Mises stress at t = {res.t[k]:.4f} s\n(rod deformation × {magnify:g} in its frame, "
                 f"which is attached to the big end)", fontsize=9)
    fig.colorbar(pc, ax=ax, label="MPa")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.savefig(out / Path(path).name, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", default=str(HERE / "output" / "meshed_rod"))
    ap.add_argument("--revolutions", type=float, default=0.1 if QUICK else 1.0)
    args = ap.parse_args()
    start = time.perf_counter()
    scene = make_scene(Path(args.out) / "conrod_quick.msh", size=QUICK_SIZE) if QUICK else make_scene()
    setup = time.perf_counter() - start
    startup = warm_up(scene)
    res, scene = run(args.out, args.revolutions * 2 * np.pi / OMEGA, scene=scene)
    rod = scene.bodies[1]
    vm = peak_von_mises(scene, res)
    print(f"rod: {rod.model.n_dofs} DOFs reduced to {rod.n_elastic} coordinates ({rod.reference}); "
          f"lowest frequencies {np.round(rod.frequencies[:3], 1)} rad/s; set-up (mesh, reduction) {setup:.1f} s")
    print(f"compile and start-up {startup:.1f} s; {res.steps} steps in {res.wall_time:.1f} s; "
          f"relative energy balance error {res.relative_energy_error():.2e}; "
          f"max |joint residual| {res.constraint_residual.max():.1e}")
    print(f"peak von Mises stress {vm.max() / 1e6:.2f} MPa at t = {res.t[np.argmax(vm)]:.4f} s")
    plot_peak(scene, res, Path(args.out) / "meshed_rod.png")
    print(f"series and figure written to {Path(args.out) / 'meshed_rod.pvd'}, {Path(args.out) / 'meshed_rod.png'}")
