"""Stale numba caches are dropped at import (dda/kernels/cache.py): numba checks only the
compiled function's own file, so a kernel calling a helper of a changed file would run the
old helper."""

from __future__ import annotations

import os

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
