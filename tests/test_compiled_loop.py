"""The compiled kernels of a floating beam against the same beam through its Python methods.

Both run in the one compiled loop (:mod:`skfem_flex.compiled.loop`): ``compiled=False`` sends every element
through its numpy methods (the ``python_elements`` family), the default through its compiled family. Both run the same scheme with the same Newton rules; the trajectories must agree to round-off
amplified by the Newton tolerance. Per-step Newton counts may differ by one where a scaled
residual lands within round-off of a convergence threshold (steps decided at the round-off
floor, e.g. the start from rest), so the totals are compared.
"""
import numpy as np
import pytest
import skfem

import skfem_flex as sf
from skfem_flex.bodies.floating.body import FloatingBeam
from skfem_flex.errors import ConvergenceError
from skfem_flex.schemes import NewtonSettings

from helpers import SPIN_UP_SECTION as SEC, assert_loop_measures_are_the_scenes, assert_same_run


def free_flying_beam(reference="pinned", n_elements=6):
    """A floating beam in free flight (no prescribed coordinate, no force): energy and momenta are constant."""
    beam = sf.TimoshenkoBeam(skfem.MeshLine(np.linspace(0.0, 10.0, n_elements + 1)), sf.Section(**SEC))
    body = FloatingBeam(beam, reference=reference, velocity=(1.0, -0.5), angular_velocity=0.8)
    body.v0[3:] = body.elastic_vector(w=lambda x: 0.02 * np.sin(np.pi * x / 10.0))
    return sf.Scene([body], name="free flight")


def test_run_path_names_the_code_that_ran():
    """``result.run_path`` says which loop, storage and solver ran and which elements went through Python."""
    fast = sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=0.02, dt=1e-2)
    assert fast.run_path["loop"] == "compiled" and fast.run_path["python_elements"] == []
    assert fast.run_path["storage"] == "dense" and fast.run_path["solver"] == "dense"
    slow = sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=0.02, dt=1e-2, compiled=False)
    assert len(slow.run_path["python_elements"]) == 1 and "FloatingBeam" in slow.run_path["python_elements"][0]
    big = sf.simulate(sf.scenes.spin_up_beam(n_elements=64), t_end=0.004, dt=2e-3)
    assert big.run_path["solver"].startswith("bordered band")


@pytest.mark.parametrize("dt", [1e-3, 2e-2])
def test_spin_up_compiled_equals_python(dt):
    runs = [sf.simulate(sf.scenes.spin_up_beam(n_elements=8), t_end=300 * dt, dt=dt, compiled=c)
            for c in (True, False)]
    assert_same_run(*runs)


@pytest.mark.parametrize("kw", [dict(order=2, n_elements=3), dict(strain="linear", n_elements=4)])
def test_spin_up_variants_compiled_equal_python(kw):
    runs = [sf.simulate(sf.scenes.spin_up_beam(**kw), t_end=2.0, dt=1e-2, record_every=7, compiled=c)
            for c in (True, False)]
    assert_same_run(*runs)
    assert runs[0].t[-1] == pytest.approx(2.0) and runs[0].t.size == 1 + 200 // 7 + 1


@pytest.mark.parametrize("reference", ["pinned", "clamped"])
def test_free_flight_compiled_equals_python(reference):
    runs = [sf.simulate(free_flying_beam(reference), t_end=1.0, dt=5e-3, compiled=c) for c in (True, False)]
    assert_same_run(*runs)
    a = runs[0]
    e = a.total_energy
    assert np.abs(e - e[0]).max() <= 1e-10 * e[0]
    assert np.abs(a.linear_momentum - a.linear_momentum[0]).max() <= 1e-10 * np.abs(a.linear_momentum[0]).max()


def test_last_step_is_shortened_and_environment_switch(monkeypatch):
    scene = sf.scenes.spin_up_beam(n_elements=4)
    a = sf.simulate(scene, t_end=0.1049, dt=1e-2)
    monkeypatch.setenv("SKFEM_FLEX_COMPILED", "0")
    b = sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=0.1049, dt=1e-2)
    assert a.t[-1] == pytest.approx(0.1049, abs=1e-15)
    assert_same_run(a, b)


