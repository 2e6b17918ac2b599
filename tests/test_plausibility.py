"""Plausibility warnings (dda.plausibility; issue 22, item 1): valid input that is most likely a
typing mistake gets one warning that names it and the mistake; sensible input gets none; the
run goes on; numbers typed as text are refused at once."""

import warnings

import numpy as np
import pytest

import dda
from dda.contact import BartonBandis, CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.io.scene_file import load_scene
from dda.materials import LinearElastic
from tests.conftest import box
from tests.test_scene_file import FULL, write


def caught(make):
    """The plausibility warnings ``make()`` gives (and its result)."""
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        out = make()
    return [str(w.message) for w in got if w.category is dda.PlausibilityWarning], out


@pytest.mark.parametrize("make, words", [
    (lambda: CoulombSingle(phi=0.52), ["CoulombSingle: phi = 0.52 degrees looks like radians "
                                       "(0.52 rad = 29.8 degrees)"]),
    (lambda: StaticDynamicTransition(0.7, 0.6), ["phi_static = 0.7 degrees looks like radians",
                                                  "phi_dynamic = 0.6 degrees looks like"]),
    (lambda: BartonBandis(jrc=8, jcs=40e6, phi_r=0.5), ["phi_r = 0.5 degrees looks like"]),
    (lambda: dda.Scene(gravity=-9.81), ["gravity = -9.81 m/s^2 points up"]),
    (lambda: dda.Scene(gravity=9810.0), ["gravity = 9810 m/s^2 is orders of magnitude off"]),
    (lambda: LinearElastic(young=5000.0, poisson=0.2, density=2500.0),
     ["young = 5000 Pa is orders of magnitude below rock", "5000 MPa = 5e+09 Pa"]),
    (lambda: LinearElastic(young=1e9, poisson=0.2, density=26.0),
     ["density = 26 kg/m^3 is far below rock", "kN/m^3 (26 kN/m^3 is 2,650 kg/m^3)"]),
])
def test_a_likely_mistake_gets_one_warning_naming_it(make, words):
    got, _ = caught(make)
    assert len(got) == (2 if "phi_dynamic" in " ".join(words) else 1), got  # one an input
    text = " | ".join(got)
    for w in words:
        assert w in text


@pytest.mark.parametrize("make", [
    lambda: CoulombSingle(phi=30.0), lambda: CoulombSingle(phi=0.0),
    lambda: StaticDynamicTransition(40.0, 31.6), lambda: dda.Scene(gravity=9.81),
    lambda: dda.Scene(), lambda: LinearElastic(young=14.9e9, poisson=0.2, density=2198.0),
    lambda: LinearElastic(young=2e6, poisson=0.3, density=1800.0),  # a soft soil
])
def test_sensible_input_gets_none(make):
    assert caught(make)[0] == []


def test_a_shake_direction_that_is_not_a_unit_vector(tmp_path):
    sine = 'sine = { amplitude = 2.0, frequency = 2.0, start = 0.01 }'
    text = FULL.replace(sine, sine[:-2] + ', direction = [2.0, 0.0] }')
    assert text != FULL
    got, _ = caught(lambda: load_scene(write(tmp_path, text)))
    assert any("scene.toml, shake[0].sine: direction = [2.0, 0.0] has length 2, not 1: it "
               "multiplies the amplitude by 2" in g for g in got), got
    unit = FULL.replace(sine, sine[:-2] + ', direction = [0.6, 0.8] }')
    assert caught(lambda: load_scene(write(tmp_path, unit, "unit.toml")))[0] == []


def _small_block_scene():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, -0.5, 2, 0.5), rock, fixed=True)
    scene.add_block(box(0.5, 0.0, 0.05, 0.05), rock, name="pebble")
    scene.set_joint(JointMaterial(1e11, 1e11, CoulombSingle(phi=30.0)))
    return scene


def test_a_step_that_skips_a_hundred_contact_periods():
    got, _ = caught(lambda: dda.Simulation(_small_block_scene(), dt=0.05))
    assert len(got) == 1
    assert "dt = 0.05 s is" in got[0] and "times the period of block 'pebble'" in got[0]
    assert "dt='auto'" in got[0]
    assert caught(lambda: dda.Simulation(_small_block_scene(), dt=1e-4))[0] == []


def test_a_static_analysis_has_no_contact_period():
    """A static step solves for equilibrium (no velocity carried): a long step is what it is
    for, and the pebble's 20 steps of 1,000 periods each settle without a cut."""
    got, result = caught(lambda: dda.Simulation(_small_block_scene(), dt=0.05,
                                                analysis="static").run(1.0, progress=False))
    assert got == []
    assert len(result.time) == 21 and result.stats.cuts == []


def test_warnings_never_stop_a_run():
    def run():
        rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
        scene = dda.Scene(gravity=9.81)
        scene.add_block(box(0, -0.5, 2, 0.5), rock, fixed=True)
        top = scene.add_block(box(0.5, 0.0, 0.3, 0.3), rock)
        scene.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(phi=0.52)))
        return dda.Simulation(scene, dt=1e-3).run(0.01), top

    got, (result, top) = caught(run)
    assert len(got) == 1
    assert result.time[-1] == pytest.approx(0.01)
    assert result.displacement(top).shape == (len(result.time), 2)


@pytest.mark.parametrize("make, words", [
    (lambda: LinearElastic(young="10e9", poisson=0.2, density=2500.0),
     "LinearElastic: young must be a number, got the text '10e9'"),
    (lambda: CoulombSingle(phi="30"), "CoulombSingle: phi must be a number, got the text"),
    (lambda: dda.Scene(gravity="9.81"), "Scene: gravity must be a number, got the text"),
])
def test_numbers_typed_as_text_are_refused_at_once(make, words):
    with pytest.raises(ValueError, match=words):
        make()


