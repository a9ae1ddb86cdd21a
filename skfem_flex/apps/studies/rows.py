"""A study's rows: its cases run as the cases of a sweep (:func:`study_rows`, :class:`StudyRows`), the
warm-up that keeps the compile out of their timings (:func:`compiled_first`), and the table written as
CSV and Markdown (:func:`write_table`)."""
from __future__ import annotations

import csv
from dataclasses import asdict
from pathlib import Path

from ...run.simulate import simulate

__all__ = ["StudyRows", "study_rows", "compiled_first", "write_table", "SCHEMES"]

#: the schemes a study compares by default
SCHEMES = ("energy-momentum", "trapezoidal", "generalized-alpha")


class StudyRows(list):
    """A study's rows (a list, in the order of its cases) with the counts of the sweep that made them.

    Attributes
    ----------
    computed : int
        Runs made now.
    skipped : int
        Runs read back from the store (``resume=True``), timings included.
    """

    computed = 0
    skipped = 0


def study_rows(specs, row, store, client, resume, n_workers):
    """Run a study's cases as a sweep; ``row(spec, case Dataset)`` makes each table row (in plan order)."""
    from ..sweep import run_cases

    rows = {}
    ds = run_cases(specs, store=store, client=client, resume=resume, n_workers=n_workers,
                   on_case=lambda s, c: rows.update({s.index: row(s, c)}))
    out = StudyRows(rows[s.index] for s in specs)
    out.computed, out.skipped = int(ds.attrs["computed"]), int(ds.attrs["skipped"])
    return out


#: (scene factory, schemes) already run once in this process by :func:`compiled_first`
_WARMED = set()


def compiled_first(factory, dt, schemes):
    """``factory`` that, the first time in a process, runs one step of its scene under every scheme, so
    that the kernels are compiled (cold Numba cache) or loaded from the cache (about 0.05 s per loop)
    before the case starts: the sweep builds the scene before it starts a case's wall-clock budget and
    run time, so neither counts against the first step size's run."""
    def build(**params):
        scene = factory(**params)
        key = (getattr(factory, "__qualname__", repr(factory)), tuple(schemes), tuple(sorted(params.items())))
        if key not in _WARMED:
            _WARMED.add(key)
            for scheme in schemes:
                try:
                    simulate(factory(**params), dt, dt, integrator=scheme, handle_signals=False)
                except Exception:        # only a warm-up: the case itself reports any failure
                    pass
        return scene
    return build


def write_table(rows, stem):
    """Write rows (dataclasses) as ``stem.csv`` and ``stem.md``; returns the two paths."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    dicts = [asdict(r) for r in rows]
    cols = list(dicts[0]) if dicts else []
    with open(stem.with_suffix(".csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(dicts)

    def fmt(v):
        if isinstance(v, float):
            return f"{v:.3g}"
        return str(v).replace("|", "/").replace("\n", " ")
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(fmt(d[c]) for c in cols) + " |" for d in dicts]
    stem.with_suffix(".md").write_text("\n".join(lines) + "\n")
    return stem.with_suffix(".csv"), stem.with_suffix(".md")
