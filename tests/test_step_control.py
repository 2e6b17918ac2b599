"""Trial / commit / revert: failed steps leave no trace and are retried with a smaller dt."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic
from dda.solvers import NewtonRaphson
from tests.conftest import box, shaken_block_scene

ROCK = LinearElastic(young=1e9, poisson=0.2, density=2000.0)


class FailsAboveDt(NewtonRaphson):
    """Newton-Raphson that refuses any step longer than ``limit`` (a step that diverges)."""

    def __init__(self, limit):
        super().__init__()
        self.limit = limit
        self.refused = 0

    def solve_step(self, problem):
        if problem.dt > self.limit * (1 + 1e-12):
            self.refused += 1
            return dda.solvers.StepSolution(None, None, False, reason="too long a step")
        return super().solve_step(problem)


def test_failed_steps_are_reverted_and_retried_with_half_the_step():
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)
    reference = dda.Simulation(scene, dt=2.5e-4, solver=NewtonRaphson()).run(0.2)
    solver = FailsAboveDt(limit=2.5e-4)
    result = dda.Simulation(scene, dt=1e-3, solver=solver).run(0.2)
    assert solver.refused > 0
    cuts = result.stats.cuts
    assert cuts and all(reason == "too long a step" for _, _, reason in cuts)
    assert {dt for _, dt, _ in cuts} <= {1e-3, 5e-4}
    # dt grows back after quiet steps, so cuts happen more than once, and never below 2.5e-4
    assert result.stats["dt"].min() == pytest.approx(2.5e-4)
    assert result.stats["dt"].max() == pytest.approx(2.5e-4)
    # a refused try leaves nothing behind: the run equals one made at 2.5e-4 from the start
    # (the shaking history is integrated again from the committed time)
    np.testing.assert_allclose(result.displacement(top)[-1], reference.displacement(top)[-1],
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(result.displacement(table)[-1],
                               reference.displacement(table)[-1], rtol=0, atol=1e-15)


def test_a_run_that_cannot_go_on_says_when_and_why_and_keeps_its_steps(tmp_path):
    scene, table, top = shaken_block_scene(phi=20, amplitude=6.0)

    class GivesUpLater(NewtonRaphson):
        def solve_step(self, problem):
            if problem.element.contacts is not None and self.calls >= 50:
                return dda.solvers.StepSolution(None, None, False, reason="a wall")
            self.calls += 1
            return super().solve_step(problem)

    solver = GivesUpLater()
    solver.calls = 0
    writer = dda.io.VTUWriter(tmp_path / "case")
    sim = dda.Simulation(scene, dt=1e-3, solver=solver)
    with pytest.raises(dda.SimulationError, match=r"cannot go on at t = 0.05 s: a wall") as info:
        sim.run(0.2, output=writer)
    partial = info.value.result
    assert len(partial.time) == 51  # the start and the 50 steps done
    assert partial.time[-1] == pytest.approx(0.05)
    assert writer.pvd_path.exists() and len(writer.files) == 51
    assert sim.state.time == pytest.approx(0.05)  # the committed state is the last good one


def test_a_step_that_moves_a_block_too_far_is_cut_and_dt_grows_back():
    """A block shot along a rough floor at 5 m/s: dt 0.05 s would move it 1.25 sizes per
    step. Steps are cut until it moves at most a tenth of its size, and grow back to the full
    dt once it has slowed down."""
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.5, 12, 0.5), rock, fixed=True)
    shot = scene.add_block(box(0, 0, 0.2, 0.2), rock, velocity=(5.0, 0.0), name="shot")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=30.0)))
    sim = dda.Simulation(scene, dt=0.05, max_displacement_ratio=0.1)
    result = sim.run(1.5)
    reasons = [c[2] for c in result.stats.cuts]
    # (the first, longest tries also fail to converge; those cuts say so)
    assert any("'shot' moved" in r and "max_displacement_ratio 0.1" in r for r in reasons)
    step_moves = np.hypot(*np.diff(result.displacement(shot)[:, :2], axis=0).T)
    assert step_moves.max() <= 0.1 * 0.2 * (1 + 1e-9)
    dt = np.asarray(result.stats.dt)
    assert dt.min() < 0.01 and dt[-3] == pytest.approx(0.05)  # cut, then grown back
    # and it stops where Coulomb says: v^2 / (2 mu g)
    stop = 25.0 / (2 * np.tan(np.radians(30.0)) * 9.81)
    assert result.displacement(shot)[-1, 0] == pytest.approx(stop, rel=0.02)
    with pytest.raises(ValueError, match="max_displacement_ratio"):
        dda.Simulation(scene, dt=0.05, max_displacement_ratio=0.0)



@pytest.mark.parametrize("solver", [dda.solvers.LegacyPullBack, NewtonRaphson])
def test_blocks_built_touching_are_tried_closed_first(solver):
    """Contacts touching at the start of a step are first tried closed. Tried open, a wall
    built touching falls freely in the first pass and closes row by row from the bottom: its
    first step took 11 passes and was cut (1000 bricks: more than max_open_close at any dt)."""
    rock = LinearElastic(young=10e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-0.5, -0.3, 2.7, 0.3), rock, fixed=True)
    for r in range(30):
        for c in range(3):
            scene.add_block(box(0.2 * (r % 2) + 0.4 * c, 0.2 * r, 0.4, 0.2), rock)
    scene.set_joint(JointMaterial(normal_penalty=1e10, shear_penalty=1e10,
                                  friction=CoulombSingle(phi=35.0)))
    result = dda.Simulation(scene, dt=1e-3, solver=solver()).run(3e-3)
    st = result.stats
    assert len(st.cuts) == 0
    assert st["open_close_passes"][0] <= 7
    assert st["closed"][-1] > 300  # of 416 vertex-edge pairs
