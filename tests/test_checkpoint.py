"""Checkpoint and resume: an interrupted run keeps what it wrote and goes on with the same
numbers as a run that was never interrupted."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

import dda
from dda.plot import read_pvd
from tests import checkpoint_scene as cs

ROOT = Path(__file__).resolve().parents[1]
STEPS = round(cs.DURATION / cs.DT)


@pytest.fixture(scope="module")
def uninterrupted():
    sim = cs.simulation()
    result = sim.run(cs.DURATION)
    return sim, result


def assert_same_state(a, b):
    assert a.state.time == pytest.approx(b.state.time, rel=1e-14)
    for name in ("x", "velocity", "stress", "rotation"):
        np.testing.assert_array_equal(getattr(a.state, name), getattr(b.state, name), name)
    np.testing.assert_array_equal(a.state.contacts.t_n, b.state.contacts.t_n)
    np.testing.assert_array_equal(a.state.contacts.t_s, b.state.contacts.t_s)


def test_interrupted_run_resumes_with_the_same_numbers(tmp_path, uninterrupted):
    ref, ref_result = uninterrupted
    sim = cs.simulation(cs.InterruptOnce(at=123, prefix=tmp_path / "none"))
    path = tmp_path / "run.ckpt"
    with pytest.raises(KeyboardInterrupt):
        sim.run(cs.DURATION, checkpoint=path, checkpoint_every=25)
    stopped = sim.state.time
    assert 0.2 < stopped < 0.3  # frame 123 is the state after step 122
    resumed = dda.Simulation.resume(path)
    assert resumed.state.time == stopped  # the interruption saved the last committed step
    result = resumed.run()
    assert result.time[-1] == pytest.approx(cs.DURATION)
    assert_same_state(resumed, ref)
    # the resumed run's history is the tail of the uninterrupted one
    tail = ref_result.displacement("block")[-len(result.time):]
    np.testing.assert_array_equal(result.displacement("block"), tail)
    with pytest.raises(ValueError, match="already ended"):
        dda.Simulation.resume(path).run()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_killed_process_keeps_its_files_and_resumes(tmp_path, uninterrupted, sig):
    """A subprocess is signalled mid-run: every VTU file it wrote is whole, the index lists
    them, and resuming from its checkpoint finishes the run with the uninterrupted numbers."""
    ref, ref_result = uninterrupted
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(
        [sys.executable, "-c", "from tests.checkpoint_scene import main; main()",
         str(tmp_path)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)
    written = 0
    for line in proc.stdout:
        written = int(line.split()[1])
        if written >= 60:
            proc.send_signal(sig)
            break
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0, "the run was not interrupted"
    assert "KeyboardInterrupt" in err
    files = sorted(tmp_path.glob("case_*.vtu"))
    assert len(files) >= 60
    assert not list(tmp_path.glob("*.tmp*"))  # nothing half-written
    for f in files:
        assert len(meshio.read(f).points) > 0
    pvd = (tmp_path / "case.pvd").read_text()
    assert pvd.count("<DataSet") == len(files)

    resumed = dda.Simulation.resume(tmp_path / "run.ckpt")
    assert resumed.state.time < cs.DURATION
    resumed.run()
    assert_same_state(resumed, ref)
    files = sorted(tmp_path.glob("case_*.vtu"))
    # the start and every step, each once (STEPS and the steps ended at a slip reversal)
    assert len(files) == len(ref_result.time) >= STEPS + 1
    assert (tmp_path / "case.pvd").read_text().count("<DataSet") == len(files)


def test_a_killed_run_leaves_an_index_of_its_frames(tmp_path):
    """SIGKILL, which no handler sees, mid-run: the .pvd index lists every VTU file on disk
    (but at most the last one, killed between its file and its entry), and it parses."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(
        [sys.executable, "-c", "from tests.checkpoint_scene import main; main()",
         str(tmp_path)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)
    for line in proc.stdout:
        if int(line.split()[1]) >= 73:
            proc.kill()
            break
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    files = sorted(p.name for p in tmp_path.glob("case_*.vtu"))
    assert len(files) >= 73
    listed = [p.name for _, p in read_pvd(tmp_path / "case.pvd")]
    assert listed == files or listed == files[:-1], (len(listed), len(files))


def test_the_index_grows_in_place_and_is_rewritten_when_not_its_own(tmp_path):
    """Each frame's entry is added as it is written; an index changed behind the writer's
    back, or a writer that comes back from a checkpoint, rewrites it whole."""
    import pickle

    sim = cs.simulation()
    writer = dda.io.VTUWriter(tmp_path / "case")
    for k in range(3):
        writer.write(sim.frame())
        assert len(read_pvd(writer.pvd_path)) == k + 1
    writer.pvd_path.write_text(writer.pvd_path.read_text() + "\n")  # not as it left it
    writer.write(sim.frame())
    assert len(read_pvd(writer.pvd_path)) == 4
    again = pickle.loads(pickle.dumps(writer))  # a resumed run's writer
    again.write(sim.frame())
    names = [p.name for _, p in read_pvd(writer.pvd_path)]
    assert names == [f"case_{i:05d}.vtu" for i in range(5)]


