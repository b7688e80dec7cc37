"""Scallop height and step-over (issue #11 §1; SPEC P3): against the circle geometry evaluated in 50-digit
arithmetic (mpmath), the textbook formula written the naive way, on convex, concave, flat and nearly flat
surfaces."""

import mpmath as mp
import numpy as np
import pytest

import machscan

mp.mp.dps = 50


def reference_height(r, rho, step):
    """SPEC P3 as printed: the cusp where the two tool circles meet, at 50 digits."""
    r, step = mp.mpf(r), mp.mpf(step)
    if np.isinf(rho):
        return r - mp.sqrt(r**2 - (step / 2) ** 2)
    rho = mp.mpf(rho)
    phi = step / abs(rho)
    if rho > 0:
        d = rho + r
        return d * mp.cos(phi / 2) - mp.sqrt(r**2 - d**2 * mp.sin(phi / 2) ** 2) - rho
    d = -rho - r
    return -rho - (d * mp.cos(phi / 2) + mp.sqrt(r**2 - d**2 * mp.sin(phi / 2) ** 2))


RADII = [np.inf, 3.0, 25.0, 400.0, 1e6, -1e6, -400.0, -25.0, -10.5]


@pytest.mark.parametrize("rho", RADII)
def test_heights_and_steps_equal_the_circle_geometry_to_1e_9(rho):
    r = 10.0
    for step in [1e-4, 0.05, 0.8, 3.0, 7.5]:
        exact = reference_height(r, rho, step)
        if isinstance(exact, mp.mpc):  # the tool circles do not meet: a strip stays unground
            with pytest.raises(ValueError, match="step"):
                machscan.scallop_height(r, rho, step)
            continue
        want = float(exact)
        assert abs(machscan.scallop_height(r, rho, step) - want) < 1e-9 * max(1.0, want)
        # The inverse: the step whose height is the reference height.
        assert abs(machscan.step_over(r, rho, want) - step) < 1e-9 * max(1.0, step)


def test_the_naive_formula_loses_digits_where_this_one_does_not():
    # Nearly flat: D cos(φ/2) − √(...) − ρ subtracts numbers of 1e6 to get 1e-2; the direct double-precision
    # evaluation keeps ~8 digits of h, this one all of them.
    r, rho, step = 10.0, 1e6, 0.8
    want = float(reference_height(r, rho, step))
    d, phi = rho + r, step / rho
    naive = d * np.cos(phi / 2) - np.sqrt(r**2 - d**2 * np.sin(phi / 2) ** 2) - rho
    assert abs(naive - want) > 1e-11
    assert abs(machscan.scallop_height(r, rho, step) - want) < 1e-15


def test_vectorised_over_broadcast_arrays_and_scalars_stay_scalars():
    h = machscan.scallop_height(10.0, np.array(RADII)[:, None], np.array([0.1, 0.5, 1.0]))
    assert h.shape == (len(RADII), 3)
    for i, rho in enumerate(RADII):
        for j, step in enumerate([0.1, 0.5, 1.0]):
            assert h[i, j] == machscan.scallop_height(10.0, rho, step)
    assert isinstance(machscan.step_over(10.0, 50.0, 0.01), float)
    # Convex rows closer than flat ones, concave ones wider, for the same cusp.
    s = machscan.step_over(10.0, [50.0, np.inf, -50.0], 0.01)
    assert s[0] < s[1] < s[2]


@pytest.mark.parametrize(
    ("args", "name"),
    [
        ((10.0, -10.0, 0.01), "curvature_radius"),  # concave no larger than the tool
        ((10.0, 0.0, 0.01), "curvature_radius"),
        ((10.0, np.nan, 0.01), "curvature_radius"),
        ((0.0, 50.0, 0.01), "tool_radius"),
        ((10.0, 50.0, 10.0), "scallop_height"),
        ((10.0, 50.0, -0.1), "scallop_height"),
        ((10.0, [50.0, -5.0], 0.01), "element 1"),
        ((10.0, [50.0, 40.0], [0.1, 0.2, 0.3]), "broadcast"),
    ],
)
def test_impossible_geometry_is_refused_by_name(args, name):
    with pytest.raises(ValueError, match=name):
        machscan.step_over(*args)


def test_a_step_that_leaves_a_strip_unground_is_refused():
    with pytest.raises(ValueError, match="step"):
        machscan.scallop_height(10.0, np.inf, 20.5)
    with pytest.raises(ValueError, match="step"):
        machscan.scallop_height(10.0, 5.0, 20.0)
