r"""Statics and linearized modes of any scene; Campbell diagrams (the analysis layer).

Beside the time loop, on the same scene assembly (docs/linearization.md):

:func:`static_equilibrium`
    The nonlinear equilibrium of a scene,

    .. math::  F(q) + Φ_q(q)ᵀ λ = 0, \qquad Φ(q, t) = 0,

    with F(q) = M(q) a_p − Q_v(q, v) + ∇V(q) − Q(q, v, t) the generalized force balance at
    rest (or at the steady velocities, ``steady=True``), found by path following from the
    start state: the homotopy H(x, s) = R(x) − (1 − s) R(x₀), x = (q_free, λ), runs the load
    factor s from 0 (the start, a solution by construction) to 1 (the scene's loads). From a
    stress-free start with loads that do not depend on q this is exactly proportional load
    stepping. The path is followed by pseudo-arc-length continuation with automatic step
    control (predictor along the tangent, Newton corrector on the hyperplane orthogonal to
    it, step halved on failure and doubled after quick convergence), so it passes turning
    points of the load; the last step lands on s = 1 by a Newton solve at fixed load.
:func:`linearize`
    Mass, damping/gyroscopic and stiffness matrices about any state (q, v, t) with
    multipliers λ and accelerations a, reduced to the independent coordinates by a sparse
    null-space basis of Φ_q (:func:`null_space_basis`).
:func:`modes`
    Eigenvalues s, frequencies, damping ratios and shapes of the linearized system about
    the static equilibrium, the steady motion, the initial state or any given state.
:func:`campbell`
    Modes of a scene against a parameter (spin rate, crank angle, ...).

See ``docs/linearization.md`` for the equations.

The rooms:

============================  ====================================================================
``statics.py``                :func:`static_equilibrium`, the entry point of statics
``balance.py``                :func:`force_balance`, the residual in the unknowns, :class:`EquilibriumState`
``load_path.py``              pseudo-arc-length continuation of the load path; settling from a singular start
``rest_state.py``             refusals of scenes that cannot be at rest (unheld, no steady state)
``start.py``                  the consistent accelerations and multipliers of a state
``linearization.py``          :func:`null_space_basis`, :class:`LinearSystem`, :func:`linearize`
``modal.py``                  :func:`modes`, :class:`Modes`, the eigensolvers
``mode_series.py``            :func:`write_mode_series` (VTK animations of modes)
``campbell_diagram.py``       :func:`campbell`, :class:`CampbellDiagram`
``matrix_tools.py``           small helpers for dense and sparse matrices alike
============================  ====================================================================
"""
from .balance import EquilibriumState, force_balance
from .campbell_diagram import CampbellDiagram, campbell
from .linearization import LinearSystem, linearize, null_space_basis
from .modal import ABOUT, Modes, modes
from .mode_series import write_mode_series
from .statics import static_equilibrium

__all__ = ["EquilibriumState", "LinearSystem", "Modes", "CampbellDiagram", "static_equilibrium", "linearize",
           "modes", "campbell", "null_space_basis", "write_mode_series", "force_balance", "ABOUT"]
