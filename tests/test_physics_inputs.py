"""Bad, extreme and oddly shaped inputs: clear errors, never a crash or a NaN."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skyfall import physics

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
bad_numbers = st.one_of(
    st.just(float("nan")), st.just(float("inf")), st.just(-float("inf")), st.floats(max_value=-1e-300, allow_nan=False)
)
models = st.sampled_from(physics.FALL_SPEED_MODELS)
air_t = st.floats(-40, 50)
air_p = st.floats(50, 1100)
air_rh = st.floats(0, 1)


def saturation_hpa(t: float) -> float:
    # Magnus (Alduchov & Eskridge 1996) over water, within 0.5 % of Wexler here.
    return 6.1094 * math.exp(17.625 * t / (t + 243.04))


@settings(max_examples=300, deadline=None)
@given(d=st.floats(0, 8), model=models, t=air_t, p=air_p, rh=air_rh)
def test_terminal_velocity_is_finite_and_bounded_everywhere(d, model, t, p, rh):
    e = rh * saturation_hpa(t)
    if e >= 0.99 * p:  # no such air: refused (tested below)
        return
    v = physics.terminal_velocity(d, model=model, temperature_c=t, pressure_hpa=p, relative_humidity=rh)
    assert isinstance(v, float)
    # Drag is never below Newton's Cd = 0.44: v <= sqrt(4 g D rho_w / (3 * 0.44 * rho_a)).
    rho_a = physics.air_density_kg_m3(t, p, rh)
    bound = math.sqrt(4 * 9.80665 * d * 1e-3 * 1000.0 / (3 * 0.44 * rho_a))
    assert math.isfinite(v) and 0.0 <= v <= 1.01 * bound + 1e-9
    if d == 0.0:
        assert v == 0.0


def test_impossible_air_is_refused():
    with pytest.raises(ValueError, match="relative_humidity.*vapour pressure"):
        physics.terminal_velocity(2.0, temperature_c=50.0, pressure_hpa=50.0, relative_humidity=1.0)


@settings(max_examples=200, deadline=None)
@given(d=bad_numbers, model=models)
def test_bad_diameters_raise_value_error_naming_the_parameter(d, model):
    with pytest.raises(ValueError, match=r"diameter_mm = .* \[0, 8\] mm"):
        physics.terminal_velocity(d, model=model)


@settings(max_examples=100, deadline=None)
@given(d=st.floats(8.0, 1e300, exclude_min=True))
def test_too_large_drops_are_refused(d):
    with pytest.raises(ValueError, match="diameter_mm"):
        physics.terminal_velocity(d)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"temperature_c": -60.0}, "temperature_c"),
        ({"temperature_c": float("nan")}, "temperature_c"),
        ({"pressure_hpa": 0.0}, "pressure_hpa"),
        ({"pressure_hpa": float("inf")}, "pressure_hpa"),
        ({"relative_humidity": 1.01}, "relative_humidity"),
        ({"relative_humidity": -0.1}, "relative_humidity"),
    ],
)
def test_bad_air_raises(kwargs, name):
    with pytest.raises(ValueError, match=name):
        physics.terminal_velocity(1.0, **kwargs)
    with pytest.raises(ValueError, match=name):
        physics.rain_rate_from_dsd(5.0, **kwargs)


def test_array_errors_name_the_element():
    with pytest.raises(ValueError, match=r"diameter_mm\[2\] = NaN"):
        physics.terminal_velocity([1.0, 2.0, np.nan])
    with pytest.raises(ValueError, match=r"pressure_hpa\[1\] = -5"):
        physics.terminal_velocity(1.0, pressure_hpa=[1000.0, -5.0])


@settings(max_examples=200, deadline=None)
@given(r=st.floats(0, 500))
def test_rain_functions_are_finite_for_every_valid_rate(r):
    sigma = physics.rain_extinction_per_m(r)
    n = physics.drops_per_m3(r)
    assert math.isfinite(sigma) and sigma >= 0 and math.isfinite(n) and n >= 0
    assert (sigma == 0.0) == (r == 0.0)
    assert np.all(np.isfinite(physics.marshall_palmer([0.0, 0.01, 8.0], r)))


@settings(max_examples=50, deadline=None)
@given(r=st.one_of(bad_numbers, st.floats(500, 1e300, exclude_min=True)))
def test_bad_rates_raise(r):
    for fn in (physics.rain_extinction_per_m, physics.drops_per_m3, physics.rain_rate_from_dsd):
        with pytest.raises(ValueError, match="rain_rate_mm_h"):
            fn(r)
    with pytest.raises(ValueError, match="rain_rate_mm_h"):
        physics.marshall_palmer(1.0, r)


def test_extremes_behave():
    assert physics.rain_rate_from_dsd(500.0) > 400.0
    assert physics.drops_per_m3(0.0) == 0.0 and physics.marshall_palmer(0.0, 0.0) == 0.0
    v = physics.terminal_velocity(np.array([0.01, 8.0]))
    assert 0.002 < v[0] < 0.004 and 9.0 < v[1] < 9.5  # Beard: 10 um drops fall ~3 mm/s


def test_extinction_and_drop_count_grow_with_rate():
    r = np.linspace(0, 500, 101)
    assert np.all(np.diff(physics.rain_extinction_per_m(r)) > 0)
    assert np.all(np.diff(physics.drops_per_m3(r)) > 0)


def test_bin_edges_must_be_ordered():
    with pytest.raises(ValueError, match="d_max_mm"):
        physics.drops_per_m3(5.0, 2.0, 1.0)
    with pytest.raises(ValueError, match="d_max_mm"):
        physics.rain_rate_from_dsd(5.0, d_max_mm=9.0)
    with pytest.raises(ValueError, match="d_min_mm"):
        physics.drops_per_m3(5.0, -1.0, 1.0)


@pytest.mark.parametrize("value", ["1.0", None, 1 + 2j, [1, "a"], {"a": 1}, [[1, 2], [3]]])
def test_non_numbers_raise_type_error(value):
    with pytest.raises(TypeError, match="diameter_mm"):
        physics.terminal_velocity(value)


def test_model_is_checked():
    with pytest.raises(ValueError, match="model = 'stokes'"):
        physics.terminal_velocity(1.0, model="stokes")
    with pytest.raises(TypeError, match="model"):
        physics.terminal_velocity(1.0, model=3)


def test_shapes_broadcast_like_numpy():
    d = np.linspace(0.5, 5, 4)
    p = np.array([[1013.25], [800.0], [600.0]])
    v = physics.terminal_velocity(d, pressure_hpa=p)
    assert v.shape == (3, 4) and v.dtype == np.float64
    np.testing.assert_array_equal(v[1], physics.terminal_velocity(d, pressure_hpa=800.0))
    assert isinstance(physics.terminal_velocity(np.float32(2.0)), float)
    assert physics.terminal_velocity(np.zeros((0, 3))).shape == (0, 3)
    assert physics.terminal_velocity(np.array([2], dtype=np.int64)).shape == (1,)
    with pytest.raises(ValueError, match="do not broadcast"):
        physics.terminal_velocity([1.0, 2.0], pressure_hpa=[900.0, 800.0, 700.0])


def test_large_inputs_match_small_ones():
    # The kernel splits long inputs across threads; results must be element-for-element equal.
    d = np.linspace(0, 8, 100_001)
    big = physics.terminal_velocity(d)
    small = np.concatenate([physics.terminal_velocity(d[i : i + 1000]) for i in range(0, d.size, 1000)])
    np.testing.assert_array_equal(big, small)
