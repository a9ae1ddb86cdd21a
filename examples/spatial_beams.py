"""Geometrically exact spatial beams: the 45° bend, the flying beam in space and the right-angle frame.

* ``bend_45``: the tip displacement under the load 600 against the converged published value
  (:data:`~skfem_flex.scenes.spatial_beams.BEND_45_REFERENCE`) for P1 and P2 meshes, and the same end state
  after 3, 8 and 30 equal load steps (path independence).
* ``flying_spaghetti_3d`` (Δt = 0.1 s): after the pulse (t ≥ 5 s) the linear momentum against the impulse
  (50, 0, 0) kg m/s, and the relative spread of the energy and of the angular momentum, under
  energy-momentum and the trapezoidal rule.
* ``right_angle_frame``: the elbow's and the tip's out-of-plane displacement, their largest values and
  times, on two meshes and steps (energy-momentum).
* The rotating cantilever (the spatial floating-frame beam ``FloatingBeam3D``, nearly Euler–Bernoulli and
  inextensible, linearized about its steady spin about an axis through its root): the first flapwise and
  lead-lag frequencies over λ = Ω √(ρA L⁴/EI) from 0 to 12, with the Green–Lagrange and the linear axial
  strain, beside the linear ``TimoshenkoBeam3D``'s spin forms, and their Campbell diagram
  (``rotating_beam_3d_campbell.png`` in OUT_DIR).
* ``spin_up_3d`` with the floating-frame and the exact beam: the tip histories' difference.

Run ``python examples/spatial_beams.py [OUT_DIR]`` (default ``examples/output/``). Importing the module computes the results. Quick mode
(``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): no bend (``tests/test_spatial_beam.py`` solves it) and
short runs.
"""
import os
import sys
from pathlib import Path

import numpy as np
import skfem

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for
from skfem_flex.scenes.spatial_beams import BEND_45_REFERENCE

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
BEND_MESHES = () if QUICK else ((1, 8), (1, 16), (1, 32), (2, 4), (2, 8), (2, 16))
LOAD_STEPS = () if QUICK else (3, 8, 30)
T_FLY = 6.0 if QUICK else 30.0
FRAME_RUNS = ((2, 0.05, 3.5),) if QUICK else ((5, 0.05, 30.0), (10, 0.025, 30.0))
LAMBDAS = (0.0, 6.0, 12.0) if QUICK else tuple(np.linspace(0.0, 12.0, 25))


def bend_tip(order, n, load_steps=None):
    scene = sf.scenes.bend_45(n_elements=n, order=order)
    tip = scene.probes["tip"].point
    q = sf.static_equilibrium(scene, load_steps=load_steps).q
    return tip.position(q) - tip.position(scene.bodies[0].q0)


bend = {(order, n): bend_tip(order, n) for order, n in BEND_MESHES}
path = {steps: bend_tip(2, 4, load_steps=steps) for steps in LOAD_STEPS}

flying = {}
for scheme in ("energy-momentum", "trapezoidal"):
    r = sf.simulate(sf.scenes.flying_spaghetti_3d(), T_FLY, 0.1, scheme=scheme)
    free = r.t >= 5.0 - 1e-12
    E, L = r.total_energy[free], r.angular_momentum[free]
    flying[scheme] = (float(np.abs(r.linear_momentum[free] - [50.0, 0.0, 0.0]).max()),
                      float(np.ptp(E) / np.abs(E).max()), float(np.ptp(L, axis=0).max() / np.abs(L).max()),
                      r.wall_time, r.wall_time / r.steps * 1e3)

frame = {}
for n, dt, t_end in FRAME_RUNS:
    r = sf.simulate(sf.scenes.right_angle_frame(n_elements=n), t_end, dt, scheme="energy-momentum")
    peaks = {}
    for probe in ("elbow", "tip"):
        z = r.probes[probe][:, 2] - r.probes[probe][0, 2]
        k = int(np.argmax(np.abs(z)))
        peaks[probe] = (float(z[k]), float(r.t[k]))
    first = int(np.argmax(r.probes["elbow"][: int(5.0 / dt), 2]))
    peaks["elbow, first peak"] = (float(r.probes["elbow"][first, 2]), float(r.t[first]))
    peaks["wall"] = (r.wall_time, r.wall_time / r.steps * 1e3)
    frame[(n, dt)] = peaks


