"""The ``skfem-flex`` command.

::

    skfem-flex run [SCENE] [--set key=value ...] [--t-end T] [--dt DT]
                   [--integrator NAME] [--rho-inf R] [--out DIR] [--every N]
                   [--no-vtk] [--no-plots] [--quiet]
    skfem-flex list
    skfem-flex study work-precision [CASE] [--schemes ...] [--quick] [--no-peer] [--out DIR]
                     [--workers N | --scheduler ADDRESS] [--store DIR] [--resume | --no-resume]
    skfem-flex study stability [--cases ...] [--schemes ...] [--quick] [--out DIR]
                     [--workers N | --scheduler ADDRESS] [--store DIR] [--resume | --no-resume]
    skfem-flex modes SCENE [--set key=value ...] [--n N] [--about static|steady|initial]
                     [--out DIR] [--frames F] [--no-vtk] [--quiet]
    skfem-flex campbell SCENE --vary NAME=VALUES [--set ...] [--n N] [--about ...] [--out DIR]
    skfem-flex sweep SCENE --vary KEY=VALUES [--vary ...] [--set key=value ...]
                     [--t-end T] [--dt DT] [--integrator NAME] [--workers N | --scheduler ADDRESS]
                     [--resume | --no-resume] [--format netcdf|zarr] [--probe NAME] [--out DIR]

``run`` builds a catalogue scene (default :data:`DEFAULT_SCENE`), integrates
it and writes into DIR (default ``results/SCENE``): the VTK time series
(``SCENE.pvd``, ``SCENE.vtu.series``, ``SCENE_NNNNNN.vtu``), ``summary.json``,
``result.npz`` (:meth:`skfem_flex.Result.load`), ``probes.csv`` and PNG plots.

``sweep`` runs a scene over a grid of parameters as Dask tasks
(:func:`skfem_flex.apps.sweep.sweep`) and writes into DIR (default
``results/sweep-SCENE``) the store ``sweep/`` (netCDF per case; ``sweep.zarr``
with ``--format zarr``), ``summary.csv``,
``sweep.json`` (counts of computed and skipped cases) and
``extremes_PROBE.png``; exit status 1 when a case did not complete.

``study`` runs its cases one after another in this process by default (their
wall times are what the work-precision study measures); ``--workers N`` or
``--scheduler ADDRESS`` spread them over a Dask cluster as ``sweep`` does, and
with ``--store DIR`` a rerun reads the runs already in that sweep store
instead of running them again (``--no-resume`` recomputes them).

Exit status: 0 on success; 2 on bad input (unknown scene or parameter, a
value of the wrong type, dt ≤ 0, an unwritable output directory, a run that
cannot fit in memory; one line on stderr, no traceback); 1 when the run stops
early (Newton failure) or an output cannot be written (disk full); 3 when the
run diverged ("diverged at t = …"); 130 after Ctrl-C and 143 after SIGTERM,
which finish the current step first. In every case the outputs up to the last
good step are kept (``result.npz``, ``probes.csv``, ``summary.json`` with
``"completed": false`` and ``"stopped"`` saying why). During the run the
histories are checkpointed every few seconds into ``checkpoint.npz``
(:meth:`skfem_flex.Result.load` reads it after a SIGKILL), and
``skfem-flex run --resume DIR`` continues an interrupted or killed run.

The parser is built from subcommands (:data:`SUBCOMMANDS`), one module per group of commands:
:mod:`~skfem_flex.apps.cli.run` (``run``, ``run --resume``; what a run reports in
:mod:`~skfem_flex.apps.cli.run_summary`), :mod:`~skfem_flex.apps.cli.catalogue` (``list``),
:mod:`~skfem_flex.apps.cli.modes` (``modes``, ``campbell``) and :mod:`~skfem_flex.apps.cli.sweeps`
(``sweep``, ``study``). Beside them: :mod:`~skfem_flex.apps.cli.errors` (one line on stderr and the
exit status for whatever goes wrong), :mod:`~skfem_flex.apps.cli.arguments` (the parser class and the
option types), :mod:`~skfem_flex.apps.cli.settings` (``--set``/``--vary`` text to scene parameters) and
:mod:`~skfem_flex.apps.cli.outputs` (the output directory, strict JSON).
"""
from __future__ import annotations

import signal
import sys

from .arguments import Parser
from .catalogue import add_list
from .errors import UsageError, exit_status, one_line_warning, raise_terminated
from .modes import add_campbell, add_modes
from .run import add_run
from .settings import DEFAULT_SCENE, convert_setting
from .sweeps import add_study, add_sweep

__all__ = ["main", "build_parser", "UsageError", "convert_setting", "DEFAULT_SCENE", "SUBCOMMANDS"]

#: functions adding one subcommand each to the subparsers
SUBCOMMANDS = [add_run, add_list, add_study, add_modes, add_campbell, add_sweep]


def build_parser():
    """The argparse parser of ``skfem-flex`` with one subparser per entry of :data:`SUBCOMMANDS`."""
    from ... import __version__

    parser = Parser(prog="skfem-flex",
                    description="Planar flexible multibody dynamics on scikit-fem: run catalogue scenes "
                                "and write VTK time series, plots and summaries.")
    parser.add_argument("--version", action="version", version=f"skfem-flex {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def _run_command(argv):
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    return args.func(args)


def main(argv=None):
    """Entry point of the ``skfem-flex`` console script; returns the exit status."""
    import threading
    import warnings

    old_term, old_show = None, warnings.showwarning
    if threading.current_thread() is threading.main_thread():
        old_term = signal.signal(signal.SIGTERM, raise_terminated)
    warnings.showwarning = one_line_warning
    try:
        return exit_status(lambda: _run_command(argv))
    finally:
        warnings.showwarning = old_show
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
