"""Result: the recorded history of a run, and the per-step statistics."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Result", "StepStats", "Frame"]


@dataclass
class Frame:
    """The state of every block and contact at one recorded step (what a writer writes)."""

    time: float
    vertices: np.ndarray
    offsets: np.ndarray
    vertex_displacement: np.ndarray
    vertex_velocity: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    rotation: np.ndarray
    stress: np.ndarray
    contact_point: np.ndarray
    contact_normal: np.ndarray
    contact_blocks: np.ndarray
    normal_force: np.ndarray
    shear_force: np.ndarray
    contact_state: np.ndarray


class StepStats:
    """Per-step statistics as arrays: ``stats.wall_time``, ``stats["open_close_passes"]`` ...

    Fields: time, dt, iterations (legacy: linear solves; Newton: iterations after OPEN-CLOSE),
    open_close_passes, contacts (vertex-edge pairs tracked), closed (closed contacts), retries
    (failed tries before the step went through), wall_time (s). ``residual_norms`` holds the
    Newton out-of-balance norms of every step and ``cuts`` every dt cut as (time, dt, reason).
    """

    FIELDS = ("time", "dt", "iterations", "open_close_passes", "contacts", "closed", "retries",
              "wall_time")

    def __init__(self):
        self._rows = {k: [] for k in self.FIELDS}
        self.cuts: list[tuple[float, float, str]] = []
        #: per step, the out-of-balance norms of the Newton iterations (empty for legacy)
        self.residual_norms: list[np.ndarray] = []

    def append(self, residual_norms=(), **row):
        for k in self.FIELDS:
            self._rows[k].append(row[k])
        self.residual_norms.append(np.asarray(residual_norms, dtype=float))

    def __getitem__(self, key) -> np.ndarray:
        if key not in self._rows:
            raise KeyError(f"no statistic {key!r}; there are {', '.join(self.FIELDS)}")
        return np.asarray(self._rows[key])

    def __getattr__(self, key):
        if key.startswith("_") or key not in self.FIELDS:
            raise AttributeError(key)
        return self[key]

    def __len__(self):
        return len(self._rows["time"])

    def keys(self):
        return self.FIELDS

    def summary(self) -> str:
        if not len(self):
            return "no steps"
        wall = self["wall_time"]
        return (
            f"{len(self)} steps, {wall.sum():.3g} s wall ({1e3 * wall.mean():.3g} ms/step), "
            f"{self['iterations'].sum()} iterations, max {self['open_close_passes'].max()} "
            f"OPEN-CLOSE passes, {len(self.cuts)} dt cuts"
        )


class Result:
    """What a run recorded: times, block motions, joint forces and per-step statistics.

    Blocks are given by handle, name or index.
    """

    def __init__(self, scene, block_names):
        self._scene = scene
        self._names = list(block_names)
        self._time: list[float] = []
        self._disp: list[np.ndarray] = []
        self._rot: list[np.ndarray] = []
        self._vel: list[np.ndarray] = []
        self._stress: list[np.ndarray] = []
        self._pairs: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.stats = StepStats()
        self.frames_written = 0

    # ---------------------------------------------------------------- recording
    def record(self, frame: Frame, pair_keys, pair_force, pair_normal):
        self._time.append(frame.time)
        self._disp.append(frame.displacement.copy())
        self._rot.append(frame.rotation.copy())
        self._vel.append(frame.velocity.copy())
        self._stress.append(frame.stress.copy())
        self._pairs.append((pair_keys, pair_force, pair_normal))

    # ---------------------------------------------------------------- access
    def _index(self, block) -> int:
        return self._scene.block(block).index

    @property
    def time(self) -> np.ndarray:
        """(n,) times of the recorded steps, starting with t = 0."""
        return np.asarray(self._time)

    def displacement(self, block) -> np.ndarray:
        """(n, 2) displacement of the block's centroid from the start (m)."""
        b = self._index(block)
        return np.array([d[b] for d in self._disp]).reshape(-1, 2)

    def rotation(self, block) -> np.ndarray:
        """(n,) rigid rotation of the block from the start (rad, counter-clockwise positive)."""
        b = self._index(block)
        return np.array([r[b] for r in self._rot])

    def velocity(self, block) -> np.ndarray:
        """(n, 6) velocity of the block's unknowns [u0, v0, r0, ex, ey, gxy] per second."""
        b = self._index(block)
        return np.array([v[b] for v in self._vel]).reshape(-1, 6)

    def stress(self, block) -> np.ndarray:
        """(n, 3) stress [sx, sy, txy] of the block (Pa, tension positive)."""
        b = self._index(block)
        return np.array([s[b] for s in self._stress]).reshape(-1, 3)

    def joint_force(self, a, b) -> np.ndarray:
        """(n, 2) total normal and shear force the pair a-b carries (N per m of thickness).

        Normal: compression positive, along the force-weighted mean contact normal ``n``
        pointing from a into b. Shear: the component along ``n`` turned clockwise by 90
        degrees of the force on b (for a base a under a block b: positive when the force on
        b points in +x). Both values are the same for (a, b) and (b, a).
        """
        ia, ib = self._index(a), self._index(b)
        lo, hi = min(ia, ib), max(ia, ib)
        key = lo * len(self._names) + hi
        out = np.zeros((len(self._time), 2))
        for i, (keys, force, normal) in enumerate(self._pairs):
            pos = np.searchsorted(keys, key)
            if pos < len(keys) and keys[pos] == key:
                n = normal[pos]
                norm = np.hypot(*n)
                if norm == 0.0:
                    continue
                n = n / norm
                f = force[pos]  # force on block hi from block lo
                out[i, 0] = f @ n
                out[i, 1] = f @ np.array([n[1], -n[0]])
        return out

    def profile(self) -> str:
        """A one-line summary of the run's cost."""
        return self.stats.summary()

    def __repr__(self):
        return f"Result({len(self._time)} recorded steps, {len(self._names)} blocks)"
