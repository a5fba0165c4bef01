"""Physical <-> normalised units (Section 1: a = b = g = 1)."""

import math

import pytest

import stairbounce as sb


def test_normalized_speed_formula_and_inverse():
    # 17 cm steps, 28 cm treads, 1.2 m/s: u = U sqrt(a/g) / b
    u = sb.normalized_speed(1.2, 0.17, 0.28)
    assert u == pytest.approx(1.2 * math.sqrt(0.17 / 9.81) / 0.28)
    assert sb.physical_speed(u, 0.17, 0.28) == pytest.approx(1.2)
    assert sb.time_scale(0.17) == pytest.approx(math.sqrt(0.17 / 9.81))


def test_same_shape_staircase_scales_with_sqrt_of_size():
    # a staircase 4 times bigger needs twice the speed for the same u
    assert sb.physical_speed(0.5, 0.8, 1.2) == pytest.approx(2 * sb.physical_speed(0.5, 0.2, 0.3))


@pytest.mark.parametrize(
    "args,match",
    [
        ((0.0, 0.17, 0.28), "speed must be > 0"),
        ((1.0, -0.17, 0.28), "step_height must be > 0"),
        ((1.0, 0.17, float("nan")), "step_length must be finite"),
    ],
)
def test_bad_units(args, match):
    with pytest.raises(ValueError, match=match):
        sb.normalized_speed(*args)
    with pytest.raises(ValueError, match="g must be > 0"):
        sb.normalized_speed(1.0, 0.17, 0.28, g=0)
