"""A thinned record (``record_every``, ``VTUWriter(every=...)`` or ``interval``) keeps the
cadence of a run never stopped across a stop, a resume and a run that goes on: the frames
and rows after it are the uninterrupted run's, plus the stop's own frame.

Before: a Ctrl-C's last frame, counted when it was skipped and again when the stop wrote it,
put every later frame one step late; ``record_every``'s count was not in the checkpoint, so
a resumed run counted from its start (rows at 0.100, 0.103, ... for 0.102, 0.105, ...)."""

import re

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.io import VTUWriter
from dda.materials import LinearElastic
from tests.conftest import box

DT, END = 1e-3, 0.2


def _scene():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    s = dda.Scene(gravity=9.81)
    s.add_block(box(-1, -0.3, 3, 0.3), rock, fixed=True)
    s.add_block(box(0, 0, 0.4, 0.4), rock)
    s.set_joint(JointMaterial(1e9, 1e9, CoulombSingle(35.0)))
    return s


def _times(prefix) -> np.ndarray:
    text = open(f"{prefix}.pvd").read()
    return np.round([float(t) for t in re.findall(r'timestep="([^"]+)"', text)], 9)


def _interrupted(tmp_path, stop_at, error=KeyboardInterrupt, **kw):
    """A run stopped by ``error`` after step ``stop_at``, then resumed from its checkpoint
    to the end; the writer's folder."""
    sim = dda.Simulation(_scene(), dt=DT, solver="legacy", **kw.pop("sim", {}))

    def stop(state, report):
        if sim.control.steps == stop_at:
            raise error

    with pytest.raises(error):
        sim.run(END, progress=False, output=VTUWriter(str(tmp_path / "I" / "v"), **kw),
                checkpoint=str(tmp_path / "I" / "run.ckpt"), checkpoint_every=50,
                callback=stop)
    return dda.Simulation.resume(str(tmp_path / "I" / "run.ckpt")).run(progress=False)


@pytest.mark.parametrize("thinning", [{"every": 3}, {"interval": 0.003}],
                         ids=["every", "interval"])
def test_frames_after_a_ctrl_c_and_a_resume_are_the_uninterrupted_runs(tmp_path, thinning):
    dda.Simulation(_scene(), dt=DT, solver="legacy").run(
        END, progress=False, output=VTUWriter(str(tmp_path / "F" / "v"), **thinning))
    _interrupted(tmp_path, 101, **thinning)
    whole, resumed = _times(tmp_path / "F" / "v"), _times(tmp_path / "I" / "v")
    assert np.array_equal(np.setdiff1d(resumed, whole), [0.101])  # the stop's own frame
    assert np.array_equal(np.setdiff1d(whole, resumed), [])


def test_rows_resumed_from_a_periodic_checkpoint_keep_record_every(tmp_path):
    """A run that died after step 120 (its last checkpoint: step 100) resumes there and
    records the steps the uninterrupted run records."""
    whole = dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=3).run(
        END, progress=False)
    resumed = _interrupted(tmp_path, 120, error=RuntimeError, sim={"record_every": 3})
    assert resumed.time[0] == pytest.approx(0.1)
    np.testing.assert_array_equal(np.round(resumed.time[1:], 9),
                                  np.round(whole.time[whole.time > 0.1 + DT / 2], 9))


def test_a_run_that_goes_on_keeps_record_every(tmp_path):
    whole = dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=3).run(
        END, progress=False)
    sim = dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=3)
    first = sim.run(0.1, progress=False)
    second = sim.run(0.1, progress=False)
    assert first.time[-1] == second.time[0] == pytest.approx(0.1)  # each run's ends
    np.testing.assert_array_equal(np.round(second.time[1:], 9),
                                  np.round(whole.time[whole.time > 0.1 + DT / 2], 9))