spin_section = sf.SpatialSection(EA=1e4, GA1=1e5, GA2=1e5, GJ=1.0, EI1=1.0, EI2=1.0, rhoA=1.0, rhoI1=1e-6,
                                 rhoI2=1e-6)
spin_beam = sf.TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, 9)), spin_section, order=2)
spin_fixed = np.concatenate([spin_beam.dofs_at(0.0), spin_beam.node_dofs[:, 2]])      # clamped, inextensible
# the floating-frame beam on the same mesh, nearly inextensible (EA = 1e7 EI/L²), about its own steady spin
rotor_section = sf.SpatialSection(EA=1e7, GA1=1e5, GA2=1e5, GJ=1.0, EI1=1.0, EI2=1.0, rhoA=1.0, rhoI1=1e-6,
                                  rhoI2=1e-6)
rotor_beam = sf.TimoshenkoBeam3D(skfem.MeshLine(np.linspace(0.0, 1.0, 9)), rotor_section, order=2)
rotors = {strain: sf.FloatingBeam3D(rotor_beam, strain=strain) for strain in ("green-lagrange", "linear")}
campbell = {}
for lam in LAMBDAS:
    stiff = rotors["green-lagrange"].spinning_modes(lam)
    linear = rotors["linear"].spinning_modes(lam)
    forms = spin_beam.rotating_modes(spin_fixed, lam)
    campbell[lam] = (stiff.first(True)[0], stiff.first(False)[0], linear.first(False), forms.first(True)[0],
                     forms.first(False)[0])

# the same rotor reduced: 6 cantilever modes with the stiffening derivatives and centrifugal shapes, and without
reduced_rotors = {"6 modes + derivatives + shapes": rotors["green-lagrange"].reduced(6),
                  "6 modes alone": rotors["green-lagrange"].reduced(6, n_derivatives=0, centrifugal=False)}
reduction = {}
for lam in (3.0, 12.0):
    full = rotors["green-lagrange"].spinning_modes(lam)
    for label, body in reduced_rotors.items():
        modes = body.spinning_modes(lam)
        reduction[label, lam] = tuple(modes.first(f)[0] / full.first(f)[0] - 1.0 for f in (True, False))

# the spin-up with its out-of-plane tip load: floating-frame against exact beam (8 P1 elements each)
SPIN_UP_T = 0.5 if QUICK else 15.0
spin_up = {body: sf.simulate(sf.scenes.spin_up_3d(body=body), SPIN_UP_T, 0.01) for body in ("floating", "exact")}


