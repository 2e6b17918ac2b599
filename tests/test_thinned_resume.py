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


def _interrupted(tmp_path, stop_at, error=KeyboardInterrupt, sim=None, **kw):
    """A run stopped by ``error`` after step ``stop_at``, then resumed from its checkpoint
    to the end; the writer's folder."""
    run = dda.Simulation(_scene(), dt=DT, solver="legacy", **(sim or {}))

    def stop(state, report):
        if run.control.steps == stop_at:
            raise error

    with pytest.raises(error):
        run.run(END, progress=False, output=VTUWriter(str(tmp_path / "I" / "v"), **kw),
                checkpoint=str(tmp_path / "I" / "run.ckpt"), checkpoint_every=50,
                callback=stop)
    return dda.Simulation.resume(str(tmp_path / "I" / "run.ckpt")).run(progress=False)


THINNINGS = [(1, {"every": 3}), (1, {"interval": 0.003}), (3, {"every": 2}),
             (3, {"interval": 0.004})]
IDS = ["every", "interval", "record_every-and-every", "record_every-and-interval"]


def _whole(tmp_path, record_every, thinning) -> np.ndarray:
    dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=record_every).run(
        END, progress=False, output=VTUWriter(str(tmp_path / "F" / "v"), **thinning))
    return _times(tmp_path / "F" / "v")


@pytest.mark.parametrize(("record_every", "thinning"), THINNINGS, ids=IDS)
@pytest.mark.parametrize(("stop_at", "error", "extra"),
                         [(101, KeyboardInterrupt, [0.1, 0.101]), (120, RuntimeError, [0.1])],
                         ids=["ctrl-c", "crash"])
def test_frames_after_a_stop_and_a_resume_are_the_uninterrupted_runs(
        tmp_path, record_every, thinning, stop_at, error, extra):
    """Resumed from the Ctrl-C's checkpoint, or from the last periodic one (step 100) after a
    run that died at step 120: the frames from step 100 on are the uninterrupted run's, the
    stop's and the resumed start's own beside them (with record_every 3, the run died at
    step 120 and record_every and every = 2 or interval = 4 ms, they came at 0.105, 0.111,
    ... for 0.102, 0.108, ...)."""
    whole = _whole(tmp_path, record_every, thinning)
    _interrupted(tmp_path, stop_at, error, sim={"record_every": record_every}, **thinning)
    resumed = _times(tmp_path / "I" / "v")
    late = resumed[resumed >= 0.1 - 1e-9]
    beside = np.setdiff1d(late, whole)
    assert set(beside) <= set(extra)
    assert np.array_equal(np.setdiff1d(whole[whole >= 0.1 - 1e-9], late), [])


@pytest.mark.parametrize(("record_every", "thinning"), THINNINGS, ids=IDS)
def test_a_run_that_goes_on_keeps_the_writers_cadence(tmp_path, record_every, thinning):
    whole = _whole(tmp_path, record_every, thinning)
    sim = dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=record_every)
    writer = VTUWriter(str(tmp_path / "S" / "v"), **thinning)
    sim.run(0.1, progress=False, output=writer)
    sim.run(0.1, progress=False, output=writer)
    split = _times(tmp_path / "S" / "v")
    assert set(np.setdiff1d(split, whole)) <= {0.1}  # the first run's end
    assert np.array_equal(np.setdiff1d(whole, split), [])


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


def test_a_writer_of_write_and_close_alone_gets_every_recorded_frame():
    """The writer protocol's least: write(frame) and close(). A run's end beside
    record_every's cadence was handed to it as write(frame, last=True): a TypeError, the
    run's result lost."""
    class Frames:
        def __init__(self):
            self.times = []

        def write(self, frame):
            self.times.append(round(frame.time, 9))

        def close(self):
            pass

    writer = Frames()
    sim = dda.Simulation(_scene(), dt=DT, solver="legacy", record_every=3)
    result = sim.run(0.010, progress=False, output=writer)
    assert writer.times == [0.0, 0.003, 0.006, 0.009, 0.01]
    np.testing.assert_allclose(result.time, writer.times)
