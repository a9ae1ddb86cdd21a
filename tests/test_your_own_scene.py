"""examples/your_own_scene.py (docs/your_own_scene.md) runs and its results obey statics and the energy balance."""
import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "your_own_scene.py"
PAGE = ROOT / "docs" / "your_own_scene.md"


@pytest.fixture(scope="module")
def example():
    mp = pytest.MonkeyPatch()
    mp.setenv("YOUR_SCENE_T_END", "0.1")          # 100 steps: the physics to check, not the whole second
    try:
        spec = importlib.util.spec_from_file_location("your_own_scene_example", EXAMPLE)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        mp.undo()
    return module


def test_the_clamp_reaction_balances_the_applied_loads(example):
    """Statics of the whole cantilever: the weld's force is minus the tip force minus the weight,
    however far the strip bends (it bends a lot: the tip drops by a third of the length)."""
    fx, fy, moment = example.clamp_reaction
    applied = np.asarray(example.TIP_FORCE) + example.strip.rhoA * example.CANTILEVER_LENGTH * np.asarray(example.G)
    np.testing.assert_allclose([fx, fy], -applied, rtol=1e-9, atol=1e-9 * np.abs(applied).max())
    assert example.tip_position[1] < -0.1 * example.CANTILEVER_LENGTH
    # the moment about the root: the tip force at the deflected tip's lever arm, plus the weight's
    # moment, which lies between that of the weight at the root (0) and at the tip
    tip_moment = -(example.tip_position[0] * example.TIP_FORCE[1])
    weight = -example.strip.rhoA * example.CANTILEVER_LENGTH * example.G[1]
    assert tip_moment < moment < tip_moment + weight * example.tip_position[0]


def test_the_mechanism_balances_energy_and_keeps_its_joints(example):
    result = example.result
    assert result.completed and result.t[-1] == pytest.approx(0.1)
    # energy-momentum scheme: E − E₀ equals the push's work to the Newton tolerance
    assert example.balance_error <= 1e-9 * example.energy_scale
    assert abs(result.external_work[-1]) > 1e-6           # the push did work
    assert result.constraint_residual.max() <= 1e-9
    # the slider stays on its rail y = 0, and the crank falls (gravity, released at rest)
    np.testing.assert_allclose(result.probes["slider"][:, 1], 0.0, atol=1e-9)
    assert result.probes["crank_angle"][-1] < result.probes["crank_angle"][0]
    assert set(result.reactions) == {"bearing", "crank_pin", "wrist_pin", "rail", "sensor_mount"}


def test_the_page_shows_the_example_code():
    """Every code block of the page is the example's code, so the page runs as written."""
    script = EXAMPLE.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) >= 8
    for block in blocks:
        assert block.strip("\n") in script, block
