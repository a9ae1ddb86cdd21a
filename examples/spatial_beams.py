"""Geometrically exact spatial beams: the 45° bend, the flying beam in space and the right-angle frame.

* ``bend_45``: the tip displacement under the load 600 against the converged published value
  (:data:`~skfem_flex.scenes.spatial_beams.BEND_45_REFERENCE`) for two-node elements interpolating the rotations
  (the default), for the director interpolation (P1 and P2), and the same end state after 3, 8 and 30 equal
  load steps on the default mesh (path independence).
* the roll-up: a straight cantilever under the end moment 2πEI/L about the normal of its bending plane, in 8
  load steps: how far its tip ends from the root (a full circle closes), for 4, 8 and 16 elements of each
  interpolation.
* ``flying_spaghetti_3d`` (Δt = 0.1 s): after the pulse (t ≥ 5 s) the linear momentum against the impulse
  (50, 0, 0) kg m/s, and the relative spread of the energy and of the angular momentum, under
  energy-momentum and the trapezoidal rule.
* ``right_angle_frame``: the elbow's and the tip's out-of-plane displacement, their extreme values and
  times, on four meshes and steps (energy-momentum), and the tip's history against Simo and Vu-Quoc's
  published curve (``examples/data/simo_vu_quoc_1988_right_angle_tip.csv``, read off their figure):
  ``right_angle_frame.png`` in OUT_DIR.
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
BEND_MESHES = () if QUICK else ((1, "rotations", 4), (1, "rotations", 8), (1, "rotations", 16),
                                 (1, "rotations", 32), (1, "directors", 8), (1, "directors", 16),
                                 (2, "directors", 4), (2, "directors", 8), (2, "directors", 16))
LOAD_STEPS = () if QUICK else (3, 8, 30)
ROLL_UP = ((4, "rotations"),) if QUICK else tuple((n, i) for i in ("rotations", "directors") for n in (4, 8, 16))
T_FLY = 6.0 if QUICK else 30.0
FRAME_RUNS = ((2, 0.05, 3.5),) if QUICK else ((5, 0.05, 30.0), (10, 0.05, 30.0), (10, 0.025, 30.0),
                                              (20, 0.01, 30.0))
PUBLISHED_TIP = np.loadtxt(Path(__file__).parent / "data" / "simo_vu_quoc_1988_right_angle_tip.csv", delimiter=",")
LAMBDAS = (0.0, 6.0, 12.0) if QUICK else tuple(np.linspace(0.0, 12.0, 25))


def bend_tip(order, interpolation, n, load_steps=None):
    scene = sf.scenes.bend_45(n_elements=n, order=order, interpolation=interpolation)
    tip = scene.probes["tip"].point
    q = sf.static_equilibrium(scene, load_steps=load_steps).q
    return tip.position(q) - tip.position(scene.bodies[0].q0)


bend = {mesh: bend_tip(*mesh) for mesh in BEND_MESHES}
path = {steps: bend_tip(1, "rotations", 8, load_steps=steps) for steps in LOAD_STEPS}


def roll_up(n, interpolation, length=10.0, EI=500.0):
    """(tip distance from the root / L, load factor reached) of a cantilever under the end moment 2πEI/L."""
    sec = sf.SpatialSection(EA=1e4, GA1=1e4, GA2=1e4, GJ=400.0, EI1=EI, EI2=700.0, rhoA=1.0, rhoI1=10.0,
                            rhoI2=10.0)
    beam = sf.SpatialExactBeam.straight(sec, (0.0, 0.0, 0.0), (length, 0.0, 0.0), n_elements=n,
                                        normal=(0.0, 0.0, 1.0), interpolation=interpolation)
    tip = beam.point(length)
    scene = sf.Scene([beam], constraints=[sf.Weld3D(beam.point(0.0))],
                     forces=[sf.SpatialMoment(tip, (0.0, 0.0, 2.0 * np.pi * EI / length))], name="roll-up")
    try:
        state = sf.static_equilibrium(scene, load_steps=8)
    except sf.ConvergenceError as exc:
        state = exc.state
    return float(np.linalg.norm(tip.position(state.q))) / length, float(state.load_factor)


rolled = {(n, interpolation): roll_up(n, interpolation) for n, interpolation in ROLL_UP}

flying = {}
for scheme in ("energy-momentum", "trapezoidal"):
    r = sf.simulate(sf.scenes.flying_spaghetti_3d(), T_FLY, 0.1, scheme=scheme)
    free = r.t >= 5.0 - 1e-12
    E, L = r.total_energy[free], r.angular_momentum[free]
    flying[scheme] = (float(np.abs(r.linear_momentum[free] - [50.0, 0.0, 0.0]).max()),
                      float(np.ptp(E) / np.abs(E).max()), float(np.ptp(L, axis=0).max() / np.abs(L).max()),
                      r.wall_time, r.wall_time / r.steps * 1e3)

def extremes(t, z):
    """(the largest value, its time), (the smallest, its time) of a history."""
    i, j = int(np.argmax(z)), int(np.argmin(z))
    return (float(z[i]), float(t[i])), (float(z[j]), float(t[j]))


frame, frame_runs = {}, {}
for n, dt, t_end in FRAME_RUNS:
    r = sf.simulate(sf.scenes.right_angle_frame(n_elements=n), t_end, dt, scheme="energy-momentum")
    elbow, tip = (r.probes[p][:, 2] - r.probes[p][0, 2] for p in ("elbow", "tip"))
    early = r.t <= 5.0
    peaks = {"elbow, first peak": extremes(r.t[early], elbow[early])[0], "elbow, least": extremes(r.t, elbow)[1]}
    peaks["tip, largest"], peaks["tip, least"] = extremes(r.t, tip)
    peaks["wall"] = (r.wall_time, r.wall_time / r.steps * 1e3)
    frame[(n, dt)] = peaks
    frame_runs[(n, dt)] = (r.t, elbow, tip)


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
             + ")", "", "| order | interpolation | elements | u | largest component error / ‖u_ref‖ |",
             "|---|---|---|---|---|"]
    for (order, interpolation, n), u in bend.items():
        lines.append(f"| P{order} | {interpolation} | {n} | ({u[0]:.3f}, {u[1]:.3f}, {u[2]:.3f}) | "
                     f"{np.abs(u - BEND_45_REFERENCE).max() / ref:.2%} |")
    if path:
        spread = max(float(np.abs(u - path[LOAD_STEPS[0]]).max()) for u in path.values())
        lines += ["", f"P1, rotations, 8 elements, load steps {LOAD_STEPS}: largest difference of the end states "
                  f"{spread:.1e}"]
    lines += ["", "roll-up under the end moment 2πEI/L, 8 load steps:", "",
              "| interpolation | elements | tip distance from the root / L | load factor reached |", "|---|---|---|---|"]
    for (n, interpolation), (gap, s) in rolled.items():
        lines.append(f"| {interpolation} | {n} | {gap:.1e} | {s:.4f} |")
    lines += ["",
              f"flying beam in space, Δt = 0.1 s, {T_FLY:g} s, after the pulse:", "",
              "| scheme | linear momentum − impulse | energy spread | angular momentum spread | wall (s) | ms a step |",
              "|---|---|---|---|---|---|"]
    for s, (p, e, L, w, ms) in flying.items():
        lines.append(f"| {s} | {p:.1e} | {e:.1e} | {L:.1e} | {w:.2f} | {ms:.2f} |")
    lines += ["", "right-angle frame, out-of-plane displacement (energy-momentum); the published tip curve (read "
              "off Simo and Vu-Quoc's figure): largest " + "{:.2f} at {:.2f} s, least {:.2f} at {:.2f} s".format(
                  *extremes(PUBLISHED_TIP[:, 0], PUBLISHED_TIP[:, 1])[0], *extremes(PUBLISHED_TIP[:, 0],
                                                                                  PUBLISHED_TIP[:, 1])[1]), "",
              "| elements per leg | Δt | elbow: first peak (t) | elbow: least (t) | tip: largest (t) | tip: least (t) | "
              "wall (s) | ms a step |", "|---|---|---|---|---|---|---|---|"]
    for (n, dt), pk in frame.items():
        cells = [f"{pk[k][0]:.3f} ({pk[k][1]:.2f} s)" for k in ("elbow, first peak", "elbow, least", "tip, largest",
                                                                  "tip, least")]
        lines.append(f"| {n} | {dt:g} | " + " | ".join(cells) + f" | {pk['wall'][0]:.1f} | {pk['wall'][1]:.2f} |")
    (pub_hi, t_hi), (pub_lo, t_lo) = extremes(PUBLISHED_TIP[:, 0], PUBLISHED_TIP[:, 1])
    finest = frame[max(frame)]
    lines += ["", f"the finest run's tip against the published curve: largest {finest['tip, largest'][0] / pub_hi - 1:+.1%}"
              f" ({finest['tip, largest'][1] - t_hi:+.2f} s), least {finest['tip, least'][0] / pub_lo - 1:+.1%} "
              f"({finest['tip, least'][1] - t_lo:+.2f} s)"]
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
    fig, ax = plt.subplots(figsize=(6, 3.6))
    n, dt = max(frame_runs)
    t, elbow, tip = frame_runs[(n, dt)]
    ax.plot(t, tip, "-", label=f"tip ({n} elements per leg, Δt = {dt:g} s)")
    ax.plot(t, elbow, "--", label="elbow")
    ax.plot(PUBLISHED_TIP[:, 0], PUBLISHED_TIP[:, 1], "ko", ms=3, label="tip, Simo and Vu-Quoc 1988 (read off)")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("out-of-plane displacement (m)")
    ax.set_title("Right-angle frame (energy-momentum)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "right_angle_frame.png", dpi=120)
    print(f"wrote {out / 'right_angle_frame.png'}")
