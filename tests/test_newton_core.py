"""The one Newton core (skfem_flex.numerics.newton): its rules on small problems with known roots, and
that every solver of the package runs it — change one rule in a copy of the package and every
scheme (compiled and Python-assembled) and the static solver change with it."""
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import skfem_flex
from skfem_flex.errors import ConvergenceError
from skfem_flex.numerics.newton import NewtonSettings, newton_solve


def scalar(f, df, scale=1e-12):
    """fun(x) of a scalar equation f(x) = 0, error |f| / scale."""
    def fun(x):
        value = f(x[0])
        return np.array([value]), np.array([[df(x[0])]]), abs(value) / scale
    return fun


def test_quadratic_convergence_to_the_cube_root_of_two():
    calls = []

    def f(x):
        calls.append(x)
        return x ** 3 - 2.0
    x, r, its = newton_solve(scalar(f, lambda x: 3 * x * x), np.array([1.0]), NewtonSettings(), "test", "here")
    assert abs(x[0] - 2.0 ** (1 / 3)) <= 4e-16 * 2 ** (1 / 3) + 1e-12 / 3 / 2 ** (2 / 3)
    assert abs(r[0]) <= 1e-12 and its <= 6
    # quadratic: the error of each iterate is about C e² of the one before
    e = np.abs(np.array(calls) - 2.0 ** (1 / 3))
    assert e[3] <= 2 * e[2] ** 2 / 2 ** (1 / 3)


def test_line_search_rescues_newton_on_arctan():
    """Plain Newton on atan(x) = 0 diverges from |x0| > 1.39; backtracking reaches the root."""
    fun = scalar(np.arctan, lambda x: 1.0 / (1.0 + x * x))
    x, _, _ = newton_solve(fun, np.array([3.0]), NewtonSettings(), "test", "here")
    assert abs(x[0]) <= 1e-12
    with pytest.raises(ConvergenceError), np.errstate(over="ignore"):
        newton_solve(fun, np.array([3.0]), NewtonSettings(line_search=False), "test", "here")


def test_failures_are_reported_with_their_reason():
    singular = scalar(lambda x: x * x + 1.0, lambda x: 0.0 * x)
    with pytest.raises(ConvergenceError, match="singular Newton matrix at here"):
        newton_solve(singular, np.array([1.0]), NewtonSettings(), "test", "here")
    with pytest.raises(ConvergenceError, match="residual is not finite"):
        newton_solve(scalar(lambda x: np.nan, lambda x: 1.0), np.array([1.0]), NewtonSettings(), "test", "here")
    # no real root: Newton wanders until the iteration cap
    with pytest.raises(ConvergenceError, match="did not converge at here") as info:
        newton_solve(scalar(lambda x: x * x + 1.0, lambda x: 2 * x), np.array([0.3]),
                     NewtonSettings(max_iterations=7, line_search=False), "test", "here")
    assert info.value.info["iterations"] == 7


def test_exceptions_of_the_residual_pass_through():
    def fun(x):
        raise KeyError("from the residual")
    with pytest.raises(KeyError, match="from the residual"):
        newton_solve(fun, np.array([1.0]), NewtonSettings(), "test", "here")


# every solver of the package, run in a fresh process on a copy of the package
PROBE = textwrap.dedent('''
    import json
    import skfem_flex as sf
    from skfem_flex.analysis import static_equilibrium
    out = {}
    # the mass on a spring with a cubic force: the scene with the fewest compiled units (the step, the loop, the
    # start, two small families), nonlinear so that Newton iterates; the pendulum's statics (Python-assembled)
    oscillator = sf.scenes.get("spring_mass")()
    for scheme in ("energy-momentum", "trapezoidal", "generalized-alpha"):
        res = sf.simulate(oscillator, 1.0, 0.05, integrator=scheme)
        out[scheme] = int(res.newton_iterations.sum())
    out["statics"] = int(static_equilibrium(sf.scenes.get("pendulum")(), q=[0.4, -0.3]).iterations)
    print(json.dumps(out))
''')


def probe(root):
    env = dict(os.environ, PYTHONPATH=str(root))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, cwd=str(root), capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_one_rule_changed_in_one_place_changes_every_scheme(tmp_path):
    """Edit the convergence threshold of the core in a copy of the package: every scheme's compiled step
    and the static solver take fewer iterations in the next process (the compiled steps, which inline the
    core from another file, are compiled afresh, not reused). "Before" runs this checkout (its cache warm)."""
    root = tmp_path / "site"
    shutil.copytree(Path(skfem_flex.__file__).parent, root / "skfem_flex",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    before = probe(Path(skfem_flex.__file__).parent.parent)
    source = root / "skfem_flex" / "numerics" / "newton.py"
    text = source.read_text()
    assert text.count("CONVERGED_BELOW = 1.0\n") == 1
    source.write_text(text.replace("CONVERGED_BELOW = 1.0\n", "CONVERGED_BELOW = 1e7\n"))
    after = probe(root)
    assert set(before) == set(after) == {"energy-momentum", "trapezoidal", "generalized-alpha", "statics"}
    for solver in before:
        assert after[solver] < before[solver], (solver, before[solver], after[solver])


def test_the_python_driver_compiles_the_core_through_the_registry(monkeypatch):
    """newton_solve compiles each core function it calls from Python through the hook the compile registry
    installs (announced and timed like every compile), once per function and process."""
    from skfem_flex.compiled import registry
    from skfem_flex.numerics import newton

    calls = []

    def hook(fn, argtypes, what):
        calls.append(fn.__name__)
        return registry.compiled_function(fn, argtypes, what)

    monkeypatch.setattr(newton, "_READY", set())
    newton.set_compile_hook(hook)
    try:
        for _ in range(2):
            x, _, _ = newton_solve(lambda x: (x ** 3 - 2.0, np.diag(3 * x ** 2), float(abs(x[0] ** 3 - 2.0) / 1e-12)),
                                   np.array([1.0]), NewtonSettings(), "test", "here")
    finally:
        newton.set_compile_hook(registry.compiled_function)
    assert calls == ["newton_start", "newton_evaluated", "newton_solved"]
    assert x[0] == pytest.approx(2.0 ** (1 / 3), rel=1e-12)
