"""Stale numba caches are dropped at import (dda/kernels/cache.py): numba checks only the
compiled function's own file, so a kernel calling a helper of a changed file would run the
old helper."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from dda.kernels.cache import drop_stale_kernel_caches


def _package(tmp_path, kernel_age, plain_age, index_age):
    """A package with a kernel file, a plain file and one cached kernel, each ``age`` s old."""
    now = 1.0e9
    cache = tmp_path / "pkg" / "__pycache__"
    cache.mkdir(parents=True)
    files = {tmp_path / "pkg" / "helpers.py": ("from numba import njit\n@njit\ndef f(x):\n"
                                                "    return x\n", kernel_age),
             tmp_path / "pkg" / "plain.py": ("X = 1\n", plain_age),
             cache / "caller.g-3.py311.nbi": ("index", index_age),
             cache / "caller.g-3.py311.1.nbc": ("code", index_age),
             cache / "plain.cpython-311.pyc": ("bytecode", index_age)}
    for path, (text, age) in files.items():
        path.write_text(text)
        os.utime(path, (now - age, now - age))
    return tmp_path / "pkg", cache


def test_a_changed_kernel_file_drops_every_cached_kernel(tmp_path):
    root, cache = _package(tmp_path, kernel_age=10, plain_age=100, index_age=50)
    assert drop_stale_kernel_caches(root) == 2
    assert sorted(p.name for p in cache.iterdir()) == ["plain.cpython-311.pyc"]


def test_fresh_caches_and_changes_without_kernels_are_kept(tmp_path):
    for kernel_age, plain_age in ((100, 100), (100, 10)):
        root, cache = _package(tmp_path / f"{kernel_age}-{plain_age}", kernel_age, plain_age, 50)
        assert drop_stale_kernel_caches(root) == 0
        assert len(list(cache.iterdir())) == 3


def test_no_cache_no_work(tmp_path):
    (tmp_path / "k.py").write_text("@njit\n")
    assert drop_stale_kernel_caches(tmp_path) == 0


def test_a_cold_cache_is_one_without_an_index_beside_the_sources(tmp_path, monkeypatch):
    """The first run of an install compiles the kernels; the progress bar says so then."""
    from dda.kernels.cache import cold_kernel_cache

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    root, cache = _package(tmp_path, kernel_age=100, plain_age=100, index_age=50)
    assert not cold_kernel_cache(root)
    drop_stale_kernel_caches(root)  # nothing stale: kept
    for p in cache.glob("*.nb*"):
        p.unlink()
    assert cold_kernel_cache(root)
    # a cache kept elsewhere cannot be told: no claim
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert not cold_kernel_cache(root)


def test_the_progress_bar_shows_its_note_until_the_first_step():
    import io
    from types import SimpleNamespace

    from dda.progress import ProgressBar

    out = io.StringIO()
    bar = ProgressBar(1.0, 0.0, file=out, note="compiling the kernels first")
    bar.bar.refresh()
    assert "compiling the kernels first" in out.getvalue()
    bar.last_call -= 5.0  # a first step that took 5 s: still compiling, maybe
    bar(SimpleNamespace(time=0.25))
    bar.bar.refresh()
    assert "compiling" in out.getvalue().rsplit("\r", 1)[-1]
    bar(SimpleNamespace(time=0.5))  # the next one at once: compiled
    bar.bar.refresh()
    bar.close()
    assert "compiling" not in out.getvalue().rsplit("\r", 1)[-1]
    assert "0.5000/1.0000" in out.getvalue()


ROOT = Path(__file__).resolve().parents[1]

_ONE_SIGNATURE = """
import sys
from numba.core.registry import CPUDispatcher
import dda
from dda.contact import CoulombSingle
from dda.registry import make_solver
from dda.studies.cases import rock_slope, stepped_table
from tests.conftest import stack_scene


for solver in ("newton", "legacy"):
    scene, _, _ = rock_slope(CoulombSingle(phi=31.6), stepped_table(670.0, 2.0, 6, 1.0),
                             shear_penalty=10e9)
    dda.Simulation(scene, dt=1e-3, solver=make_solver(solver)).run(0.05)
    dda.Simulation(stack_scene(10), dt=1e-3, solver=make_solver(solver)).run(0.01)
for name, module in list(sys.modules.items()):
    if name.startswith("dda"):
        for attr, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and len(obj.signatures) > 1:
                print(f"{name}.{attr}: {len(obj.signatures)} versions")
"""


@pytest.mark.parametrize("cold", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_every_kernel_compiles_once_for_both_solvers(cold, tmp_path):
    """A kernel called with a literal constant, a module's read-only array or another array
    layout compiles a second version of itself and of everything it calls (17 kernels did,
    some 15 s of a fresh install's first run). After the demo scene and a 10 x 10 stack (the
    sparse path) under both solvers each kernel holds one version. A fresh process: other
    tests call kernels with their own argument types. With the cache the suite has filled, a
    cached caller carries its callees' versions inside, and only kernels called from Python
    with two signatures show (the 17 passed so); the ``slow`` run compiles all into an empty
    cache (about 90 s) and finds all 17 on the code before."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path)) if cold else None
    run = subprocess.run([sys.executable, "-c", _ONE_SIGNATURE], capture_output=True, text=True,
                         timeout=900, env=env, cwd=ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout == ""
