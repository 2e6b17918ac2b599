"""Runs of small steps in one kernel call (dda.compiled_run, dda.kernels.run_steps) against
the same runs step by step: the same records, stats, state and step control to the bit, batches
taken where they should be and not where a run needs every step in Python."""

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import dda
import dda.compiled_run as compiled_run
from dda.contact import BartonBandis, CoulombSingle, StaticDynamicTransition
from dda.penalty_advice import PenaltyWarning
from dda.progress import ProgressBar
from dda.solvers import LegacyPullBack, NewtonRaphson
from tests.conftest import incline_scene, stack_scene
from tests.stability import scenes

SOLVERS = {"legacy": LegacyPullBack, "newton": NewtonRaphson}


def _incline(law, kick=1.0):
    return scenes.incline(law, kick=kick)[0], 1e-3, 0.4


def _stability(name):
    made = getattr(scenes, name)()
    if len(made) == 4:  # (scene, dt, duration, work)
        return made[:3]
    return made[0], 1e-3, made[1]  # the impacts: (scene, duration) at dt 1e-3


def _moving_base():  # a block on a shaken table (a callable acceleration, integrated)
    from dda.studies.cases import moving_base

    return moving_base()[0], 1e-3, 0.5


def _dragged():  # a block on a base moved in full by a displacement history
    scene = stack_scene(1)
    scene.prescribe_motion(0, lambda t: (0.02 * np.sin(2 * np.pi * 3.0 * t), 0.0))
    return scene, 1e-3, 0.4


CASES = {
    "coulomb incline": lambda: _incline(CoulombSingle(phi=30.0)),
    # kicked uphill: it stops and turns (a slip reversal located)
    "incline kicked up": lambda: _incline(CoulombSingle(phi=20.0), kick=-1.0),
    "transition by faces": lambda: _incline(StaticDynamicTransition(35.0, 25.0)),
    "stack 3x3": lambda: (stack_scene(3), 1e-3, 0.15),
    # blocks that land, bounce and settle: refused steps and located reversals between the
    # batches
    "block on block": lambda: _stability("block_on_block"),
    "ell on a step": lambda: _stability("ell_on_a_step"),
    "lip": lambda: _stability("lip"),
    "moving base": _moving_base,
    "dragged by its base": _dragged,
    # a rigid block (3 unknowns; its strain velocities held at zero)
    "rigid block sliding": lambda: (incline_scene(25.0, rigid=True)[0], 1e-3, 0.3),
}


def _run(make, solver, on, monkeypatch, **kw):
    """(simulation, result, steps taken in batches) of one case."""
    monkeypatch.setattr(compiled_run, "COMPILED_RUN", on)
    batched = []
    advance = compiled_run.StepRuns.advance

    def counted(self, *a, **k):
        n = advance(self, *a, **k)
        batched.append(n)
        return n

    monkeypatch.setattr(compiled_run.StepRuns, "advance", counted)
    scene, dt, duration = make()
    run_kw = {k: kw.pop(k) for k in ("progress", "callback", "checkpoint", "checkpoint_every")
              if k in kw}
    sim = dda.Simulation(scene, dt=dt, solver=SOLVERS[solver](), **kw)
    result = sim.run(duration, **{"progress": False, **run_kw})
    return sim, result, sum(batched)


def _everything(sim, result) -> dict:
    """What a run leaves: every recorded step, every stats column but the timings, the
    committed state and the step control's counts."""
    st = result.stats
    out = {f"stats {k}": np.asarray(st[k]) for k in st.FIELDS if not k.endswith("_time")}
    out["cuts"] = np.array([(t, dt) for t, dt, _ in st.cuts]).reshape(-1, 2)
    out["cut reasons"] = [r for _, _, r in st.cuts]
    out["reversals"] = np.array(st.reversals).reshape(-1, 2)
    out["residual norms"] = [list(map(float, n)) for n in st.residual_norms]
    out["time"] = result.time
    for b in range(len(sim.scene.blocks)):
        for name in ("displacement", "rotation", "velocity", "stress"):
            out[f"{name} {b}"] = getattr(result, name)(b)
    for i, (keys, force, normal) in enumerate(result._pairs):
        out[f"pairs {i}"] = (keys, force, normal)
    s = sim.committed
    for k in ("time", "x", "velocity", "stress", "rotation", "centroid", "last_move",
              "untracked", "penetration"):
        out[f"state {k}"] = getattr(s, k)
    c = s.contacts
    for k in ("vertex", "edge", "bj", "bk", "state", "xi0", "t_n", "t_s", "held_ago"):
        out[f"contacts {k}"] = getattr(c, k)
    for k, v in c.history.items():
        out[f"history {k}"] = v
    ctl = sim.control
    out["control"] = (ctl.steps, ctl.good_steps, ctl.reversal_wait, ctl.contact_cuts,
                      ctl.dt_now, ctl.wait, ctl.probing, ctl.ceiling)
    out["warned"] = sorted(sim.advisor.warned)
    return out