def test_failing_steps_are_halved_as_on_the_python_path():
    """Steps too large for Newton are halved alike on both paths."""
    runs = [sf.simulate(sf.scenes.spin_up_beam(n_elements=4, omega=10.0), t_end=20.0, dt=1.0, max_halvings=3,
                        compiled=c) for c in (True, False)]
    assert runs[0].halvings == runs[1].halvings > 0
    assert_same_run(*runs, q_tol=1e-7, v_tol=1e-6)


def test_convergence_error_is_the_python_paths():
    errors = []
    for c in (True, False):
        with pytest.raises(ConvergenceError) as info:
            sf.simulate(sf.scenes.spin_up_beam(n_elements=4, omega=10.0), t_end=20.0, dt=1.0, max_halvings=0,
                        compiled=c)
        errors.append(info.value)
    assert str(errors[0]) == str(errors[1])
    steps = errors[1].result.steps          # the steps done before the one that failed (7 with this start)
    assert "Newton did not converge" in str(errors[0]) and f"[step {steps + 1} of 20]" in str(errors[0])
    assert errors[0].result.steps == steps and 5 <= steps < 19
    np.testing.assert_allclose(errors[0].result.q, errors[1].result.q, rtol=0,
                               atol=1e-9 * np.abs(errors[1].result.q).max())


def test_newton_settings_reach_the_compiled_loop():
    """A looser tolerance must change the compiled run exactly as it changes the Python one."""
    loose = NewtonSettings(rtol=1e-6, etol=1e-8)
    runs = [sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=1.0, dt=1e-2, newton=loose, compiled=c)
            for c in (True, False)]
    assert_same_run(*runs, q_tol=1e-6, v_tol=1e-4)
    tight = sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=1.0, dt=1e-2)
    assert runs[0].newton_iterations.sum() < tight.newton_iterations.sum()


def test_large_banded_spin_up_compiled_equals_python():
    """Above the dense size the compiled loop solves the banded free-free block (kl = ku = 4 here)."""
    scene = sf.scenes.spin_up_beam(n_elements=64)
    assert not scene.dense
    runs = [sf.simulate(sf.scenes.spin_up_beam(n_elements=64), t_end=0.3, dt=2e-3, compiled=c) for c in (True, False)]
    assert_same_run(*runs)


def test_bad_compiled_switch_is_rejected():
    with pytest.raises(ValueError, match="compiled must be"):
        sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=0.01, dt=1e-3, compiled="yes")


def test_energies_and_momenta_computed_in_the_loop_equal_the_scene_methods():
    """The compiled loop evaluates T, V and the momenta of the recorded states itself; they must be the
    scene's values at the recorded (q, v)."""
    assert_loop_measures_are_the_scenes(free_flying_beam("clamped"), rel=1e-13)


@pytest.mark.parametrize("scheme", ["energy-momentum", "generalized-alpha"])
def test_results_do_not_depend_on_the_chunks(monkeypatch, scheme):
    """A run is cut into chunks by the wall time its steps take; each step's times are the run's exact
    t₀ + k Δt whatever the chunks, so that a run in chunks of one step and one in the default chunks are the
    same run, bit for bit (the hub's law of the spin-up and the last, shortened step included)."""
    from skfem_flex.run import driver
    runs = []
    for chunk_seconds in (driver.CHUNK_SECONDS, 0.0):
        monkeypatch.setattr(driver, "CHUNK_SECONDS", chunk_seconds)
        runs.append(sf.simulate(sf.scenes.spin_up_beam(n_elements=4), t_end=0.1037, dt=2e-3, integrator=scheme))
    a, b = runs
    assert a.steps == b.steps == 52
    for name in ("t", "q", "v", "lam", "total_energy", "external_work"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_advance_checks_its_times():
    """Stepper.advance takes the end of each step; a wrong count is a clear error, not steps read past an array."""
    from skfem_flex.schemes.base import State
    from skfem_flex.schemes.stepper import Stepper
    scene = sf.scenes.pendulum()
    st = Stepper(scene, sf.EnergyMomentum())
    q, v = scene.initial_state()
    st.load(st.starting_state(State(0.0, q, v)))
    with pytest.raises(ValueError, match="end of each of the 3 steps, got 2"):
        st.advance(0.0, np.full(3, 1e-2), np.ones(3, dtype=bool), 25, True, times=np.array([0.01, 0.02]))
    chunk = st.advance(0.0, np.full(3, 1e-2), np.ones(3, dtype=bool), 25, True, times=np.array([0.01, 0.02, 0.03]))
    assert chunk.steps == 3