def summary():
    ref = np.linalg.norm(BEND_45_REFERENCE)
    lines = ["45° bend, tip displacement under 600 (reference " + ", ".join(f"{x:.3f}" for x in BEND_45_REFERENCE)
             + ")", "", "| order | elements | u | largest component error / ‖u_ref‖ |", "|---|---|---|---|"]
    for (order, n), u in bend.items():
        lines.append(f"| P{order} | {n} | ({u[0]:.3f}, {u[1]:.3f}, {u[2]:.3f}) | "
                     f"{np.abs(u - BEND_45_REFERENCE).max() / ref:.2%} |")
    if path:
        spread = max(float(np.abs(u - path[LOAD_STEPS[0]]).max()) for u in path.values())
        lines += ["", f"P2, 4 elements, load steps {LOAD_STEPS}: largest difference of the end states {spread:.1e}"]
    lines += ["",
              f"flying beam in space, Δt = 0.1 s, {T_FLY:g} s, after the pulse:", "",
              "| scheme | linear momentum − impulse | energy spread | angular momentum spread | wall (s) | ms a step |",
              "|---|---|---|---|---|---|"]
    for s, (p, e, L, w, ms) in flying.items():
        lines.append(f"| {s} | {p:.1e} | {e:.1e} | {L:.1e} | {w:.2f} | {ms:.2f} |")
    lines += ["", "right-angle frame, out-of-plane displacement (energy-momentum):", "",
              "| elements per leg | Δt | elbow: first peak (t) | elbow: largest (t) | tip: largest (t) | wall (s) | "
              "ms a step |", "|---|---|---|---|---|---|---|"]
    for (n, dt), pk in frame.items():
        cells = [f"{pk[k][0]:.3f} ({pk[k][1]:.2f} s)" for k in ("elbow, first peak", "elbow", "tip")]
        lines.append(f"| {n} | {dt:g} | " + " | ".join(cells) + f" | {pk['wall'][0]:.1f} | {pk['wall'][1]:.2f} |")
    lines += ["", "rotating cantilever, first frequencies ω √(ρA L⁴/EI) over λ = Ω √(ρA L⁴/EI): the floating-frame beam "
              "about its steady spin, and the linear beam's spin forms:", "",
              "| λ | flapwise | lead-lag | lead-lag, linear strain (growth rate if it diverges) | linear beam: flapwise, "
              "lead-lag |", "|---|---|---|---|---|"]
    for lam, (flap, lag, (lin, growth), f_forms, g_forms) in campbell.items():
        lin_text = f"{lin:.4f}" if growth <= 1e-6 * flap else f"diverges ({growth:.3f})"
        lines.append(f"| {lam:g} | {flap:.4f} | {lag:.4f} | {lin_text} | {f_forms:.4f}, {g_forms:.4f} |")
    lines += ["", "the rotor reduced (relative error of the first flapwise and lead-lag frequencies against the full beam):",
              "", "| basis | coordinates | λ | flapwise | lead-lag |", "|---|---|---|---|---|"]
    for (label, lam), (flap, lag) in reduction.items():
        lines.append(f"| {label} | {reduced_rotors[label].n_elastic} | {lam:g} | {flap:.1e} | {lag:.1e} |")
    tips = {k: r.probes["tip"] for k, r in spin_up.items()}
    peak = np.abs(tips["exact"]).max(axis=0)
    diff = np.abs(tips["floating"] - tips["exact"]).max(axis=0)
    lines += ["", f"spin_up_3d, {SPIN_UP_T:g} s at Δt = 0.01 s, tip in the hub frame (axial, in plane, out of plane):",
              "", "| | axial | in plane | out of plane | wall (s) | ms a step |", "|---|---|---|---|---|---|",
              f"| largest, exact beam | {peak[0]:.3e} | {peak[1]:.3e} | {peak[2]:.3e} | "
              f"{spin_up['exact'].wall_time:.1f} | {spin_up['exact'].wall_time / spin_up['exact'].steps * 1e3:.2f} |",
              f"| floating frame − exact | {diff[0]:.1e} | {diff[1]:.1e} | {diff[2]:.1e} | "
              f"{spin_up['floating'].wall_time:.1f} | {spin_up['floating'].wall_time / spin_up['floating'].steps * 1e3:.2f} |"]
    return "\n".join(lines)


if __name__ == "__main__":
    print(summary())
    plt, out = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    lams = np.array(list(campbell))
    vals = np.array([[c[0], c[1], c[2][0]] for c in campbell.values()])
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(lams, vals[:, 0], "o-", label="flapwise")
    ax.plot(lams, vals[:, 1], "s-", label="lead-lag")
    ax.plot(lams, vals[:, 2], "x--", label="lead-lag, linear strain")
    ax.plot(lams, lams, "k:", label="λ (once per revolution)")
    ax.set_xlabel("λ = Ω √(ρA L⁴/EI)")
    ax.set_ylabel("ω √(ρA L⁴/EI)")
    ax.plot(lams, [c[3] for c in campbell.values()], "k+", label="linear beam's spin forms")
    ax.plot(lams, [c[4] for c in campbell.values()], "k+")
    ax.set_title("Rotating cantilever (FloatingBeam3D about its steady spin)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "rotating_beam_3d_campbell.png", dpi=120)
    print(f"wrote {out / 'rotating_beam_3d_campbell.png'}")
