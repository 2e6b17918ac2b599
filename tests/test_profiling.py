"""The cost profile: exclusive section timers, per-step stats and Result.profile()."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import dda
from dda import profiling
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from dda.profiling import SECTIONS, StepProfile, section

ROCK = LinearElastic(young=1e9, poisson=0.2, density=2000.0)


class FakeClock:
    """perf_counter that advances by one second per call."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        self.now += 1.0
        return self.now


def test_nested_sections_count_their_time_once(monkeypatch):
    monkeypatch.setattr(profiling, "perf_counter", FakeClock())
    p = StepProfile()
    with p.active():
        with section("assembly"):  # reads the clock at 1 and at 6
            with section("solve"):  # 2 and 3
                pass
            with section("return_map"):  # 4 and 5
                pass
    assert p.seconds["solve"] == 1.0
    assert p.seconds["return_map"] == 1.0
    assert p.seconds["assembly"] == 5.0 - 2.0  # its own time only
    assert sum(p.seconds.values()) == 5.0  # the outer section's wall time


def test_sections_without_an_active_profile_do_nothing():
    p = StepProfile()
    with section("solve"):
        pass
    assert p.seconds["solve"] == 0.0


def test_unknown_section_is_an_error():
    with pytest.raises(ValueError, match="unknown section 'factorization'"):
        section("factorization")


def test_threads_keep_their_own_profile(monkeypatch):
    profiles = [StepProfile() for _ in range(4)]
    barrier = threading.Barrier(4)

    def work(p, name):
        with p.active():
            barrier.wait()
            with section(name):
                barrier.wait()

    names = ["solve", "assembly", "detection", "return_map"]
    threads = [threading.Thread(target=work, args=(p, n)) for p, n in zip(profiles, names,
                                                                         strict=True)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for p, name in zip(profiles, names, strict=True):
        assert p.seconds[name] > 0.0
        assert all(v == 0.0 for k, v in p.seconds.items() if k != name)


def block_on_base():
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block([(0, 0), (2, 0), (2, 0.5), (0, 0.5)], ROCK, fixed=True)
    scene.add_block([(0.5, 0.5), (1.5, 0.5), (1.5, 1.0), (0.5, 1.0)], ROCK,
                    velocity=(0.5, 0.0))
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=20.0)))
    return scene, base


@pytest.mark.parametrize("mode", ["composed", "one call", "small step"])
@pytest.mark.parametrize("solver", [dda.solvers.LegacyPullBack, dda.solvers.NewtonRaphson])
def test_step_stats_hold_the_parts_and_the_counts(solver, mode, monkeypatch):
    """Every section is timed in every step; with a dense system's OPEN-CLOSE and Newton
    iterations in one kernel call (``one call``) their return maps and assembly are the
    ``solve`` section's, and a small scene's common step (``small step``: every step here but
    the first, which starts without contacts) is ``solve`` from its detection to its guard
    (:mod:`dda.kernels.small_step`)."""
    from dda import step
    from dda.solvers import newton, open_close

    monkeypatch.setattr(open_close, "DENSE_PASSES", mode != "composed")
    monkeypatch.setattr(newton, "DENSE_NEWTON", mode != "composed")
    monkeypatch.setattr(step, "SMALL_STEP", mode == "small step")
    scene, _ = block_on_base()
    result = dda.Simulation(scene, dt=1e-3, solver=solver()).run(0.05)
    st = result.stats
    parts = np.sum([st[f"{name}_time"] for name in SECTIONS], axis=0)
    assert np.all(parts > 0.0)
    assert np.all(parts <= st["wall_time"])
    folded = {"composed": set(), "one call": {"return_map", "assembly"},
              "small step": {"return_map", "assembly", "detection", "contact_element",
                             "guard"}}[mode]
    later = slice(1, None) if mode == "small step" else slice(None)
    for name in SECTIONS:
        if name not in folded:
            assert np.all(st[f"{name}_time"][later] > 0.0), name
        elif mode == "small step":
            assert np.all(st[f"{name}_time"][later] == 0.0), name
    if mode != "composed" and solver is dda.solvers.LegacyPullBack:  # the step's friction
        assert np.all(st["return_map_time"] == 0.0)
    # every OPEN-CLOSE pass solves once; Newton adds one solve per iteration
    expected = st["open_close_passes"] + (st["iterations"] if solver is
                                          dda.solvers.NewtonRaphson else 0)
    np.testing.assert_array_equal(st["solves"], expected)
    assert np.all(st["contacts"] == 2)

    prof = result.profile()
    assert prof.steps == len(st) == 50
    assert prof.solves == st["solves"].sum()
    assert prof.contacts_max == 2
    assert prof.wall == pytest.approx(st["wall_time"].sum())
    assert sum(prof.fractions().values()) == pytest.approx(1.0)
    text = str(prof)
    for name in (*SECTIONS, "other"):
        assert name in text
    assert prof.summary.startswith("50 steps")


def test_a_scene_without_free_blocks_solves_nothing():
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)], ROCK, fixed=True)
    result = dda.Simulation(scene, dt=1e-2).run(0.05)
    assert result.stats["solves"].sum() == 0
    assert result.stats["solve_time"].sum() == 0.0
    assert result.profile().solves == 0


def test_the_profile_tells_the_kernels_start_up_from_the_steps():
    # (a fresh install's first run booked minutes of numba compiling under "solve"; a
    # process's first run also loads the kernels from numba's cache)
    import subprocess
    import sys

    script = """
import dda
from tests.stability import scenes
from dda.contact import CoulombSingle
scene = scenes.incline(CoulombSingle(phi=30.0))[0]
first = dda.Simulation(scene, dt=1e-3, solver="legacy").run(0.02, progress=False)
again = dda.Simulation(scene, dt=1e-3, solver="legacy").run(0.02, progress=False)
print(first.stats.kernel_time, first.profile().wall, again.stats.kernel_time)
print(first.profile())
"""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=root, timeout=600)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    first, wall, again = (float(v) for v in out.splitlines()[0].split())
    assert 0.0 < first, out
    assert again == 0.0, out
    assert "numba compiled its kernels or loaded them" in out, out
