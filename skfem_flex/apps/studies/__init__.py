"""Studies: error against run time (work–precision) and stability on stiff and extreme cases.

Both studies run catalogue scenes through :func:`~skfem_flex.run.simulate.simulate`
as the cases of a sweep (:mod:`skfem_flex.apps.sweep`: in this process by default,
on a Dask cluster with ``client=``, resumable with ``store=``), catch every
failure (a failed run is a row with its message and the time it happened,
never a crash) and return plain tables that the command line writes as
Markdown, CSV and PNG.

With exudyn installed (:func:`skfem_flex.apps.peer.peer_available`), the work–precision
study also runs the peer code's model of the flexible pendulum and the spin-up
(:mod:`skfem_flex.apps.peer`) at the same steps and measures its error in the same way
against the same reference (rows with scheme :data:`PEER_SCHEME`).

The package's rooms: :mod:`~skfem_flex.apps.studies.references` (exact periods and motions, the error
functions), :mod:`~skfem_flex.apps.studies.work_precision_study`,
:mod:`~skfem_flex.apps.studies.stability_study` and :mod:`~skfem_flex.apps.studies.rows` (running a
study's cases as a sweep, writing its table).
"""
from __future__ import annotations

from .references import (history_error, oscillator_period, pendulum_period, pendulum_position, period_error,
                         upward_crossings)
from .rows import SCHEMES, StudyRows, write_table
from .stability_study import (QUICK_BUDGET, QUICK_STEPS, STABILITY_CASES, StabilityCase, StabilityRow, plot_stability,
                              stability)
from .work_precision_study import (PEER_SCHEME, WORK_PRECISION_CASES, WorkPrecisionCase, WorkPrecisionRow,
                                   plot_work_precision, work_precision)

__all__ = ["WorkPrecisionRow", "StabilityRow", "StudyRows", "work_precision", "stability", "write_table",
           "plot_work_precision", "plot_stability", "WORK_PRECISION_CASES", "STABILITY_CASES", "oscillator_period",
           "pendulum_period", "upward_crossings", "period_error", "history_error", "PEER_SCHEME", "pendulum_position",
           "WorkPrecisionCase", "StabilityCase", "QUICK_STEPS", "QUICK_BUDGET", "SCHEMES"]
