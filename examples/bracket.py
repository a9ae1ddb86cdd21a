"""An angle bracket read from a gmsh file: bolted at its base, pulled at its flange, stresses out.

``examples/data/bracket.msh`` (gmsh 2.2, written by :func:`make_bracket_mesh` below with meshio: 0.1 m × 0.1 m
base and flange, 0.01 m thick, 1140 tetrahedra) carries two physical surface groups: ``"bolts"``, the base's
underside beyond y = 0.06 m, and ``"load"``, the flange's top edge face. :func:`~skfem_flex.fem.elasticity3d.load_mesh_3d`
reads it with those groups as named boundaries. The bracket (steel, P2) is reduced by Craig–Bampton with its
frame clamped at the bolts and the load face as a rigid interface, welded to the ground at its frame, and
pulled at the load face by 1 kN along −y (static equilibrium). The script prints

* the load face's displacement of the reduced body against the full mesh's static solution with the same
  rigid face (the constraint modes make them equal: a static interface load is the reduction's exact case);
* the largest von Mises stress, and writes the VTK series of the stressed bracket (``bracket.pvd`` in OUT_DIR).

Run ``python examples/bracket.py [OUT_DIR]`` (default ``examples/output/``). Importing the module computes the
results. Quick mode (``SKFEM_FLEX_EXAMPLE_QUICK=1``, used by the tests): P1 tetrahedra.
"""
import os
import sys
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla
import skfem

import skfem_flex as sf
from skfem_flex.fem.elasticity3d import load_mesh_3d, von_mises_3d
from skfem_flex.io.output import VTKSeries

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK", "") not in ("", "0")
MESH_FILE = Path(__file__).parent / "data" / "bracket.msh"
FORCE = np.array([0.0, -1e3, 0.0])


def make_bracket_mesh(path):
    """Write the bracket's gmsh 2.2 file: an L of hexahedra (10 × 10 × 10 of 0.01 m, those with z > 0.01 m and
    y > 0.01 m removed) split into tetrahedra, with the physical groups "bolts" and "load" (triangles) and
    "bracket" (the tetrahedra)."""
    import meshio
    grid = skfem.MeshHex.init_tensor(*(np.linspace(0.0, 0.1, 11),) * 3)
    centres = grid.p[:, grid.t].mean(axis=1)
    mesh = grid.remove_elements(np.flatnonzero((centres[2] > 0.01) & (centres[1] > 0.01))).to_meshtet()
    tri = mesh.facets.T
    mid = mesh.p[:, mesh.facets].mean(axis=1)
    bolts = tri[np.isclose(mid[2], 0.0) & (mid[1] > 0.06) & np.all(np.isclose(mesh.p[2, mesh.facets], 0.0), axis=0)]
    load = tri[np.all(np.isclose(mesh.p[2, mesh.facets], 0.1), axis=0)]
    blocks = [("triangle", bolts), ("triangle", load), ("tetra", mesh.t.T)]
    tags = [np.full(len(b[1]), k + 1) for k, b in enumerate(blocks)]
    meshio.write(path, meshio.Mesh(mesh.p.T, blocks, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                                   field_data={"bolts": np.array([1, 2]), "load": np.array([2, 2]),
                                               "bracket": np.array([3, 3])}), file_format="gmsh22", binary=False)


mesh = load_mesh_3d(MESH_FILE)
solid = sf.ElasticSolid3D(mesh, E=2e11, nu=0.3, rho=7800.0, order=1 if QUICK else 2, name="bracket")
bracket = sf.FloatingSolid3D(solid, "bolts", 6, interfaces={"load": "load"})
scene = sf.Scene([bracket], constraints=[sf.Weld3D(bracket.point("frame"), name="bolted")],
                 forces=[sf.SpatialPointForce(bracket.point("load"), FORCE, name="pull")], name="bracket")
state = sf.static_equilibrium(scene)
load_point = bracket.point("load")
reduced = load_point.position(state.q) - load_point.position(bracket.q0)

# the full mesh: the bolts held, the load face tied rigidly to six DOFs, the force on its translation
T, n_free = solid.tie(solid.nodes("bolts"), [solid.nodes("load")])
rhs = np.zeros(T.shape[1])
rhs[n_free:n_free + 3] = FORCE
w = spla.spsolve((T.T @ solid.stiffness @ T).tocsc(), rhs)
full = w[n_free:n_free + 3]
von_mises = von_mises_3d(bracket.stresses(state.q))


def summary():
    return "\n".join([
        f"bracket from {MESH_FILE.name}: {mesh.t.shape[1]} tetrahedra, {solid.n_dofs} DOFs "
        f"(P{solid.order}); reduced to {bracket.n_elastic} coordinates",
        f"load face displacement under {FORCE[1]:g} N along y: reduced {reduced * 1e6} µm, full mesh "
        f"{full * 1e6} µm (largest difference {np.abs(reduced - full).max() / np.abs(full).max():.1e} of it)",
        f"largest von Mises stress {von_mises.max() / 1e6:.1f} MPa"])


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "output"
    sf.simulate(scene, 1e-3, 1e-3, start="static", output=VTKSeries(out, "bracket"))
    print(summary())
    print(f"wrote {out / 'bracket.pvd'}")
