"""Checkpoints are data (dda.io.checkpoint): a hostile or careless file gives a clear error
and runs nothing; a scene whose callables cannot be named is refused when the run starts,
saying what to do; a checkpoint resumes from another process and folder."""

import io
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dda
from dda.cli import main as cli
from dda.io.checkpoint import CHECKPOINT_VERSION, FORMAT
from tests import checkpoint_scene as cs

ROOT = Path(__file__).resolve().parents[1]


class Marker:
    """Unpickling this writes a marker file (what a hostile pickle would do)."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (Path.write_text, (Path(self.path), "pwned"))


def _checkpoint(tmp_path) -> Path:
    path = tmp_path / "run.ckpt"
    cs.simulation().run(0.02, checkpoint=path, checkpoint_every=5)
    return path


def _edit(path: Path, change) -> Path:
    """A copy of the checkpoint with its header changed by ``change(header)``."""
    with np.load(path, allow_pickle=False) as f:
        arrays = {k: f[k] for k in f.files}
    header = json.loads(arrays["header"].tobytes().decode())
    change(header)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    out = path.with_name("edited.ckpt")
    with open(out, "wb") as f:  # (a file object: np.savez adds no .npz suffix)
        np.savez(f, **arrays)
    return out


def test_a_pickle_that_would_run_code_is_never_loaded(tmp_path):
    marker = tmp_path / "marker"
    evil = tmp_path / "evil.ckpt"
    evil.write_bytes(pickle.dumps({"version": CHECKPOINT_VERSION, "simulation": Marker(marker)}))
    with pytest.raises(ValueError, match="never loaded"):
        dda.Simulation.resume(evil)
    assert cli(["run", str(evil), "--no-progress"]) != 0
    assert not marker.exists()


def test_a_pickle_inside_an_npz_is_never_loaded(tmp_path):
    marker = tmp_path / "marker"
    evil = tmp_path / "evil.ckpt"
    buffer = io.BytesIO()
    np.savez(buffer, header=np.array([Marker(marker)], dtype=object))
    evil.write_bytes(buffer.getvalue())
    with pytest.raises(ValueError, match="not a readable checkpoint"):
        dda.Simulation.resume(evil)
    assert not marker.exists()


def test_a_header_with_the_version_and_nothing_else(tmp_path):
    path = tmp_path / "thin.ckpt"
    header = json.dumps({"format": FORMAT, "version": CHECKPOINT_VERSION}).encode()
    with open(path, "wb") as f:
        np.savez(f, header=np.frombuffer(header, dtype=np.uint8))
    with pytest.raises(ValueError, match="header is incomplete"):
        dda.Simulation.resume(path)


@pytest.mark.parametrize("change, message", [
    (lambda h: h["scene"]["shakes"][0]["acceleration"].update(function="os:system"),
     "names no function"),
    (lambda h: h["scene"]["shakes"][0]["acceleration"].update(function="builtins:exec"),
     "names no function"),
    (lambda h: h["simulation"]["solver"].update(name="os:system"), "not a subclass"),
    (lambda h: h["scene"]["joints"]["default"]["friction"].update(law="subprocess:Popen"),
     "not a subclass"),
    (lambda h: h.update(writer={"class": "subprocess:Popen", "prefix": "x", "inside": "x",
                                "every": 1, "entries": [], "n": 0, "seen": 0,
                                "last_time": None, "extra": {}}), "not a dda.io.VTUWriter"),
    (lambda h: h["writer"].update(inside="../../elsewhere/case"), "not a path inside"),
    (lambda h: h["writer"].update(inside=None, prefix="/tmp/elsewhere/case"),
     "outside the checkpoint's folder"),
    (lambda h: h["state"].update(time="0; import os"), "state.time: not a number"),
    (lambda h: h.update(version=4), "layout 4"),
    (lambda h: h.update(extra=1), "unknown"),
])
def test_a_header_naming_what_it_should_not_is_refused(tmp_path, change, message):
    path = tmp_path / "run.ckpt"
    sim = dda.Simulation(cs.build_scene(), dt=cs.DT, solver=dda.solvers.LegacyPullBack(),
                         output=dda.io.VTUWriter(tmp_path / "out" / "case"))
    sim.run(0.01, checkpoint=path)
    with pytest.raises(ValueError, match=message):
        dda.Simulation.resume(_edit(path, change))


def test_a_function_of_the_script_run_as_a_program_is_refused_when_the_run_starts(tmp_path):
    """The portability failure of the pickled checkpoints (a script's own shaking function,
    saved as __main__.accel, which no other program can read) is now an error at the start
    of the run that says what to do."""
    script = tmp_path / "run_me.py"
    script.write_text(
        "import numpy as np\n"
        "import dda\n"
        "from tests import checkpoint_scene as cs\n"
        "def accel(t):\n"
        "    return (np.sin(t), 0.0)\n"
        "scene = cs.build_scene()\n"
        "scene.shake('block', acceleration=accel)\n"
        "dda.Simulation(scene, dt=2e-3).run(0.01, checkpoint=r'%s')\n"
        % (tmp_path / "run.ckpt"))
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          env=env, cwd=tmp_path)
    assert done.returncode != 0
    assert "__main__.accel has no import path" in done.stderr
    assert "top level of a module you can import" in done.stderr
    assert not (tmp_path / "run.ckpt").exists()


def test_a_checkpoint_resumes_in_another_process_and_folder(tmp_path):
    """Written by this process, resumed by the command in a fresh one started elsewhere: the
    named functions (tests.checkpoint_scene.table_acceleration) are imported there."""
    path = _checkpoint(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    done = subprocess.run([sys.executable, "-m", "dda", "run", str(path), "--duration", "0.01",
                           "--no-progress"], capture_output=True, text=True, env=env,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "resuming at t = 0.02 s" in done.stdout
    assert dda.Simulation.resume(path).state.time == pytest.approx(0.03)


def test_a_resumed_run_writes_only_beside_its_checkpoint(tmp_path):
    """The file's own idea of where its checkpoint goes is not followed: the resumed run
    checkpoints to the file it was resumed from; a VTU series written outside the
    checkpoint's folder goes on there only when asked."""
    path = tmp_path / "run.ckpt"
    sim = dda.Simulation(cs.build_scene(), dt=cs.DT, solver=dda.solvers.LegacyPullBack(),
                         output=dda.io.VTUWriter(tmp_path / "out" / "case"))
    sim.run(0.01, checkpoint=path)
    victim = tmp_path / "elsewhere" / "important.txt"
    victim.parent.mkdir()
    victim.write_text("keep me")
    edited = _edit(path, lambda h: h.update(checkpoint=[str(victim), 1]))
    resumed = dda.Simulation.resume(edited)
    resumed.run(0.01)
    assert victim.read_text() == "keep me"
    assert dda.Simulation.resume(edited).state.time == pytest.approx(0.02)
    assert (tmp_path / "out" / "case_00010.vtu").is_file()  # the series went on beside it

    outside = dda.io.VTUWriter(tmp_path / "series" / "case")
    sim = dda.Simulation(cs.build_scene(), dt=cs.DT, output=outside)
    ckpt = tmp_path / "ckpts" / "run.ckpt"
    sim.run(0.01, checkpoint=ckpt)
    with pytest.raises(ValueError, match="allow_outside_output=True"):
        dda.Simulation.resume(ckpt)
    assert dda.Simulation.resume(ckpt, allow_outside_output=True).output.prefix == (
        tmp_path / "series" / "case")


