"""The compiled floating-frame kernels on a ModalBody, and the compiled loop on a reduced body.

A ModalBody's own methods stay in numpy (FloatingFrame's kinetic algebra, QuarticEnergy's discrete
gradient): they are the reference. The compiled kernels (bodies/floating/kernel.py with the quartic
energy of bodies/modal/kernel.py), which the floating-frame family runs for this body, must agree with
them to round-off; the compiled run must then be the run through the body's Python methods.
"""
import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies import PlaneStress
from skfem_flex.bodies.floating import kernel as fk
from skfem_flex.bodies.floating.body import FloatingBeam
from skfem_flex.bodies.modal.body import ModalBody
from skfem_flex.bodies.modal.kernel import pack_quartic, quartic_discrete_gradient, quartic_energy
from skfem_flex.bodies.modal.stiffening import QuarticEnergy

from helpers import (SPIN_UP_SECTION as SEC, assert_loop_measures_are_the_scenes, assert_same_run, contract_terms,
                     dense, random_floating_states, relerr)


def spin_up_modal(**kw):
    return sf.scenes.spin_up_beam(body="beam-modal", **kw)


def free_flying_modal(strain="green-lagrange"):
    """A reduced beam in free flight (two interfaces, frame at the root): energy and momenta are constant."""
    beam = sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, 10.0, 7)), sf.Section(**SEC))
    full = FloatingBeam(beam, reference="clamped", strain=strain, velocity=(1.0, -0.5), angular_velocity=0.8)
    body = full.reduced(3, strain=strain)
    body.v0[3:] = 0.05 * np.arange(1, body.n_elastic + 1) / body.n_elastic
    return sf.Scene([body], name="free flight, reduced")


_BODIES = {}


def body_of(kind):
    """ModalBodies of both strain measures and of two models (beam, plane stress), built once."""
    if kind not in _BODIES:
        if kind == "beam-gl":
            b = spin_up_modal().bodies[0]
        elif kind == "beam-linear":
            b = spin_up_modal(strain="linear").bodies[0]
        elif kind == "plane-stress-gl":
            b = sf.scenes.slider_crank(body="plane-stress-modal", n_elements=16, n_across=2).bodies[1]
        else:                  # a plate whose frame origin is a corner (S_0 has both components)
            mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3))
            ps = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01, order=2 if kind == "plate-gl" else 1)
            b = ps.reduced(4) if kind == "plate-gl" else ps.body()
            assert abs(b._S0[1]) > 0.1 * abs(b._S0[0]) > 0
        _BODIES[kind] = b
    return _BODIES[kind]


KINDS = ["beam-gl", "beam-linear", "plane-stress-gl", "plate-gl", "plate-full-linear"]


def elastic_scale(body, frac):
    """Size of η whose displacements Φη are about ``frac`` × the body's size."""
    return frac * np.abs(body.model.position).max() / np.abs(body.Phi).max()


@pytest.mark.parametrize("kind", KINDS)
def test_energy_momentum_kernel_equals_the_contract_methods(kind):
    body = body_of(kind)
    kd = body.compiled_kernel_data()
    assert kd is body.compiled_kernel_data()                          # packed once
    assert kd.quartic == (not body.energy.linear)
    n = body.n_dofs
    rng = np.random.default_rng(3)
    for frac in (1e-3, 0.1):                                         # the quartic terms small and large
        scale = elastic_scale(body, frac)
        for dt in (1e-3, 2e-2):
            q0, q1, v0, v1 = random_floating_states(body, rng, scale, 0.1 * scale)
            p, gk, gp, data, floor = fk.energy_momentum_terms(kd, q0, q1, v0, v1, dt)
            got = (p, gk, gp, data.reshape(n, n), floor)
            fused = body.energy_momentum_terms(q0, q1, v0, v1, dt)       # the Python path's call (numpy)
            ref = contract_terms(body, q0, q1, v0, v1, dt)
            for name, a, b, c in zip(("p1", "g_kin", "g_pot", "jac", "floor"), got, fused, ref):
                assert relerr(a, b) < 1e-12, (name, relerr(a, b))
                assert relerr(a, c) < 1e-12, (name, relerr(a, c))


@pytest.mark.parametrize("kind", KINDS)
def test_momentum_and_strain_energy_kernels_equal_the_contract_methods(kind):
    body = body_of(kind)
    kd = body.compiled_kernel_data()
    rng = np.random.default_rng(5)
    for frac in (1e-3, 0.1):
        scale = elastic_scale(body, frac)
        q, _, v, _ = random_floating_states(body, rng, scale, 0.1 * scale)
        assert relerr(fk.momentum(kd, q, v), dense(body.mass_matrix(q)) @ v) < 1e-12
        assert fk.potential_energy(kd, q) == pytest.approx(body.potential_energy(q), rel=1e-12)


def random_quartic(m, rng):
    """A QuarticEnergy with tensors of the symmetries it promises (K3 in (j, k); K4 in (i, j), (k, l), (ij) ↔ (kl))."""
    K3 = rng.normal(size=(m, m, m))
    K3 = 0.5 * (K3 + K3.transpose(0, 2, 1))
    K4 = rng.normal(size=(m, m, m, m))
    K4 = 0.5 * (K4 + K4.transpose(1, 0, 2, 3))
    K4 = 0.5 * (K4 + K4.transpose(0, 1, 3, 2))
    K4 = 0.5 * (K4 + K4.transpose(2, 3, 0, 1))
    return QuarticEnergy(np.zeros((m, m)), K3, K4)           # K = 0: only the terms of the kernels


