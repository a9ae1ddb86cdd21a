"""Write ``conrod.msh``: a planar connecting rod with two holes, as a gmsh 2.2 file with physical groups.

No gmsh needed: points on the outer contour (the convex hull of the two eye circles), on the two
hole circles and on a grid inside are triangulated by Delaunay (scipy); triangles whose centroid
lies in a hole are dropped. The hole boundaries are written as line elements in the physical
groups ``big_end`` and ``small_end`` (the interface candidates), the contour as ``outline`` and the
triangles as ``rod``. Units: m. Big-end hole centre at (0, 0), small-end hole centre at (L, 0).

    python examples/meshes/make_conrod.py [--size 0.003] [--out examples/meshes/conrod.msh]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import meshio
import numpy as np
from scipy.spatial import Delaunay, cKDTree

#: centre distance, hole radii and eye radii (m)
LENGTH, BIG_HOLE, SMALL_HOLE, BIG_EYE, SMALL_EYE = 0.30, 0.012, 0.007, 0.024, 0.015


def _circle(centre, radius, size):
    n = max(12, int(np.ceil(2 * np.pi * radius / size)))
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def _outline(size):
    """Points along the convex hull of the two eye circles (arcs and tangent lines), counter-clockwise."""
    d, r1, r2 = LENGTH, BIG_EYE, SMALL_EYE
    beta = np.arcsin((r1 - r2) / d)                      # tangent lines meet the circles at ±(π/2 + β)
    a1 = np.linspace(np.pi / 2 + beta, 3 * np.pi / 2 - beta, max(8, int(np.ceil(r1 * (np.pi - 2 * beta) / size))))
    a2 = np.linspace(-np.pi / 2 + beta, np.pi / 2 - beta, max(8, int(np.ceil(r2 * (np.pi + 2 * beta) / size))))
    big = np.column_stack([r1 * np.cos(a1), r1 * np.sin(a1)])
    small = np.column_stack([d + r2 * np.cos(a2), r2 * np.sin(a2)])
    lower = np.linspace(big[-1], small[0], int(np.ceil(np.linalg.norm(small[0] - big[-1]) / size)) + 1)[1:-1]
    upper = np.linspace(small[-1], big[0], int(np.ceil(np.linalg.norm(big[0] - small[-1]) / size)) + 1)[1:-1]
    return np.vstack([big, lower, small, upper])


def _inside(p, size):
    """Inside the rod and at least 0.7 size away from the contour and the holes."""
    dense = _outline(size / 4)
    in_hull = Delaunay(dense).find_simplex(p) >= 0
    far_edge = cKDTree(dense).query(p)[0] > 0.7 * size
    x, y = p[:, 0], p[:, 1]
    far_holes = (np.hypot(x, y) > BIG_HOLE + 0.7 * size) & (np.hypot(x - LENGTH, y) > SMALL_HOLE + 0.7 * size)
    return in_hull & far_edge & far_holes


def make(size=0.003):
    """(points (n, 2), triangles (m, 3), line groups {name: (edges (k, 2))})."""
    outline = _outline(size)
    big, small = _circle((0.0, 0.0), BIG_HOLE, size), _circle((LENGTH, 0.0), SMALL_HOLE, size)
    hx = np.arange(-BIG_EYE, LENGTH + SMALL_EYE + size, size)
    hy = np.arange(-BIG_EYE, BIG_EYE + size, size * np.sqrt(3) / 2)
    gx, gy = np.meshgrid(hx, hy)
    gx = gx + (np.arange(hy.size)[:, None] % 2) * size / 2           # staggered rows: near-equilateral triangles
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    grid = grid[_inside(grid, size)]
    pts = np.vstack([outline, big, small, grid])
    tri = Delaunay(pts).simplices
    c = pts[tri].mean(axis=1)
    keep = (np.hypot(c[:, 0], c[:, 1]) > BIG_HOLE) & (np.hypot(c[:, 0] - LENGTH, c[:, 1]) > SMALL_HOLE)
    tri = tri[keep]
    # counter-clockwise orientation
    a, b, cc = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (cc[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (cc[:, 0] - a[:, 0]) < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    n0, n1 = outline.shape[0], outline.shape[0] + big.shape[0]

    def ring(start, count):
        i = np.arange(count)
        return np.column_stack([start + i, start + (i + 1) % count])
    groups = {"outline": ring(0, n0), "big_end": ring(n0, big.shape[0]), "small_end": ring(n1, small.shape[0])}
    return pts, tri, groups


def write(path, size=0.003):
    """Write the rod mesh to ``path`` (gmsh 2.2 ASCII) and return it as a meshio.Mesh."""
    pts, tri, groups = make(size)
    tags = {"rod": (1, 2), "outline": (2, 1), "big_end": (3, 1), "small_end": (4, 1)}
    cells = [("triangle", tri)] + [("line", groups[k]) for k in ("outline", "big_end", "small_end")]
    phys = [np.full(len(tri), 1)] + [np.full(len(groups[k]), tags[k][0]) for k in ("outline", "big_end", "small_end")]
    mesh = meshio.Mesh(np.column_stack([pts, np.zeros(len(pts))]), cells,
                       cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                       field_data={k: np.array(v) for k, v in tags.items()})
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)
    return mesh


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=float, default=0.003, help="target element size, m")
    ap.add_argument("--out", default=str(Path(__file__).with_name("conrod.msh")))
    args = ap.parse_args(argv)
    m = write(args.out, args.size)
    print(f"wrote {args.out}: {len(m.points)} nodes, {len(m.cells[0].data)} triangles")


if __name__ == "__main__":
    main()