def _assert_same(a: dict, b: dict):
    assert a.keys() == b.keys()
    for k in a:
        x, y = a[k], b[k]
        if isinstance(x, tuple) and x and isinstance(x[0], np.ndarray):
            for u, v in zip(x, y, strict=True):
                np.testing.assert_array_equal(u, v, err_msg=k)
        elif isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, k
            np.testing.assert_array_equal(x, y, err_msg=k)
        else:
            assert x == y, k


@pytest.mark.parametrize("solver", ["legacy", "newton"])
@pytest.mark.parametrize("case", list(CASES))
def test_batches_give_the_steps_one_by_one_to_the_bit(case, solver, monkeypatch):
    one = _everything(*_run(CASES[case], solver, False, monkeypatch)[:2])
    sim, result, batched = _run(CASES[case], solver, True, monkeypatch)
    assert batched >= 10  # (else this compares the step-by-step run with itself)
    _assert_same(one, _everything(sim, result))


def test_records_every_third_step_and_a_partial_carry(monkeypatch):
    kw = {"record_every": 3, "velocity_carry": 0.8}
    make = CASES["coulomb incline"]
    one = _everything(*_run(make, "newton", False, monkeypatch, **kw)[:2])
    sim, result, batched = _run(make, "newton", True, monkeypatch, **kw)
    assert batched >= 100
    assert len(result.time) < len(result.stats) / 2
    # the profile says which steps it cannot split into parts
    assert result.stats.batched == batched
    assert f"{batched} of the {len(result.stats)} steps in batches" in str(result.profile())
    _assert_same(one, _everything(sim, result))


def test_the_soft_spring_warning_comes_at_the_same_step(monkeypatch):
    """A penalty so soft that a block sinks: the batch stops after the step whose largest
    normal force fails the advisor's quick test, and the warning is the step-by-step run's."""

    def soft():
        scene = stack_scene(1)
        scene.set_joint(replace(scene.default_joint, normal_penalty=2e5, shear_penalty=2e5))
        return scene, 1e-3, 0.3

    caught = {}
    for on in (False, True):
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            sim, result, batched = _run(soft, "legacy", on, monkeypatch)
        caught[on] = ([str(x.message) for x in w if x.category is PenaltyWarning],
                      _everything(sim, result), batched)
    assert caught[True][2] > 0
    assert caught[False][0] and caught[False][0] == caught[True][0]
    _assert_same(caught[False][1], caught[True][1])


def test_no_batch_where_the_run_needs_every_step(monkeypatch, tmp_path):
    """A callback or a writer of every step sees every step; a static analysis, or a scene
    whose steps are not taken in one kernel call (a law without a kernel), takes no batch."""
    make = CASES["coulomb incline"]
    calls = []
    _, result, batched = _run(make, "legacy", True, monkeypatch,
                              callback=lambda state, report: calls.append(state.time))
    assert batched == 0 and len(calls) == len(result.stats)
    _, _, batched = _run(make, "legacy", True, monkeypatch, output=dda.io.VTUWriter(
        tmp_path / "out"))
    assert batched == 0
    _, _, batched = _run(make, "legacy", True, monkeypatch, analysis="static")
    assert batched == 0
    _, _, batched = _run(lambda: _incline(BartonBandis(jrc=10.0, jcs=50e6, phi_r=28.0)),
                         "legacy", True, monkeypatch)
    assert batched == 0


def test_a_run_that_checkpoints_takes_batches_between_its_checkpoints(monkeypatch, tmp_path):
    """A batch stops before each step after which the run writes its checkpoint, and the run
    takes that step itself: the checkpoints come at the same steps, and hold the same
    states, as step by step, and half a run resumed from its checkpoint ends as one
    simulation run for two halves (on the 2-block incline of ``benchmarks/small_step.py``,
    6,000 steps with a checkpoint every 1,000: 134 us a step without batches, 31 with them,
    28 without checkpoints)."""
    make = CASES["coulomb incline"]
    saved = {}
    save = dda.Simulation.save_checkpoint

    def spy(self, path, *a, **k):
        saved.setdefault(Path(path).parent.name, []).append(
            (self.control.steps, self.committed.x.copy()))
        return save(self, path, *a, **k)

    monkeypatch.setattr(dda.Simulation, "save_checkpoint", spy)
    runs = {}
    for on in (False, True):
        folder = tmp_path / ("batches" if on else "one by one")
        sim, result, batched = _run(make, "legacy", on, monkeypatch,
                                    checkpoint=folder / "run.ckpt", checkpoint_every=25)
        runs[on] = _everything(sim, result)
        assert (batched >= 100) == on, batched
    _assert_same(runs[False], runs[True])
    one, batches = saved["one by one"], saved["batches"]
    assert [n for n, _ in one] == [n for n, _ in batches] and len(one) >= 5
    for (_, a), (_, b) in zip(one, batches, strict=True):
        np.testing.assert_array_equal(a, b)
    # half a run with checkpoints, resumed from its last and run on for the other half: the
    # end of one simulation run for two halves, to the bit
    scene, dt, duration = make()
    halves = dda.Simulation(scene, dt=dt, solver=SOLVERS["legacy"]())
    halves.run(0.5 * duration, progress=False)
    halves.run(0.5 * duration, progress=False)
    half = dda.Simulation(make()[0], dt=dt, solver=SOLVERS["legacy"]())
    half.run(0.5 * duration, progress=False, checkpoint=tmp_path / "half.ckpt",
             checkpoint_every=25)
    resumed = dda.Simulation.resume(tmp_path / "half.ckpt")
    resumed.run(0.5 * duration, progress=False)
    np.testing.assert_array_equal(resumed.committed.x, halves.committed.x)
    np.testing.assert_array_equal(resumed.committed.velocity, halves.committed.velocity)


