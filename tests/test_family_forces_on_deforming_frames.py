"""The force-element families on points of deforming frames: position maps r = R + A(θ)(y₀ + Y q_f) with
q_f ≠ ∅ (the terms of ∂(Dᵀf)/∂q_b, ∂(J_rᵀ f)/∂q and ∂(J_r v)/∂q over q_f that rigid bodies never reach).

A test body with coordinates (x, y, θ, q_f) and a constant mass matrix whose points follow that map (their
numpy methods written here from the map's formula: the exact discrete gradient from A(θ₁) − A(θ₀) =
sinc(Δθ/2) Δθ A(θ_m) E and (A₀ + A₁)/2 = cos(Δθ/2) A(θ_m), its derivative by complex steps) carries every
force element kind of the four families (two-point springs and dampers, point and follower forces, a
point moment, torsion springs and dampers, a coordinate spring on q_f):

1. the Newton matrix of the energy-momentum and trapezoidal steps equals 5-point central differences of
   the residual (1e-10 of its scale), and g_p and Q equal the elements' numpy contracts (1e-12);
2. runs of 100 steps equal the Python path (compiled=False) (q to 1e-10) under energy-momentum, trapezoidal and
   generalized-α, work included; energy-momentum keeps T + V − W to the Newton tolerance.
"""
import numpy as np
import pytest

import skfem_flex as sf
from skfem_flex.bodies.base import Body, BodyPoint
from force_family_checks import (compare_runs, derivative_check, evaluation_points, initial_energy, local,
                                 random_stepper,
                                 scatter)

_E = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s], [s, c]])


def _sinc(x):
    return 1.0 - x * x / 6.0 if abs(x) < 1e-6 else np.sin(x) / x


class DeformingFrame(Body):
    """A test body: frame (x, y, θ) and ``ne`` deformation coordinates q_f, constant mass diag(m, m, J, μ…)."""

    constant_mass = True

    def __init__(self, q0, v0, masses, name):
        self.q0, self.v0 = np.array(q0, dtype=float), np.array(v0, dtype=float)
        self.n_dofs = self.q0.size
        self._mass = np.diag(np.asarray(masses, dtype=float))
        self.name = name

    def mass_matrix(self, q):
        return self._mass

    def point(self, y0, Y):
        return FramePoint(self, y0, Y)


class FramePoint(BodyPoint):
    """r = R + A(θ)(y₀ + Y q_f), ϑ = θ."""

    has_angle = True

    def __init__(self, body, y0, Y):
        self.body = body
        self.y0 = np.asarray(y0, dtype=float)
        self.Y = np.asarray(Y, dtype=float).reshape(2, body.n_dofs - 3)

    def _s(self, q):
        return self.y0 + self.Y @ q[3:]

    def position(self, q):
        return q[:2] + _rot(q[2]) @ self._s(q)

    def position_jacobian(self, q):
        A = _rot(q[2])
        return np.hstack([np.eye(2), (A @ _E @ self._s(q))[:, None], A @ self.Y])

    def position_hessian_product(self, q, f):
        A = _rot(q[2])
        n = self.body.n_dofs
        h = np.zeros((n, n))
        h[2, 2] = -f @ A @ self._s(q)
        h[2, 3:] = h[3:, 2] = f @ A @ _E @ self.Y
        return h

    def position_discrete_gradient(self, q0, q1):
        d = q1[2] - q0[2]
        A = np.array([[np.cos(q0[2] + d / 2), -np.sin(q0[2] + d / 2)], [np.sin(q0[2] + d / 2), np.cos(q0[2] + d / 2)]])
        sm = self.y0 + self.Y @ (0.5 * (q0[3:] + q1[3:]))
        return np.hstack([np.eye(2), (_sinc(d / 2) * A @ _E @ sm)[:, None], np.cos(d / 2) * A @ self.Y])

    def position_discrete_gradient_jacobian(self, q0, q1, f):
        n, eps = self.body.n_dofs, 1e-30
        out = np.zeros((n, n))
        for j in range(n):                      # complex step: exact to round-off
            qc = np.asarray(q1, dtype=complex).copy()
            qc[j] += 1j * eps
            out[:, j] = (self.position_discrete_gradient(q0, qc).T @ f).imag / eps
        return out

    def compiled_map(self):
        return "frame", 1.0, self.y0, self.Y

    def angle(self, q):
        return float(q[2])

    def angle_jacobian(self, q):
        g = np.zeros(self.body.n_dofs)
        g[2] = 1.0
        return g


