"""Statics, modes and a Campbell diagram of catalogue scenes (skfem_flex.analysis).

Three questions asked before or beside a transient run:

1. **Where does it rest?** The flexible pendulum (EA raised to 1e9 N so the Green–Lagrange
   correction is negligible) hangs under gravity: ``sf.static_equilibrium`` gives the tip
   stretch and the pin reaction, compared with the hanging bar's ρA g L²/(2EA) and ρA g L;
   an ``ExactBeam`` cantilever under the end moment 2πEI/L rolls up into a full circle,
   reached by the automatic load stepping (steps and Newton iterations printed).
2. **What are its modes?** The hanging pendulum's first frequency against the rigid rod's
   √(ρA g L²/2 / (ρA L³/3 + ρI L)), and the slider–crank with its crank held at angle 0.
3. **How do the modes move with a parameter?** The Campbell diagram of the rotating
   cantilever (``rotating_beam``): the lowest in-plane frequencies linearized about the steady
   spin for λ = ω √(ρA L⁴/EI) from 0 to 12, with the Green–Lagrange strain (geometric
   stiffening) and with the linear strain, whose lowest mode diverges (a real growing pair)
   once λ passes the standing beam's first frequency.

Run ``python examples/modes.py [OUT_DIR]`` for the tables and ``campbell.png`` (default
``examples/output``).

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): the roll-up on 8 elements only, the
Campbell diagram at λ = 0, 4, 8, 12 instead of every integer.
"""
import math
import os
import sys
from pathlib import Path

import numpy as np

import skfem_flex as sf
from skfem_flex.io.plots import pyplot_for

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
G = 9.81

# ---------------------------------------------------------------- 1. statics
pendulum = sf.scenes.flexible_pendulum(EA=1e9, EI=1e6)
q_guess, _ = pendulum.initial_state()
q_guess[2] = -0.5 * math.pi                     # start the search from the straight hanging beam
hanging = sf.static_equilibrium(pendulum, q=q_guess)
tip = pendulum.probes["tip"](pendulum, 0.0, hanging.q, hanging.v)
stretch = -tip[1] - 1.0
STRETCH_REF = 1.0 * G * 1.0 ** 2 / (2 * 1e9)
reaction = hanging.reactions["pivot"][1]

roll_up = []
for n in ((8,) if QUICK else (8, 16, 64)):
    section = sf.Section(EA=5e5, EI=50.0, kGA=2e5, rhoA=1.0, rhoI=1e-3)
    beam = sf.ExactBeam.from_points(section, (0.0, 0.0), (2.0, 0.0), n_elements=n)
    fixed = sf.MotionLaw(lambda t: 0.0, lambda t: 0.0, lambda t: 0.0)
    scene = sf.Scene([beam], forces=[sf.NodalLoad(beam, 2.0, moment=2 * math.pi * section.EI / 2.0)],
                     prescribed=[sf.Prescribed(beam, c, fixed) for c in ("ux0", "uy0", "psi0")], name="roll_up")
    state = sf.static_equilibrium(scene)
    gap = beam.point(2.0).position(state.q) - beam.point(0.0).position(state.q)
    roll_up.append((n, state.steps, state.iterations, float(np.max(np.abs(gap))) / 2.0))

# ---------------------------------------------------------------- 2. modes
pendulum_modes = sf.modes(pendulum, about=hanging, n_modes=3)
RIGID_ROD = math.sqrt(1.0 * G / 2 / (1.0 / 3 + 1e-4))
crank = sf.scenes.slider_crank(omega=0.0)
crank_modes = sf.modes(crank, about="static", n_modes=4)

# ---------------------------------------------------------------- 3. Campbell
SCALE = math.sqrt(1.2 * 10.0 ** 4 / 1.4e4)       # λ = ω · SCALE for the default rotating_beam section
LAMBDAS = np.linspace(0.0, 12.0, 4 if QUICK else 13)
green_lagrange = sf.campbell(sf.scenes.rotating_beam, "omega", LAMBDAS / SCALE, n_modes=3)
linear = sf.campbell(sf.scenes.rotating_beam, "omega", LAMBDAS / SCALE, n_modes=4, strain="linear")
#: with the linear strain the lowest bending mode diverges beyond λ ≈ 3.5 (a real pair s = ±σ, Im s = 0);
#: the first two bending modes then are: nothing (NaN) and the lowest oscillating one
diverging = np.nanmax(linear.growth_rate, axis=1) > 1e-9
linear_bending = np.array([[np.nan, row[row > 0][0]] if div else row[row > 0][:2]
                           for row, div in zip(linear.omega, diverging)])
