"""The cantilever example computes at import time; check what it reports."""
import importlib.util
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "cantilever.py"


def load_example():
    spec = importlib.util.spec_from_file_location("cantilever_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cantilever_example_results():
    example = load_example()
    np.testing.assert_allclose(example.observed_order["reduced"], 2.0, atol=0.05)
    assert np.all(np.abs(example.tip_error["reduced"][-1]) < 1e-4)
    assert np.all(np.abs(example.tip_error["full"][:, 1:]) > 0.4)  # locking when slender
    assert list(example.is_axial) == [False, False, True, False]
    assert "order" in example.convergence_table()
