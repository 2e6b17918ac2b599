"""Stale compiled kernels dropped before any is loaded.

numba's on-disk cache (``cache=True``) checks the source file of the function it compiled, not
the files of the compiled functions that function calls: a kernel that calls a helper of
another file (the penetration guard's pass calls the narrow phase's point-in-block test, the
blocks' start the polygon moments) would keep running the old helper after that file changed.
So at import, when any source file with a compiled function is newer than a cache index of the
package, every cache file of the package is removed and the kernels compile again on their
first call (a minute, once). Installed copies do not change after installation and lose
nothing; only a working tree being edited pays the recompilation.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cold_kernel_cache", "drop_stale_kernel_caches"]

_CACHE_SUFFIXES = (".nbi", ".nbc")
#: whether the kernels' cache was cold when ``dda`` was imported (set there; the first progress
#: bar of the process says that it compiles them, and clears it)
COLD = False


def drop_stale_kernel_caches(package: Path | None = None) -> int:
    """Remove the numba cache files under ``package`` (default: this package) when a
    ``.py`` file there that defines a compiled function is newer than the oldest cache
    index. Returns how many files were removed (0 when the cache is fresh or cannot be
    written)."""
    root = Path(__file__).resolve().parents[1] if package is None else Path(package)
    try:
        indexes = list(root.rglob("__pycache__/*.nbi"))
        if not indexes:
            return 0
        oldest = min(p.stat().st_mtime for p in indexes)
        changed = [p for p in root.rglob("*.py") if p.stat().st_mtime > oldest]
        if not any("@njit" in p.read_text(encoding="utf-8", errors="ignore") for p in changed):
            return 0
        removed = 0
        for p in root.rglob("__pycache__/*"):
            if p.suffix in _CACHE_SUFFIXES:
                p.unlink(missing_ok=True)
                removed += 1
        return removed
    except OSError:  # a read-only installation: numba keeps its cache elsewhere
        return 0


def cold_kernel_cache(package: Path | None = None) -> bool:
    """Whether the kernels will compile on this run: numba keeps its cache beside the sources
    of ``package`` (default: this package; no ``NUMBA_CACHE_DIR``, a folder it may write) and
    holds no cache index there yet (a fresh install, or one whose cache
    :func:`drop_stale_kernel_caches` just dropped). Where the cache lives elsewhere the answer
    is False: it cannot be told."""
    root = Path(__file__).resolve().parents[1] if package is None else Path(package)
    if os.environ.get("NUMBA_CACHE_DIR") or not os.access(root, os.W_OK):
        return False
    try:
        return next(root.rglob("__pycache__/*.nbi"), None) is None
    except OSError:
        return False
