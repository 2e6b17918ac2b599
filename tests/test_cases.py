"""Scene builders and table waves of the paper cases (dda.studies.cases)."""

import numpy as np
import pytest
from scipy.integrate import quad

from dda.studies.cases import ramped_sine, sine_displacement, stacked_cubes, stepped_table


def test_stepped_table_rises_in_steps_and_does_not_drift():
    table = stepped_table(670.0, 2.0, levels=8, hold=2.0)
    assert table.breakpoints == [2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0]
    for k in range(8):  # the crest of each level: (k + 1) / 8 of 670 gal
        assert table(2.0 * k + 0.5)[0] == pytest.approx(6.70 * (k + 1) / 8, rel=1e-12)
    # from rest, the velocity is back at zero after every whole period: no drift
    for t_end in (2.0, 7.5, 16.0):
        v, _ = quad(lambda t: table(t)[0], 0.0, t_end, points=table.breakpoints, limit=400)
        assert v == pytest.approx(0.0, abs=1e-9)


def test_stepped_table_refuses_a_hold_that_cuts_a_period():
    with pytest.raises(ValueError, match="whole number of periods"):
        stepped_table(670.0, 2.0, levels=8, hold=0.3)


def test_ramped_sine_starts_and_stops_without_a_jump():
    table = ramped_sine(3.0, 700.0, ramp=0.5, stop=4.0)
    assert table(0.0)[0] == 0.0
    assert table(0.0 + 1e-6)[0] == pytest.approx(0.0, abs=1e-6)
    t = np.linspace(0.5, 3.5, 3001)
    assert np.abs([table(ti)[0] for ti in t]).max() == pytest.approx(7.0, rel=1e-4)
    assert table(4.0 - 1e-6)[0] == pytest.approx(0.0, abs=1e-6)
    assert table(4.5) == (0.0, 0.0)


def test_sine_displacement_has_the_sine_acceleration_and_starts_moving():
    """A's table: u = -(a / omega^2) sin(omega t); its second difference is a sin(omega t)
    (to the finite difference's h^2), and it starts at 0 with the velocity -a / omega."""
    u = sine_displacement(3.0, 700.0)
    a, omega, h = 7.0, 6.0 * np.pi, 1e-4
    assert u(0.0) == (0.0, 0.0)
    for t in (0.05, 0.3, 1.234):
        accel = (u(t + h)[0] - 2 * u(t)[0] + u(t - h)[0]) / h**2
        assert accel == pytest.approx(a * np.sin(omega * t), abs=1e-5 * a)
    assert (u(h)[0] - u(-h)[0]) / (2 * h) == pytest.approx(-a / omega, rel=1e-6)


def test_stacked_cubes_take_one_table_motion():
    scene, table, _ = stacked_cubes(displacement=sine_displacement(5.0, 400.0))
    assert len(scene.motions) == 1 and len(scene.shakes) == 0
    with pytest.raises(ValueError, match="one of the two"):
        stacked_cubes()
    with pytest.raises(ValueError, match="one of the two"):
        stacked_cubes(ramped_sine(3.0, 400.0), displacement=sine_displacement(3.0, 400.0))
