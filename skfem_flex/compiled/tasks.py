r"""What the loop asks of a kernel, and the weights that make one set of element kernels serve every scheme.

A kernel reads ``ctx.task`` and does its part of that task; a family with nothing to do for a task
returns at once.

``TASK_EVAL`` — the step's residual and Newton matrix. The unknowns x are the free coordinates'
increments Δq and the multipliers μ; a kernel adds its terms into the context's residual parts and
its derivatives into the Newton matrix, weighted by the context's coefficients, so that the scheme's
residual is

.. math::

    r = w_p\,p + w_{gk}\,g_k + w_{gp}\,g_p + w_{ext}\,Q + D^\mathsf{T}\mu
        \;(+\ \text{the scheme's own constant-mass inertia}),\qquad
    c = \text{the constraint rows}

with the parts each element kind supplies:

=================  ==========================================  ========================================
kind               residual part                               derivative added to the Newton matrix
=================  ==========================================  ========================================
inertia (bodies    energy-momentum: p ← p(q₁, v₁),             w_p (∂p/∂q₁ dq1 + ∂p/∂v₁ dv1)
with M(q))         g_k ← D_G(q₀, q₁; v₀, v₁)                   + w_gk (∂g_k/∂q₁ dq1 + ∂g_k/∂v₁ dv1)
                   Newmark: p ← M(q₁) a₁, g_k ← Q_v(q₁, v₁)    w_p (∂(M a)/∂q dq1 + M da1)
                                                               + w_gk (∂Q_v/∂q dq1 + ∂Q_v/∂v dv1)
potential          g_p ← D_V(q_a, q_b)                         w_gp c_dg ∂D_V/∂q_b dq1
loads, dampers     Q ← Q(q_e, v_e, t)                          w_ext (∂Q/∂q dqe + ∂Q/∂v dve)
constraints        Dᵀμ ← D(q_a, q_b)ᵀ μ,                       w_mu c_dg ∂(Dᵀμ)/∂q_b dq1;
                   rows (ctx.rows): Φ(q₁, t₁) | (Φ_q v₁ +       border: w_mu D (column of μ) and the
                   Φ_t)/c_v | Φ_q a₁ + ∂(Φ_q v₁)/∂q v₁ + Φ_tt   row derivative (below)
=================  ==========================================  ========================================

with dq1 = ∂q₁/∂x, dv1 = ∂v₁/∂x (a vector: per coordinate), da1 = ∂a₁/∂x, dqe, dve the same for the
point where loads are evaluated. The energy-momentum scheme sets q_a, q_b = q₀, q₁ and c_dg = 1; the
Newmark schemes and statics set q_a = q_b = q₁ and c_dg = 2, since a discrete gradient at equal end
points is the gradient and its derivative there half the Hessian (one code for both). The row
derivatives: Φ_q dq1 (position rows), (∂(Φ_q v₁)/∂q dq1 + Φ_q dv1)/c_v (velocity rows), Φ_q da1
(acceleration rows). Each constraint row also reports its scale Σ|Φ_q||q₁| (``rscale``), D·(q_b − q_a)
(``ddphi``, the work of its force) and Φ_t (``phit``).

``TASK_EVAL_LOADS`` — the loads and dampers' part of TASK_EVAL, asked for separately after the others
(the energy-momentum step scales the rows of Cayley coordinates between the two).

``TASK_MOMENTUM`` — at (q₁, v₁): bodies whose mass matrix depends on q add p = M(q) v into ``ctx.p``
(the loop has already put the constant-mass part there); every body adds its linear and angular
momentum about the origin into ``out[1:4]`` and ``out[4:7]`` (planar bodies: (p_x, p_y, 0) and
(0, 0, L)).

``TASK_ENERGY`` — potential energy V(q₁) into ``out[0]``.

``TASK_ROWS`` — constraint rows at (q₁, v₁, t₁): Φ into ``ctx.phi``, Φ_t into ``ctx.phit`` and
Φ_q v₁ + Φ_t into ``ctx.ddphi``.

``TASK_LOADS`` — only the loads and dampers: Q(q_e, v_e, t) into ``ctx.ext`` (no matrix).
"""
from __future__ import annotations

__all__ = ["TASK_EVAL_LOADS", "STATUS_MISSED", "TASK_EVAL", "TASK_MOMENTUM", "TASK_ENERGY", "TASK_ROWS", "TASK_LOADS", "SCHEME_EM", "SCHEME_NEWMARK",
           "SCHEME_STATIC", "ROWS_POSITION", "ROWS_VELOCITY", "ROWS_ACCELERATION", "STATUS_OK", "STATUS_REFUSED",
           "STATUS_PYTHON_ERROR", "REFUSAL_NONE", "REFUSAL_TURN", "REFUSAL_NOT_FINITE", "REFUSAL_ENERGY", "PHASE_PREDICT", "PHASE_EVALUATE", "PHASE_ACCEPT", "PHASE_START"]

TASK_EVAL, TASK_MOMENTUM, TASK_ENERGY, TASK_ROWS, TASK_LOADS, TASK_EVAL_LOADS = 0, 1, 2, 3, 4, 5
SCHEME_EM, SCHEME_NEWMARK, SCHEME_STATIC = 0, 1, 2
ROWS_POSITION, ROWS_VELOCITY, ROWS_ACCELERATION = 0, 1, 2
#: ctx.status: an element refused the state (a folded element, a turn of π or more in a step), a Python
#: element raised, or a kernel wrote outside the Newton matrix's pattern; the step is abandoned and
#: handled in Python
STATUS_OK, STATUS_REFUSED, STATUS_PYTHON_ERROR, STATUS_MISSED = 0, 1, 2, 3
#: ctx.refusal: why a scheme refused a converged step itself (STATUS_REFUSED with ``bad_family`` < 0):
#: a free angle turned by MAX_INCREMENT or more, a state that is not finite, an energy jump (.acceptance)
REFUSAL_NONE, REFUSAL_TURN, REFUSAL_NOT_FINITE, REFUSAL_ENERGY = 0, 1, 2, 3
#: phases of a scheme's kernel (ctx.phase)
PHASE_PREDICT, PHASE_EVALUATE, PHASE_ACCEPT, PHASE_START = 0, 1, 2, 3
