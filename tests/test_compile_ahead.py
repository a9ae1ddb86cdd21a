"""Compiling a run's missing units on two processes (skfem_flex.compiled.ahead)."""
import json
import os
import subprocess
import sys

import pytest

import skfem_flex as sf
from skfem_flex.compiled import ahead
from skfem_flex.compiled.loop import entry_types, record_at, run_steps, start_state
from skfem_flex.compiled.pack import packed_scene
from skfem_flex.schemes.stepper import units

from helpers import ROOT

# Two rounds in a fresh process with an empty cache: a helper that dies at once (everything is compiled
# here), then a working helper (each process compiles one of two units). Small units: about 6 s.
SCRIPT = """
import json, subprocess, sys
from skfem_flex.compiled import ahead, registry, solvers
from skfem_flex.compiled.families import constant_mass, linear_rows, springs

with registry.planning() as first:
    constant_mass.kernel(); solvers.dense_solver()
real = ahead._start_helper
ahead._start_helper = lambda folder: subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])
done = ahead.compile_units(first)
report = {"dead helper": [sorted(done.here), sorted(done.helper)]}
ahead._start_helper = real
with registry.planning() as second:
    linear_rows.kernel(); springs.kernel()
done = ahead.compile_units(second)
report["helper"] = [sorted(done.here), sorted(done.helper)]
report["cached"] = all(registry.is_cached(u) for u in first + second)
report["names"] = sorted(registry.compiled_names())
print(json.dumps(report))
"""


def test_two_processes_share_a_cold_compile_and_a_dead_helper_costs_nothing(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(tmp_path), SKFEM_FLEX_QUIET="1",
               SKFEM_FLEX_COMPILE_PROCESSES="2")
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout.splitlines()[-1])
    assert report["dead helper"] == [["the constant-mass bodies' family", "the dense linear solver"], []]
    here, helper = report["helper"]
    assert here and helper and sorted(here + helper) == ["the linear-constraint family", "the springs family"], report
    assert report["cached"]
    assert report["names"] == sorted(report["dead helper"][0] + here + helper), report


def test_the_loop_entry_types_are_those_a_run_calls_with():
    """Compiled ahead for :func:`entry_types`, the loop's entry points need no second compile in a run."""
    sf.simulate(sf.scenes.get("pendulum")(), 0.02, 1e-2)
    types = entry_types()
    for fn in (run_steps, record_at, start_state):
        assert fn.signatures == [types[fn.__name__]], fn.__name__


def test_a_run_asks_for_its_scheme_loop_families_start_and_solver():
    scene = sf.scenes.get("pendulum")()
    listed = [u.what for u in units(packed_scene(scene), sf.EnergyMomentum())]
    assert listed[:2] == ["the energy-momentum step", "the time loop"]   # no allocating kernel here
    assert {"the gravity family", "the distance-constraint family", "the consistent start",
            "the dense linear solver", "the recorder", "the consistent start's driver"} <= set(listed)
    assert len(listed) == len(set(listed))


@pytest.mark.parametrize("text", ["3", "two", "0"])
def test_a_wrong_process_count_is_named(monkeypatch, text):
    monkeypatch.setenv("SKFEM_FLEX_COMPILE_PROCESSES", text)
    with pytest.raises(ValueError, match=f"SKFEM_FLEX_COMPILE_PROCESSES must be 1 or 2, got '{text}'"):
        ahead.processes()


def test_the_allocating_kernels_come_first():
    """The floating-frame family and the band solver (numba's reference counting) compile longest: first."""
    scene = sf.scenes.get("spin_up_beam")()
    listed = units(packed_scene(scene), sf.EnergyMomentum())
    assert [u.nrt for u in listed] == sorted((u.nrt for u in listed), reverse=True)
    assert {u.what for u in listed if u.nrt} == {"the floating-frame family", "the band-with-border linear solver"}