def test_a_scene_files_warnings_name_its_line(tmp_path):
    text = FULL.replace("density = 2500.0", "density = 26.0", 1)
    got, _ = caught(lambda: load_scene(write(tmp_path, text)))
    assert any(g.startswith("scene.toml, line 5, materials.rock: LinearElastic: density = 26")
               for g in got), got


def _shaken_block(penalty, freq=10.0, acceleration=None):
    """A 1 x 0.5 m block (1,250 kg/m) on a shaken table, a sine of ``freq`` Hz (or
    ``acceleration``)."""
    rock = LinearElastic(young=1e10, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    table = scene.add_block(box(0, 0, 3, 0.5), rock, fixed=True, name="table")
    scene.add_block(box(1, 0.5, 1, 0.5), rock, name="block")
    scene.set_joint(JointMaterial(penalty, penalty, CoulombSingle(phi=30.0)))
    scene.shake(table, acceleration=acceleration or (
        lambda t: (3.0 * np.sin(2 * np.pi * freq * t), 0.0)))
    return scene


@pytest.mark.parametrize("solver, steps, auto", [("newton", 8.35, 167), ("legacy", 20.0, 400)])
def test_a_step_that_cannot_follow_the_shaking_is_warned_of(solver, steps, auto):
    """Fewer steps a period of the shaking than a twentieth of what dt="auto" takes (167
    Newton, 400 legacy DDA): under a 12 Hz record at 4 steps a period a block's slip erred
    +2.4% (Newton) and -18 to -28% (legacy), at 1.7 steps +32% and -78 to -98%, unsaid."""
    coarse = 1.0 / (10.0 * steps * 0.95)
    got, _ = caught(lambda: dda.Simulation(_shaken_block(1e9), dt=coarse, solver=solver))
    assert len(got) == 1, got
    assert (f"dt = {coarse:g} s takes {steps * 0.95:.2g} steps a period of the shaking's 10 Hz"
            in got[0] and f"where dt='auto' takes {auto} for {solver}" in got[0]), got
    fine = 1.0 / (10.0 * steps * 1.05)
    assert caught(lambda: dda.Simulation(_shaken_block(1e9), dt=fine, solver=solver))[0] == []
    auto = caught(lambda: dda.Simulation(_shaken_block("auto"), dt="auto", solver=solver))
    assert auto[0] == []


def test_a_penalty_that_rides_the_shaking_is_warned_of():
    """A contact frequency within 3 times the shaking's: a 1,250 kg block on 1e7 N/m (14 Hz)
    under 10 Hz; at 4e8 N/m (90 Hz) nothing is said."""
    got, _ = caught(lambda: dda.Simulation(_shaken_block(1e7), dt=1e-3))
    assert len(got) == 1 and "a penalty of 1e+07 N/m lets block 'block'" in got[0], got
    assert "contact frequency, 14.2 Hz, is within 3 times the shaking's 10 Hz" in got[0]
    assert caught(lambda: dda.Simulation(_shaken_block(4e8), dt=1e-3))[0] == []


def test_the_shaking_check_calls_a_python_shaking_a_few_thousand_times_at_most():
    """It sampled a callable over 20 s at 1 kHz: 20,000 calls, 33.7 s at 1 ms a call."""
    calls = []

    def table(t):
        calls.append(t)
        return (3.0 * np.sin(2 * np.pi * 10.0 * t), 0.0)

    scene = _shaken_block(1e9, acceleration=table)
    calls.clear()
    dda.Simulation(scene, dt=1e-3)
    assert 0 < len(calls) <= 4100
    # ... over the auto rule's 20 s: a shaking that starts at 3 s is seen (over the first
    # 2 s it was not)
    late = _shaken_block(1e9, acceleration=lambda t: (
        3.0 * np.sin(2 * np.pi * 10.0 * t) * (t > 3.0), 0.0))
    got, _ = caught(lambda: dda.Simulation(late, dt=0.05))
    assert len(got) == 1 and "of the shaking's 10" in got[0], got


def test_a_soft_joint_between_two_blocks_is_judged_on_their_reduced_mass():
    """A 1e6 N/m pad under a 0.1 m block (25 kg/m) on a 2 m block that rests on 1e10 N/m:
    the pad's frequency is the small block's, 32 Hz, above 3 x 2 Hz; it was judged with the
    2 m block's 10 t (1.6 Hz) and the 2 m block told to take 1.4e7 N/m. On a 10 Hz table the
    small block does ride its pad, and is named."""
    def scene(freq):
        s = dda.Scene(gravity=9.81)
        table = s.add_block(box(-2, -1, 6, 1), ROCK_10, fixed=True, name="table")
        big = s.add_block(box(0, 0, 2, 2), ROCK_10, name="big")
        small = s.add_block(box(0.9, 2, 0.1, 0.1), ROCK_10, name="small")
        s.set_joint(JointMaterial(1e10, 1e10, CoulombSingle(phi=35.0)))
        s.set_joint(JointMaterial(1e6, 1e6, CoulombSingle(phi=35.0)), between=(big, small))
        s.shake(table, acceleration=lambda t: (2.0 * np.sin(2 * np.pi * freq * t), 0.0))
        return s

    assert caught(lambda: dda.Simulation(scene(2.0), dt=1e-3))[0] == []
    got, _ = caught(lambda: dda.Simulation(scene(12.0), dt=1e-3))
    assert len(got) == 1 and "lets block 'small'" in got[0], got


ROCK_10 = LinearElastic(young=1e10, poisson=0.2, density=2500.0)
