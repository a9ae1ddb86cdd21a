"""Time and memory of reducing a meshed 3D solid, from 10³ to 10⁵ nodes.

A steel bar (10 × 1 × 1 in units of its width, P1 tetrahedra from a hexahedral grid) is assembled with
scikit-fem (:class:`skfem_flex.ElasticSolid3D`) and reduced (:class:`skfem_flex.FloatingSolid3D`: the frame
clamped at one end, a rigid interface at the other, 8 fixed-interface modes and the interface's 6 constraint
modes: Craig–Bampton with one sparse factorization, ``eigsh`` in shift-invert mode on it, the invariants by
sparse products). Each size runs in a fresh process, which reports its wall time per stage, the
factorization it used (:mod:`skfem_flex.fem.spd_solver`: SuperLU, or PARDISO from the optional
``pypardiso`` above 20 000 rows) and its peak resident memory (``ru_maxrss``) above the memory of the
imports. The table goes to standard output and, with a folder argument, to ``reduction_scaling.md`` there::

    python examples/reduction_scaling.py                        # 10³ … 10⁵ nodes (10⁵ only with pypardiso)
    python examples/reduction_scaling.py docs/study             # the same, written as a table for the docs
    python examples/reduction_scaling.py /tmp/out 3000 10000    # other sizes (nodes)

SuperLU's factorization of a 3D stiffness grows as about N^1.6 in time (10⁵ nodes: many minutes and more
than 7 GB), so the default run leaves 10⁵ nodes out without PARDISO. ``SKFEM_FLEX_EXAMPLE_QUICK=1`` runs
10³ and 3·10³ nodes only.
"""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

QUICK = os.environ.get("SKFEM_FLEX_EXAMPLE_QUICK") == "1"
SIZES = (1_000, 3_000) if QUICK else (1_000, 3_000, 10_000, 30_000, 110_000)


def grid(nodes):
    """(nx, ny) of a 10:1:1 grid of about ``nodes`` nodes: nx·ny² nodes with nx − 1 = 10 (ny − 1)."""
    ny = 2
    while (10 * (ny) + 1) * (ny + 1) ** 2 <= nodes:
        ny += 1
    return 10 * (ny - 1) + 1, ny


def measure(nodes):
    """One size, in this process: the stages' wall times (s) and the peak memory above the imports (MB)."""
    import resource

    import numpy as np
    import skfem

    import skfem_flex as sf
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    nx, ny = grid(nodes)
    width = 0.1
    t0 = time.perf_counter()
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 10 * width, nx), np.linspace(0, width, ny),
                                     np.linspace(0, width, ny)).to_meshtet()
    solid = sf.ElasticSolid3D(mesh, 2.1e11, 0.3, 7850.0, order=1)
    t1 = time.perf_counter()
    body = sf.FloatingSolid3D(solid, lambda X: np.isclose(X[0], 0.0), 8,
                              interfaces={"tip": lambda X: np.isclose(X[0], 10 * width)})
    t2 = time.perf_counter()
    return dict(nodes=int(mesh.p.shape[1]), dofs=int(solid.n_dofs), assemble=t1 - t0, reduce=t2 - t1,
                factor=body.factorization,
                memory=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 - base,
                f1=float(body.frequencies[0]))


def main(out=None, sizes=SIZES):
    rows = []
    from skfem_flex.fem.spd_solver import pardiso_available
    if sizes == SIZES and not pardiso_available():
        sizes = tuple(n for n in sizes if n < 50_000)
        print("pypardiso is not installed: 10⁵ nodes left out (SuperLU would need many minutes and > 7 GB)")
    for nodes in sizes:
        proc = subprocess.run([sys.executable, __file__, "--one", str(nodes)], capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"the run of {nodes} nodes failed:\n{proc.stderr[-3000:]}")
        rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        r = rows[-1]
        print(f"{r['nodes']:>8} nodes: assembly {r['assemble']:.2f} s, reduction {r['reduce']:.2f} s ({r['factor']}), "
              f"peak memory {r['memory']:.0f} MB, first frequency {r['f1']:.1f} rad/s", flush=True)
    lines = ["| nodes | DOFs | assembly (s) | reduction (s) | factorization | peak memory above imports (MB) | "
             "µs per DOF (both) | first bending frequency (rad/s) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['nodes']} | {r['dofs']} | {r['assemble']:.2f} | {r['reduce']:.2f} | {r['factor']} | "
                     f"{r['memory']:.0f} | "
                     f"{1e6 * (r['assemble'] + r['reduce']) / r['dofs']:.0f} | {r['f1']:.2f} |")
    text = "\n".join(lines)
    print(text)
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / "reduction_scaling.md").write_text(text + "\n")
    return rows


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--one":
        print(json.dumps(measure(int(sys.argv[2]))))
    else:
        main(sys.argv[1] if len(sys.argv) > 1 else None, tuple(int(a) for a in sys.argv[2:]) or SIZES)