@pytest.mark.parametrize("m", [1, 2, 7])
def test_quartic_kernels_equal_quartic_energy(m):
    """The cubic and quartic terms alone (K = 0), on tensors unrelated to any model."""
    rng = np.random.default_rng(m)
    energy = random_quartic(m, rng)
    packed = pack_quartic(energy.K3, energy.K4)
    for _ in range(4):
        q0, q1 = rng.normal(size=m + 3), rng.normal(size=m + 3)
        assert quartic_energy(packed[0], packed[4], q1, 3) == pytest.approx(energy.energy(q1[3:]), rel=1e-12)
        g, dg = quartic_discrete_gradient(*packed, q0, q1, 3)
        g_ref, dg_ref = energy.discrete_gradient(q0[3:], q1[3:])
        assert relerr(g, g_ref) < 1e-12 and relerr(dg, dg_ref) < 1e-12
        # and the discrete gradient is exact: g · (η1 − η0) = V(η1) − V(η0)
        dv = energy.energy(q1[3:]) - energy.energy(q0[3:])
        assert float(g @ (q1[3:] - q0[3:])) == pytest.approx(dv, rel=1e-11, abs=1e-12 * np.abs(g).max())


def test_reduced_bodies_run_in_the_floating_frame_family():
    """Reduced bodies, with or without joints and under every scheme, run compiled (no Python element)."""
    scene = spin_up_modal()
    assert isinstance(scene.bodies[0], ModalBody) and scene.bodies[0].n_elastic <= 10
    for make, scheme in [(spin_up_modal, "energy-momentum"), (spin_up_modal, "trapezoidal"),
                         (lambda: sf.scenes.slider_crank(body="beam-modal"), "energy-momentum")]:
        res = sf.simulate(make(), t_end=2e-3, dt=1e-3, scheme=scheme)
        assert res.run_path["python_elements"] == [], (scheme, res.run_path)
    beam = sf.scenes.spin_up_beam(n_elements=4).bodies[0]
    assert beam.compiled_kernel_data() is beam.compiled_kernel_data()


#: compiled run against Python run (free flight: q agrees to 2e-13, v to 1e-10 after 200 steps)
# (energies, momenta and the hub torque to 2e-8: the two paths' Newton iterations stop one apart at some
# steps (a residual within round-off of the threshold), so the torque, the most sensitive output, agrees to
# the Newton tolerance (measured 1.7e-8 at Δt = 1e-3); and p = M(q) v is summed in the kernel, its terms
# cancelling (Σ|M_ij v_j| ~ 10 |p| about the pinned hub), in another order than the numpy method's)
SAME_RUN_TOL = dict(q_tol=1e-10, v_tol=1e-8, e_tol=2e-8)


def energy_balance(res):
    """max |E − E0 − W| relative to the energy scale of the run."""
    e = res.total_energy - res.total_energy[0] - res.external_work
    return np.abs(e).max() / (np.abs(res.total_energy).max() + np.abs(res.external_work).max())


@pytest.mark.parametrize("dt", [1e-3, 2e-2])
def test_reduced_spin_up_compiled_equals_python(dt):
    runs = [sf.simulate(spin_up_modal(), t_end=300 * dt, dt=dt, compiled=c) for c in (True, False)]
    assert_same_run(*runs, **SAME_RUN_TOL)
    assert energy_balance(runs[0]) <= 1e-9
    assert runs[0].potential.max() > 0 and np.abs(runs[0].probes["tip"]).max() > 1e-4   # it deforms


def test_reduced_linear_spin_up_compiled_equals_python():
    runs = [sf.simulate(spin_up_modal(strain="linear"), t_end=2.0, dt=1e-2, record_every=7, compiled=c)
            for c in (True, False)]
    assert_same_run(*runs, **SAME_RUN_TOL)
    assert runs[0].t[-1] == pytest.approx(2.0) and runs[0].t.size == 1 + 200 // 7 + 1


def free_spinning_plate():
    """A reduced plate spinning in free flight, its frame origin at a corner (S_0 has both components)."""
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3))
    body = PlaneStress(mesh, 2e9, 0.3, 1000.0, thickness=0.01, order=2).reduced(
        4, position=(0.1, 0.2), angle=0.3, velocity=(1.0, -0.5), angular_velocity=20.0)
    body.v0[3] = 0.2 * np.abs(body.v0).max()
    return sf.Scene([body], name="spinning plate, reduced")


@pytest.mark.parametrize("make, t_end, dt", [(free_flying_modal, 1.0, 5e-3), (free_spinning_plate, 0.02, 2e-4)])
def test_reduced_free_flight_compiled_equals_python_and_conserves(make, t_end, dt):
    runs = [sf.simulate(make(), t_end=t_end, dt=dt, compiled=c) for c in (True, False)]
    assert_same_run(*runs, **SAME_RUN_TOL)
    a = runs[0]
    assert energy_balance(a) <= 1e-9
    assert np.abs(a.total_energy - a.total_energy[0]).max() <= 1e-9 * a.total_energy[0]
    assert np.abs(a.linear_momentum - a.linear_momentum[0]).max() <= 1e-10 * np.abs(a.linear_momentum[0]).max()
    # angular momentum: O(Δt²) only for floating frames (docs/flexible_bodies.md), not checked here


def test_long_reduced_spin_up_energy_balance():
    """The benchmark's case (5 s at Δt = 1e-3 after the spin-up started) keeps its energy balance."""
    res = sf.simulate(spin_up_modal(omega=4.0), t_end=3.0, dt=1e-3, record_every=10)
    assert energy_balance(res) <= 1e-9
    assert res.external_work[-1] > 0


def test_energies_and_momenta_computed_in_the_loop_equal_the_scene_methods():
    assert_loop_measures_are_the_scenes(free_flying_modal(), rel=1e-12)