def deforming_frames(forces=True):
    """Two deforming frames (one and two q_f) with every force element kind between them and to the ground."""
    a = DeformingFrame([0.0, 0.0, 0.3, 0.1], [0.1, -0.2, 1.2, 0.5], [1.0, 1.0, 0.1, 0.05], "a")
    b = DeformingFrame([1.2, 0.3, -0.5, 0.05, -0.1], [0.2, 0.1, -0.8, -0.3, 0.4], [0.8, 0.8, 0.08, 0.04, 0.03], "b")
    pa = a.point((0.5, 0.0), [[0.4], [0.3]])
    pa2 = a.point((-0.3, 0.1), [[-0.2], [0.5]])
    pb = b.point((-0.3, 0.05), [[0.3, -0.1], [0.2, 0.6]])
    pb2 = b.point((0.2, -0.1), [[0.1, 0.4], [-0.3, 0.2]])
    elements = [sf.LinearSpring(pa, pb, 150.0, rest_length=0.3), sf.LinearSpring(pb2, (1.5, 1.0), 60.0),
                sf.LinearSpring(pa2, None, 20.0),
                sf.LinearDamper(pa, pb2, 2.0), sf.LinearDamper(pa2, (-0.5, 0.4), 1.0),
                sf.PointForce(pa2, lambda t: (2.0 * np.sin(3.0 * t), -1.0)),
                sf.PointForce(pb, lambda t: (-2.0, 5.0 * np.sin(3.0 * t)), follower=True),
                sf.PointMoment(pb2, lambda t: np.cos(2.0 * t)),
                sf.RotationalSpring(pb, pa, stiffness=5.0), sf.RotationalDamper(pa, None, damping=0.3),
                sf.NonlinearSpring(b, 40.0, exponent=2.0, coordinate=4)]
    return sf.Scene([a, b], forces=elements if forces else [], name="deforming frames")


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal"])
def test_newton_matrix_and_residual_parts_follow_the_specification(scheme):
    scene = deforming_frames()
    for seed in range(3):
        st = random_stepper(scene, scheme, seed)[0]
        x = 0.3 * np.random.default_rng(10 + seed).normal(size=st.packed.nx)
        h, t0 = 0.2, 0.3
        mat, err = derivative_check(st, t0, h, x)
        assert err <= 1e-10, err
        (qa, qb), (qe, ve, te) = evaluation_points(st, t0, h)
        gp = sum(scatter(scene, f, f.potential_discrete_gradient(local(scene, f, qa), local(scene, f, qb))[0])
                 for f, _ in scene.conservative_forces)
        ext = sum(scatter(scene, f, f.generalized_force(local(scene, f, qe), local(scene, f, ve), te)[0])
                  for f, _ in scene.loads)
        assert np.abs(st.ws.vectors["gp"] - gp).max() <= 1e-12 * np.abs(gp).max()
        assert np.abs(st.ws.vectors["ext"] - ext).max() <= 1e-12 * np.abs(ext).max()
        mat0 = random_stepper(deforming_frames(forces=False), scheme, seed)[0].evaluate(t0, h, x)[1]
        assert np.abs(mat - mat0).max() >= 0.05 * np.abs(mat).max()


@pytest.mark.parametrize("scheme", ["energy-momentum", "trapezoidal", "generalized-alpha"])
def test_runs_equal_the_python_path(scheme):
    new, old, dq = compare_runs(deforming_frames, scheme, 0.5, 0.005)
    assert dq <= 1e-10, dq
    e_scale = np.abs(old.total_energy).max() + np.abs(old.external_work).max()
    assert np.abs(new.work - old.external_work[1:]).max() <= 1e-10 * e_scale
    assert np.abs(new.derived[:, 1] - old.potential[1:]).max() <= 1e-10 * e_scale
    if scheme == "energy-momentum":
        energy = new.derived[:, 0] + new.derived[:, 1] - new.work
        assert np.abs(energy - initial_energy(deforming_frames())).max() <= 1e-8 * e_scale
