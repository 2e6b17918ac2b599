"""Three stacked cubes on a shaking table (A 3, A 4(2), METHOD.md section 9), short version:
3 s of shaking instead of 4. See ``examples/stacked_cubes.py`` for the full table."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from dda.studies.cases import ramped_sine

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "stacked_cubes.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("stacked_cubes", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("freq", [3.0, 5.0])
def test_below_the_rocking_threshold_the_stack_stands(example, freq):
    """300 gal < g b / H = 327 gal: stable, as in the test."""
    run = example.run_case(freq, 300.0, 3.0)
    assert run["outcome"] == run["test"] == "stable"
    assert run["peak_rotation"] < 0.005 and run["residual"] < 1e-3


@pytest.fixture(scope="module")
def strong_shaking(example):
    return example.run_case(3.0, 700.0, 3.0)


def test_above_it_the_stack_rocks(strong_shaking):
    assert strong_shaking["status"] == "ok"
    assert strong_shaking["peak_rotation"] > 0.05  # 0.13 rad here
    assert strong_shaking["outcome"] == "moved"


@pytest.mark.xfail(strict=True, reason=(
    "open: the stack rocks to about 0.15 rad but does not reach the 0.32 rad it needs to tip; "
    "the test saw it topple (see the docstring of examples/stacked_cubes.py)"))
def test_strong_shaking_topples_the_stack(strong_shaking):
    assert strong_shaking["outcome"] == "toppled"


def test_classification_rules(example):
    tip = example.TIP_ANGLE
    z = np.zeros(3)
    assert example.classify(z, z, z) == "stable"
    assert example.classify(z, z, np.array([0, 0, 6e-3])) == "moved"
    assert example.classify(np.array([0, 0, np.radians(2.5)]), z, z) == "moved"
    assert example.classify(np.array([0, 0, tip + 1e-3]), z, z) == "toppled"
    assert example.classify(z, np.array([0, 0.08, 0]), z) == "toppled"


@pytest.mark.parametrize("freq, gal", [(3.0, 500.0), (3.0, 700.0), (5.0, 700.0)])
def test_the_rigid_block_theory_does_not_topple_the_stack_either(freq, gal):
    """Why the strict xfail above stays: the 45 cm stack as one rigid block under the
    example's 4 s ramped sine, with Housner's impacts (r = 0.85), rocks to 8.2, 11.2 and
    4.3 degrees in the three cases the test saw topple, and tips at none; the three cubes in
    DDA rock to 8.2-8.6, 9.1-11.2 and 3.9-4.2. It would tip at 3 Hz 700 gal only if its
    impacts lost at most 10% of the rocking velocity (r >= 0.9), and at 5 Hz 700 gal not even
    without any loss; with Housner's r it tips at 3 Hz between 900 and 1,100 gal."""
    from dda.studies.references import housner_shaken

    table = ramped_sine(freq, gal, stop=4.0)
    rigid = housner_shaken(0.15, 0.45, table, 5.0)
    assert not rigid.toppled and 0.05 < rigid.peak < 0.2
    lossless = housner_shaken(0.15, 0.45, table, 5.0, restitution=1.0)
    assert lossless.toppled == (freq == 3.0)