reference = np.array([sf.scenes.rotating_beam_frequencies(w, n_modes=3) for w in LAMBDAS / SCALE])


def tables():
    lines = ["Hanging flexible pendulum (EA = 1e9 N, EI = 1e6 N m²):",
             f"  tip stretch {stretch:.9e} m, hanging bar ρA g L²/(2EA) = {STRETCH_REF:.9e} m "
             f"(rel. {stretch / STRETCH_REF - 1:+.1e})",
             f"  pin reaction {reaction:.9f} N, ρA g L = {G:.9f} N",
             f"  first frequency {pendulum_modes.omega[0]:.9f} rad/s, rigid rod {RIGID_ROD:.9f} rad/s "
             f"(rel. {pendulum_modes.omega[0] / RIGID_ROD - 1:+.1e})", "",
             "Roll-up of an exact cantilever under M = 2πEI/L:", "",
             "| elements | load steps | Newton iterations | |tip − root| / L |", "|---|---|---|---|"]
    lines += [f"| {n} | {s} | {i} | {g:.1e} |" for n, s, i, g in roll_up]
    lines += ["", "Slider–crank, crank held at angle 0 (rad/s):",
              "  " + ", ".join(f"{w:.6g}" for w in crank_modes.omega), "",
              "Campbell diagram of rotating_beam, ω̄ = ω √(ρA L⁴/EI) in the rotating frame:", "",
              "| λ | ω̄₁ Green–Lagrange | ω̄₂ | ω̄₁ rotating_beam_frequencies | ω̄₁ linear strain "
              "| largest growth rate · √(ρA L⁴/EI), linear |",
              "|---|---|---|---|---|---|"]
    for k, lam in enumerate(LAMBDAS):
        first_linear = "diverges" if diverging[k] else f"{linear_bending[k, 0] * SCALE:.4f}"
        lines.append(f"| {lam:g} | {green_lagrange.omega[k, 0] * SCALE:.5f} | {green_lagrange.omega[k, 1] * SCALE:.4f} "
                     f"| {reference[k, 0] * SCALE:.5f} | {first_linear} | {np.nanmax(linear.growth_rate[k]) * SCALE:.3f} |")
    lines += ["", f"largest relative difference to rotating_beam_frequencies (3 modes, all λ): "
                  f"{np.max(np.abs(green_lagrange.omega / reference - 1)):.1e}"]
    return "\n".join(lines)


def plot(out_dir):
    plt, out_dir = pyplot_for(out_dir)
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    for k in range(2):
        ax.plot(LAMBDAS, green_lagrange.omega[:, k] * SCALE, "o-", color=f"C{k}",
                label=f"mode {k + 1}, Green–Lagrange strain")
        ax.plot(LAMBDAS, linear_bending[:, k] * SCALE, "s--", color=f"C{k}", mfc="none",
                label=f"mode {k + 1}, linear strain")
    ax.plot(LAMBDAS, LAMBDAS, "k:", lw=0.8, label="1× spin rate")
    ax.plot(LAMBDAS[diverging], np.zeros(diverging.sum()), "x", color="C3", ms=9,
            label="linear strain: lowest mode diverges (s = ±σ)")
    ax.set_xlabel("λ = ω √(ρA L⁴/EI)")
    ax.set_ylabel("ω̄ = Im s · √(ρA L⁴/EI), rotating frame")
    ax.set_title("Campbell diagram of the rotating cantilever (about the steady spin)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.savefig(out_dir / "campbell.png", dpi=110)
    plt.close(fig)
    return out_dir


if __name__ == "__main__":
    print(tables())
    where = plot(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")
    print(f"PNG written to {where}")