def test_the_progress_bar_counts_a_batch_as_its_steps(monkeypatch):
    """A batch counts as its steps, and the bar's dt is a step's, not the batch's span (it
    showed 0.016-0.018 s for a run at 2e-3 s a step)."""
    seen, shown = [], []
    call = ProgressBar.__call__

    def spy(self, state, report=None, steps=1):
        seen.append(steps)
        out = call(self, state, report, steps)
        shown.append(float(self.bar.postfix.split("dt ")[1].split(" s")[0]))
        return out

    monkeypatch.setattr(ProgressBar, "__call__", spy)
    sim, result, batched = _run(CASES["coulomb incline"], "legacy", True, monkeypatch,
                                progress=True)
    assert batched > 0 and max(seen) > 1
    assert sum(seen) == len(result.stats) == sim.control.steps
    last = np.cumsum(seen) - 1  # each call's last step
    np.testing.assert_allclose(shown, np.asarray(result.stats["dt"])[last], rtol=1e-2)  # .3g


def test_a_scene_solved_sparse_tries_no_batch(monkeypatch):
    """A scene with more unknowns than a dense system takes (the 10 x 10 stack's 600) never
    takes the one-call step, and a try would replace the system pattern and analysis its
    solver keeps: no try at all."""
    tries = []
    monkeypatch.setattr(compiled_run.StepRuns, "_batch",
                        lambda self, *a: tries.append(1) or (0, compiled_run.STEPS_DONE))
    _run(lambda: (stack_scene(10), 1e-3, 0.01), "newton", True, monkeypatch)
    assert tries == []
    _run(lambda: (stack_scene(2), 1e-3, 0.01), "newton", True, monkeypatch)
    assert tries


def test_a_failed_batch_waits_longer_each_time(monkeypatch):
    """Where every try of a batch is refused at its first step, the tries thin out (1, 2, 4
    ... 64 steps apart) and the run is the step-by-step one."""
    tries = []

    def refused(self, t_end, bar, room=None):
        tries.append(self.sim.control.steps)
        return 0, compiled_run.STEPS_DONE

    monkeypatch.setattr(compiled_run.StepRuns, "_batch", refused)
    sim, result, batched = _run(CASES["coulomb incline"], "legacy", True, monkeypatch)
    assert batched == 0
    gaps = np.diff(tries)
    assert list(gaps[:7]) == [2, 3, 5, 9, 17, 33, 65]
    assert len(tries) < 20



def test_ctrl_c_stops_the_run_at_the_end_of_a_batch(monkeypatch):
    """A signal that comes while a batch runs in compiled code stops the run after it, the
    committed state whole (its time the sum of its steps) and the handler given back."""
    import os
    import signal
    import threading
    import time

    scene = scenes.incline(CoulombSingle(phi=30.0))[0]
    sim = dda.Simulation(scene, dt=1e-4, solver=LegacyPullBack())
    sim.run(0.01, progress=False)  # (the kernels compiled)
    before = signal.getsignal(signal.SIGINT)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        sim.run(60.0, progress=False)
    assert time.perf_counter() - start < 5.0
    steps = sim.control.steps
    assert 1000 < steps < 600_000
    assert sim.committed.time == pytest.approx(steps * 1e-4, rel=1e-9)
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.parametrize("thinned", [{"every": 7}, {"interval": 0.013}, {}])
def test_a_vtu_series_is_the_one_written_step_by_step(thinned, monkeypatch, tmp_path):
    """With a VTU writer a batch stops at each step whose frame the writer takes: the same
    files, byte for byte, and the same index (no batch where every step is a frame)."""
    files = {}
    for on in (False, True):
        writer = dda.io.VTUWriter(tmp_path / str(on) / "case", **thinned)
        sim, result, batched = _run(CASES["moving base"], "newton", on, monkeypatch,
                                    output=writer)
        paths = sorted(writer.files)
        files[on] = ([p.name for p in paths], [p.read_bytes() for p in paths],
                     writer.pvd_path.read_text(), result.frames_written, batched)
    assert (files[True][4] > 100) == bool(thinned)
    assert files[False][:4] == files[True][:4]
    assert len(files[True][0]) > 20