def test_a_checkpoint_from_before_the_control_remembered_its_failed_size_resumes(tmp_path):
    """Checkpoints of this layout written before ``StepControl.ceiling`` existed resume, with
    no failed size remembered; a ceiling that is not a number is refused."""
    path = _checkpoint(tmp_path)
    sim = dda.Simulation.resume(_edit(path, lambda h: h["control"].pop("ceiling")))
    assert sim.control.ceiling == 0.0
    with pytest.raises(ValueError, match="control.ceiling"):
        dda.Simulation.resume(_edit(path, lambda h: h["control"].update(ceiling="x")))


def test_a_checkpoint_from_before_the_natural_step_resumes_with_the_scenes(tmp_path):
    """Checkpoints written before ``StepControl.natural_dt`` existed resume with the scene's
    natural step (:func:`dda.penalty_advice.natural_step`), as a new run has it; one that
    is not a number is refused."""
    path = _checkpoint(tmp_path)
    kept = dda.Simulation.resume(path).control.natural_dt
    assert kept > 0.0
    sim = dda.Simulation.resume(_edit(path, lambda h: h["control"].pop("natural_dt")))
    assert sim.control.natural_dt == kept
    with pytest.raises(ValueError, match="control.natural_dt"):
        dda.Simulation.resume(_edit(path, lambda h: h["control"].update(natural_dt="x")))
