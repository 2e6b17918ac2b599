"""Random input at the public API: a clear error from dda or a finite result, never a crash.

A "clear error" is a ValueError, TypeError or SimulationError raised by dda's own code (the
innermost frame of its traceback lies in the dda package) with a message that names what is
wrong; an exception escaping from inside numpy or scipy, or any other type, fails the test.
"""

from __future__ import annotations

import traceback
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import dda
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.materials import LinearElastic

PACKAGE = Path(dda.__file__).resolve().parent
CLEAR = (ValueError, TypeError, dda.SimulationError)
# derandomized: the same examples on every run, so CI cannot fail on a new draw; explore
# new ones with  pytest tests/test_api_fuzz.py --hypothesis-seed=N  (how the two bugs in
# tests/test_scene_validation.py and tests/test_step_control.py were found)
FUZZ = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])

# numbers as a careless script or a scene file may give them
any_number = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1e3, 1e3),
    st.integers(-10, 10),
    st.sampled_from([0, 0.0, -0.0, 1e-300, 1e300, "1.5", "abc", None, [1.0], True]),
)
coordinate = st.one_of(st.floats(-10, 10), st.sampled_from([np.nan, np.inf, 1e200, 0.0]))


def mostly(valid):
    """Usually a valid value, sometimes anything at all."""
    return st.one_of(valid, valid, valid, any_number)


@st.composite
def convex_polygons(draw):
    """A counter-clockwise convex polygon of 3 to 8 corners, any size and place."""
    n = draw(st.integers(3, 8))
    radius = draw(st.floats(1e-3, 1e3))
    cx, cy = draw(st.floats(-1e4, 1e4)), draw(st.floats(-1e4, 1e4))
    gaps = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=n, max_size=n)))
    angles = 2 * np.pi * np.cumsum(gaps) / gaps.sum()
    return [(cx + radius * np.cos(a), cy + radius * np.sin(a)) for a in angles]


def clear_error_or_value(fn):
    """Call ``fn``; return its value, or None after checking that it failed clearly."""
    try:
        value = fn()
        event("a result")
        return value
    except CLEAR as exc:
        event(f"a clear {type(exc).__name__}")
        origin = Path(traceback.extract_tb(exc.__traceback__)[-1].filename).resolve()
        assert PACKAGE in origin.parents, (
            f"{type(exc).__name__} escaped from {origin}, not from dda: {exc}")
        assert len(str(exc)) >= 15, f"an error that says too little: {exc!r}"
        return None


def _rock():
    return LinearElastic(young=1e9, poisson=0.2, density=2000.0)


def _joint():
    return JointMaterial(normal_penalty=1e9, shear_penalty=1e9, friction=CoulombSingle(phi=30))


@FUZZ
@given(points=st.one_of(st.lists(st.tuples(coordinate, coordinate), max_size=8),
                        convex_polygons()))
def test_random_polygons(points):
    scene = dda.Scene()
    block = clear_error_or_value(lambda: scene.add_block(points, _rock(), name="fuzz"))
    if block is not None:
        x, offsets = scene.vertex_arrays()
        assert np.all(np.isfinite(x)) and offsets[-1] >= 3


@FUZZ
@given(young=mostly(st.floats(1e3, 1e12)), poisson=mostly(st.floats(-0.99, 0.49)),
       density=mostly(st.floats(1.0, 1e4)))
def test_random_materials(young, poisson, density):
    mat = clear_error_or_value(lambda: LinearElastic(young=young, poisson=poisson,
                                                     density=density))
    if mat is not None:
        assert np.all(np.isfinite(mat.elasticity()))


@FUZZ
@given(pn=mostly(st.floats(1e3, 1e13)), ps=mostly(st.floats(1e3, 1e13)),
       phi=mostly(st.floats(0, 89)), phi_d=mostly(st.floats(0, 89)),
       cohesion=mostly(st.floats(0, 1e7)), law=st.sampled_from(["coulomb", "transition"]))
def test_random_joints(pn, ps, phi, phi_d, cohesion, law):
    def build():
        if law == "coulomb":
            friction = CoulombSingle(phi=phi, cohesion=cohesion)
        else:
            friction = StaticDynamicTransition(phi_static=phi, phi_dynamic=phi_d)
        return JointMaterial(normal_penalty=pn, shear_penalty=ps, friction=friction)

    clear_error_or_value(build)


@FUZZ
@given(dt=mostly(st.floats(1e-4, 0.1)), carry=mostly(st.floats(0, 1)),
       max_oc=mostly(st.integers(1, 20)), every=mostly(st.integers(1, 5)),
       ratio=mostly(st.floats(0.01, 1.0)),
       analysis=st.sampled_from(["dynamic", "static", "dynamic", "quasi", 3]),
       duration=mostly(st.floats(1e-4, 0.5)))
def test_random_simulation_arguments(dt, carry, max_oc, every, ratio, analysis, duration):
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)], _rock())

    def run():
        sim = dda.Simulation(scene, dt=dt, velocity_carry=carry, max_open_close=max_oc,
                             record_every=every, max_displacement_ratio=ratio,
                             analysis=analysis)
        # at most 50 steps, whatever dt is
        return sim.run(duration=min(float(duration), 50 * sim.dt))

    result = clear_error_or_value(run)
    if result is not None:
        assert np.all(np.isfinite(result.displacement(0)))


boxes = st.lists(
    st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(0.01, 2), st.floats(0.01, 2)),
    min_size=1, max_size=4,
)


@settings(FUZZ, max_examples=40)
@given(boxes=boxes, fixed=st.lists(st.booleans(), min_size=4, max_size=4),
       gravity=st.floats(-30, 30), dt=st.floats(1e-5, 0.2), steps=st.integers(1, 6),
       young=st.floats(1e6, 1e11), pn_ratio=st.floats(1e-3, 1e3),
       phi=st.floats(0, 80), speed=st.floats(-20, 20),
       solver=st.sampled_from(["legacy", "newton"]))
def test_random_scenes(boxes, fixed, gravity, dt, steps, young, pn_ratio, phi, speed, solver):
    """Random boxes (they may overlap, float apart or stack), properties and solvers."""
    rock = LinearElastic(young=young, poisson=0.25, density=2500.0)
    joint = JointMaterial(normal_penalty=pn_ratio * young, shear_penalty=pn_ratio * young,
                          friction=CoulombSingle(phi=phi))
    scene = dda.Scene(gravity=gravity)
    for i, (x, y, w, h) in enumerate(boxes):
        scene.add_block([(x, y), (x + w, y), (x + w, y + h), (x, y + h)], rock,
                        fixed=fixed[i], velocity=(speed, 0.0) if i == 0 else (0.0, 0.0))
    scene.set_joint(joint)
    make = {"legacy": dda.solvers.LegacyPullBack, "newton": dda.solvers.NewtonRaphson}[solver]

    def run():
        return dda.Simulation(scene, dt=dt, solver=make()).run(duration=steps * dt)

    result = clear_error_or_value(run)
    if result is not None:
        for i in range(len(boxes)):
            assert np.all(np.isfinite(result.displacement(i)))
            assert np.all(np.isfinite(result.velocity(i)))
            assert np.all(np.isfinite(result.stress(i)))
