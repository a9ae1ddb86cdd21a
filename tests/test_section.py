"""Section: resultant properties, constructors from material, loud bad input."""
import dataclasses
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from skfem_flex.fem.section import Section

GOOD = dict(EA=2.8e7, EI=1.4e4, kGA=1e7, rhoA=1.2, rhoI=6e-4)
BAD_VALUES = [0.0, -1.0, math.nan, math.inf, -math.inf]


def test_section_stores_floats_and_is_frozen():
    sec = Section(**GOOD)
    assert sec == Section(**{k: float(v) for k, v in GOOD.items()})
    assert all(type(getattr(sec, k)) is float for k in GOOD)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sec.EA = 1.0


def test_rotary_inertia_may_be_zero():
    assert Section(**{**GOOD, "rhoI": 0.0}).rhoI == 0.0


@pytest.mark.parametrize(
    "name, value",
    [(n, v) for n in GOOD for v in BAD_VALUES if not (n == "rhoI" and v == 0.0)],
)
def test_invalid_section_value_names_field(name, value):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        Section(**{**GOOD, name: value})


@given(
    name=st.sampled_from(list(GOOD)),
    value=st.one_of(
        st.floats(max_value=0.0, exclude_max=True),
        st.just(math.nan),
        st.just(math.inf),
        st.sampled_from([None, "1.0", True, [1.0]]),
    ),
)
def test_invalid_section_values_generated(name, value):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        Section(**{**GOOD, name: value})


def test_rectangle_matches_hand_computation():
    E, nu, b, h, rho, k = 210e9, 0.3, 0.1, 0.2, 7850.0, 5 / 6
    sec = Section.rectangle(E, nu, b, h, rho, k=k)
    A, I, G = b * h, b * h**3 / 12, E / (2 * (1 + nu))
    assert sec.EA == pytest.approx(E * A, rel=1e-15)
    assert sec.EI == pytest.approx(E * I, rel=1e-15)
    assert sec.kGA == pytest.approx(k * G * A, rel=1e-15)
    assert sec.rhoA == pytest.approx(rho * A, rel=1e-15)
    assert sec.rhoI == pytest.approx(rho * I, rel=1e-15)


def test_from_material_matches_hand_computation():
    sec = Section.from_material(E=70e9, G=26e9, A=2e-4, I=3e-9, rho=2700.0, k=0.9)
    assert sec == Section(EA=70e9 * 2e-4, EI=70e9 * 3e-9, kGA=0.9 * 26e9 * 2e-4,
                          rhoA=2700.0 * 2e-4, rhoI=2700.0 * 3e-9)


@pytest.mark.parametrize("nu", [-1.0, 0.5, 0.7, -2.0, math.nan, math.inf])
def test_rectangle_rejects_poisson_ratio_outside_range(nu):
    with pytest.raises(ValueError, match=r"^nu\b"):
        Section.rectangle(E=210e9, nu=nu, b=0.1, h=0.1, rho=7850.0)


@pytest.mark.parametrize("name", ["E", "b", "h", "rho", "k"])
@pytest.mark.parametrize("value", BAD_VALUES)
def test_rectangle_rejects_bad_inputs(name, value):
    args = dict(E=210e9, nu=0.3, b=0.1, h=0.1, rho=7850.0, k=5 / 6)
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        Section.rectangle(**{**args, name: value})


@pytest.mark.parametrize("name", ["E", "G", "A", "I", "rho", "k"])
@pytest.mark.parametrize("value", BAD_VALUES)
def test_from_material_rejects_bad_inputs(name, value):
    args = dict(E=210e9, G=80e9, A=1e-2, I=1e-5, rho=7850.0, k=5 / 6)
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        Section.from_material(**{**args, name: value})
