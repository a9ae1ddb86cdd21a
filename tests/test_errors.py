"""Every way a run can fail is one family under the documented base ``sf.SimulationError`` (skfem_flex/errors.py)."""
import importlib

import pytest

import skfem_flex as sf
from skfem_flex import errors


def _reexporters():
    """The package root and the schemes package, which re-export the errors."""
    return [sf, importlib.import_module("skfem_flex.schemes")]

FAMILY = ["ConvergenceError", "DivergenceError", "Interrupted", "OutputError"]


def test_the_base_is_exported_and_documented():
    assert sf.SimulationError is errors.SimulationError
    assert "SimulationError" in errors.__all__
    assert issubclass(sf.SimulationError, RuntimeError)
    doc = errors.__doc__
    for name in FAMILY + ["SimulationError", "ElementInversionError"]:
        assert name in doc, name


@pytest.mark.parametrize("name", FAMILY)
def test_every_failure_is_a_simulation_error_defined_once(name):
    cls = getattr(errors, name)
    assert issubclass(cls, sf.SimulationError)
    # one class, whatever the path it is imported from
    assert getattr(sf, name) is cls
    for mod in _reexporters():
        if hasattr(mod, name):
            assert getattr(mod, name) is cls, mod.__name__
    assert cls.__module__ == "skfem_flex.errors"


def test_divergence_is_a_simulation_error_and_not_a_convergence_error():
    assert issubclass(sf.DivergenceError, sf.SimulationError)
    assert not issubclass(sf.DivergenceError, sf.ConvergenceError)


def test_element_inversion_is_a_convergence_failure_and_bad_input():
    assert issubclass(sf.ElementInversionError, sf.ConvergenceError)
    assert issubclass(sf.ElementInversionError, sf.SimulationError)
    assert issubclass(sf.ElementInversionError, ValueError)


def test_one_except_catches_a_failed_run():
    """A run that Newton cannot continue (V = ½ u³, unbounded below: the mass escapes) raises a
    SimulationError that carries the steps done."""
    scene = sf.scenes.spring_mass(exponent=1.5)
    with pytest.raises(sf.SimulationError) as info:
        sf.simulate(scene, 100.0, 0.1)
    assert info.value.result is not None and not info.value.result.completed
    assert 0 < len(info.value.result.t) < 1001
    assert isinstance(info.value.info, dict)
