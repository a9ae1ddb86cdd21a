"""Timoshenko cantilever: tip load convergence and natural modes.

A steel cantilever (E = 210 GPa, ν = 0.3, ρ = 7850 kg/m³, 0.1 m × 0.1 m,
k = 5/6) clamped at x = 0.

* Static: tip load P; the finite element tip deflection is compared with
  Timoshenko theory, P L³/(3EI) + P L/(kGA), for L/h = 5, 100 and 1000 on
  P1 meshes with reduced (one-point) and full shear integration. Reduced
  shear converges at second order; full integration locks for slender beams.
* Modes: the first natural frequencies of the L = 1 m (L/h = 10) cantilever
  with 64 P1 elements; the mode shapes are saved as a PNG.

Run ``python examples/cantilever.py [OUTPUT_DIR]`` (default
``examples/output/``). Importing the module computes the results without
plotting.

Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests) changes nothing here: static
solves and one small eigenproblem take about a second at full size.
"""
import sys
from pathlib import Path

import numpy as np
import skfem

from skfem_flex.fem.beam import TimoshenkoBeam
from skfem_flex.io.plots import pyplot_for
from skfem_flex.fem.section import Section

E, NU, WIDTH, HEIGHT, RHO = 210e9, 0.3, 0.1, 0.1, 7850.0
SECTION = Section.rectangle(E=E, nu=NU, b=WIDTH, h=HEIGHT, rho=RHO)
TIP_LOAD = -1e3  # N, transverse
SLENDERNESS = (5, 100, 1000)  # L/h
N_ELEMENTS = (2, 4, 8, 16, 32, 64)
SHEAR_RULES = ("reduced", "full")


def cantilever(length, n_elements, order=1, shear="reduced"):
    """Beam on a uniform mesh of [0, length] and its clamped DOFs."""
    mesh = skfem.MeshLine(np.linspace(0.0, length, n_elements + 1))
    beam = TimoshenkoBeam(mesh, SECTION, order=order, shear=shear)
    return beam, beam.dofs_at(0.0)


def tip_deflection_error(slenderness, n_elements, shear):
    """Relative error of the FE tip deflection under a tip load."""
    length = slenderness * HEIGHT
    beam, clamp = cantilever(length, n_elements, shear=shear)
    q = beam.solve_static(beam.load(Q=(length, TIP_LOAD)), fixed=clamp)
    exact = TIP_LOAD * length**3 / (3 * SECTION.EI) + TIP_LOAD * length / SECTION.kGA
    return q[beam.dofs_at(length)[1]] / exact - 1.0


# tip_error[shear][i, j]: N_ELEMENTS[i] elements, SLENDERNESS[j]
tip_error = {
    shear: np.array([[tip_deflection_error(s, n, shear) for s in SLENDERNESS] for n in N_ELEMENTS])
    for shear in SHEAR_RULES
}
# observed order between the two finest meshes
observed_order = {
    shear: np.log2(np.abs(errors[-2] / errors[-1])) for shear, errors in tip_error.items()
}

modal_beam, modal_clamp = cantilever(1.0, 64)
omega, mode_shapes = modal_beam.modes(fixed=modal_clamp, n_modes=4)
# a mode is axial when its largest u exceeds its largest w
is_axial = (
    np.abs(mode_shapes[modal_beam.field_dofs[0]]).max(axis=0)
    > np.abs(mode_shapes[modal_beam.field_dofs[1]]).max(axis=0)
)


def convergence_table():
    """The tip-deflection errors as a text table."""
    header = "elements | " + " | ".join(
        f"{shear:>7} L/h={s:<4}" for shear in SHEAR_RULES for s in SLENDERNESS
    )
    lines = [header, "-" * len(header)]
    for i, n in enumerate(N_ELEMENTS):
        cells = [f"{tip_error[shear][i, j]:>+16.3e}" for shear in SHEAR_RULES
                 for j in range(len(SLENDERNESS))]
        lines.append(f"{n:>8} | " + " | ".join(cells))
    cells = [f"{observed_order[shear][j]:>16.2f}" for shear in SHEAR_RULES
             for j in range(len(SLENDERNESS))]
    lines.append(f"{'order':>8} | " + " | ".join(cells))
    return "\n".join(lines)


if __name__ == "__main__":
    print("Relative error of the tip deflection, P1 elements "
          "(exact: P L^3/(3EI) + P L/(kGA))")
    print(convergence_table())
    print("\nNatural frequencies of the L/h = 10 cantilever, 64 P1 elements")
    for k, (w, axial) in enumerate(zip(omega, is_axial), start=1):
        kind = "axial" if axial else "bending"
        print(f"  mode {k}: {w:10.2f} rad/s = {w / (2 * np.pi):9.2f} Hz  ({kind})")

    plt, output = pyplot_for(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "output")

    x = modal_beam.x_nodes
    fig, ax = plt.subplots(figsize=(7, 4))
    for k in range(omega.size):
        u, w = (mode_shapes[modal_beam.node_dofs[:, f], k] for f in (0, 1))
        field, name = (u, "u") if is_axial[k] else (w, "w")
        ax.plot(x, field / np.abs(field).max(),
                label=f"mode {k + 1}, {omega[k] / (2 * np.pi):.0f} Hz ({name})")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("normalised displacement")
    ax.set_title("Timoshenko cantilever, L/h = 10, 64 P1 elements")
    ax.legend()
    fig.tight_layout()
    fig.savefig(output / "cantilever_modes.png", dpi=120)

    fig, ax = plt.subplots(figsize=(7, 4))
    for shear, style in zip(SHEAR_RULES, ("-o", "--s")):
        for j, s in enumerate(SLENDERNESS):
            ax.loglog(N_ELEMENTS, np.abs(tip_error[shear][:, j]), style,
                      label=f"{shear}, L/h = {s}")
    ax.set_xlabel("elements")
    ax.set_ylabel("relative tip deflection error")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(output / "cantilever_convergence.png", dpi=120)
    print(f"\nfigures written to {output}")