def test_checkpoint_needs_a_picklable_scene(tmp_path):
    scene = cs.build_scene()
    scene.shake(scene.block("block"), acceleration=lambda t: (0.0, 0.0))  # a lambda
    sim = dda.Simulation(scene, dt=cs.DT)
    with pytest.raises(ValueError, match="shaking of block 'block'.* has no import path"):
        sim.run(0.01, checkpoint=tmp_path / "x.ckpt")
    assert not (tmp_path / "x.ckpt").exists()


def test_resume_and_run_errors(tmp_path):
    with pytest.raises(ValueError, match="no checkpoint file"):
        dda.Simulation.resume(tmp_path / "missing.ckpt")
    bad = tmp_path / "bad.ckpt"
    bad.write_bytes(b"not a pickle")
    with pytest.raises(ValueError, match="not an .npz file"):
        dda.Simulation.resume(bad)
    with pytest.raises(ValueError, match="give the duration"):
        cs.simulation().run()
    with pytest.raises(ValueError, match="checkpoint_every"):
        cs.simulation().run(0.01, checkpoint=tmp_path / "c.ckpt", checkpoint_every=0)


def test_a_checkpoint_of_an_older_layout_is_refused_clearly(tmp_path):
    import pickle

    from dda.simulation import CHECKPOINT_VERSION

    old = tmp_path / "old.ckpt"
    old.write_bytes(pickle.dumps({"version": CHECKPOINT_VERSION - 1, "simulation": None}))
    with pytest.raises(ValueError, match="not a checkpoint of this version of dda"):
        dda.Simulation.resume(old)


def test_the_command_stops_on_a_signal_with_one_line_and_how_to_go_on(tmp_path):
    """Ctrl-C or SIGTERM on 'dda run': the checkpoint is written, one line says when it
    stopped and the command that resumes it, no traceback (issue 22)."""
    import time

    from tests.test_scene_file import TABLES

    scene = tmp_path / "tables.toml"
    scene.write_text(TABLES.replace("duration = 0.03", "duration = 100.0")
                     .replace("checkpoint_every = 10", "checkpoint_every = 5"))
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "dda", "run", str(scene), "--out", str(out),
                             "--no-progress"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ckpt = out / "tables.ckpt"
    deadline = time.time() + 120
    while not (ckpt.exists() and len(list(out.glob("tables_*.vtu"))) >= 20):
        assert time.time() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("dda: stopped at t = ")
    assert lines[0].endswith(f"resume with: dda run {ckpt}")
    stopped = dda.Simulation.resume(ckpt).state.time
    assert f"t = {stopped:g} s" in lines[0]


def test_a_layout_5_checkpoint_resumes_and_a_newer_one_is_named_as_newer(tmp_path):
    """Layout 6 keeps record_every's count; a layout 5 checkpoint (written before) resumes
    with it at 0, and a checkpoint from a later dda is refused by its layout, not as a
    header with an unknown key."""
    import json

    import numpy as np

    from dda.io import checkpoint as ck

    sim = cs.simulation()
    sim.run(0.01, checkpoint=tmp_path / "a.ckpt")

    def rewrite(src, dst, change):
        with np.load(src, allow_pickle=False) as f:
            arrays = {k: f[k] for k in f.files}
        header = json.loads(arrays.pop("header").tobytes().decode())
        change(header)
        raw = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
        np.savez(dst, header=raw, **arrays)

    def as_five(h):
        h["version"] = 5
        del h["record_since"]

    rewrite(tmp_path / "a.ckpt", tmp_path / "five.npz", as_five)
    assert dda.Simulation.resume(tmp_path / "five.npz")._record_since == 0
    # layout 5 as the first commits with record_every's count wrote it: read, count and all
    rewrite(tmp_path / "a.ckpt", tmp_path / "five_b.npz", lambda h: h.update(version=5))
    dda.Simulation.resume(tmp_path / "five_b.npz")
    for bad in (1, 10**30, -1, 1.0, True):  # record_every is 1 here: only 0
        rewrite(tmp_path / "a.ckpt", tmp_path / "bad.npz",
                lambda h, bad=bad: h.update(record_since=bad))
        with pytest.raises(ValueError, match="record_since"):
            dda.Simulation.resume(tmp_path / "bad.npz")
    rewrite(tmp_path / "a.ckpt", tmp_path / "float.npz", lambda h: h.update(version=6.0))
    with pytest.raises(ValueError, match="layout 6.0"):
        dda.Simulation.resume(tmp_path / "float.npz")
    rewrite(tmp_path / "a.ckpt", tmp_path / "seven.npz",
            lambda h: h.update(version=ck.CHECKPOINT_VERSION + 1, later_key=1))
    with pytest.raises(ValueError, match=r"layout 7, this version reads 5 and 6"):
        dda.Simulation.resume(tmp_path / "seven.npz")
