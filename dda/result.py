"""Result: the recorded history of a run, and the per-step statistics."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dda.contact.contacts import pair_key
from dda.profiling import SECTIONS

__all__ = ["Result", "StepStats", "Frame", "CostProfile"]

#: the share of a run's wall time from which its profile says how much of it numba spent
#: compiling or loading the kernels
KERNEL_NOTE = 0.05


@dataclass
class Frame:
    """The state of every block and contact at one recorded step (what a writer writes).

    ``contact_normal`` is the unit normal of each contact's edge, pointing out of the edge's
    block (``contact_blocks[:, 1]``) towards the vertex's block (``contact_blocks[:, 0]``);
    ``normal_force`` is compression positive, so the normal force on the vertex's block is
    ``normal_force * contact_normal``. ``block_names`` names the blocks in index order and
    ``shaken`` lists the indices of the shaken blocks.
    """

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
    block_names: tuple = ()
    shaken: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    # the bolts (dda.bolts): (n, 2, 2) ends, (n,) axial force (tension positive), broken
    bolt_points: np.ndarray | None = None
    bolt_force: np.ndarray | None = None
    bolt_broken: np.ndarray | None = None


class StepStats:
    """Per-step statistics as arrays: ``stats.wall_time``, ``stats["open_close_passes"]`` ...

    Fields: time, dt, iterations (legacy: linear solves; Newton: iterations after OPEN-CLOSE),
    open_close_passes, contacts (vertex-edge pairs tracked), closed (closed contacts: sticking
    or sliding), sliding (closed contacts that slip at the end of the step), retries
    (failed tries before the step went through), wall_time (s), solves (linear solves, retries
    included), unknowns (size of the step's linear system: 6 per free block, 3 per rigid
    one; fixed and shaken blocks have none), pairs (block pairs whose bounding boxes came
    within the contact search distance: the only pairs the narrow phase looks at),
    penetration (the deepest vertex inside another block at the end of the step, m, found
    geometrically by the penetration guard), spring_penetration (the deepest closed contact's
    spring penetration ``-t_n / p_n``, m) and the seconds spent in each part of the step
    (retries included): detection_time, contact_element_time, return_map_time, assembly_time,
    solve_time, guard_time (see :mod:`dda.profiling`). ``residual_norms`` holds the Newton
    out-of-balance norms of every step, ``cuts`` every dt cut as (time, dt, reason) and
    ``reversals`` every step shortened to end at a slip reversal as (time at its start, the
    share of the step it kept) (:mod:`dda.slip_events`).

    Memory: the rows are kept as compact columns (times and dt in float64, counts in the
    smallest unsigned integers that hold them, depths and residual norms in float32; the
    newest 256 rows as tuples until they move there), 35 to 50 bytes a step, and the
    timings (wall_time and the parts' seconds, 28 bytes) summed over ``timing_every`` steps
    (the run's ``record_every``) and read back as each interval's mean: exact per step when
    every step is recorded, exact in total always (what :meth:`dda.Result.profile` uses). A
    30,000-step run recording every 1,000th step holds 1.6 MB of statistics; a million
    steps 48 MB (a 2-block scene, legacy DDA) to 64 MB (60,000 contacts, Newton's two
    residual norms a step), 86 and 102 MB recording every step. (The lists of one dict a
    step this replaced held 0.55 MiB a 1,000 steps: 550 MB a million.)
    """

    FIELDS = ("time", "dt", "iterations", "open_close_passes", "contacts", "closed", "sliding",
              "retries",
              "wall_time", "solves", "unknowns", "pairs", "penetration", "spring_penetration")
    FIELDS += tuple(f"{name}_time" for name in SECTIONS)
    _FLOAT64 = ("time", "dt")
    _FLOAT32 = ("penetration", "spring_penetration")
    _TIMINGS = ("wall_time",) + tuple(f"{name}_time" for name in SECTIONS)
    _COUNTS = ("iterations", "open_close_passes", "contacts", "closed", "sliding", "retries",
               "solves", "unknowns", "pairs")
    _BUFFER = 256  # rows kept as Python tuples before they go into the columns

    def __init__(self, timing_every: int = 1):
        self.timing_every = max(1, int(timing_every))
        self._n = 0  # rows in the columns
        self._cols = {k: np.zeros(0, dtype=np.float64) for k in self._FLOAT64}
        self._cols.update({k: np.zeros(0, dtype=np.float32) for k in self._FLOAT32})
        self._cols.update({k: np.zeros(0, dtype=np.uint8) for k in self._COUNTS})
        self._cols["norm_count"] = np.zeros(0, dtype=np.uint8)
        self._timing = np.zeros((0, len(self._TIMINGS)), dtype=np.float32)
        self._n_timing = 0  # closed timing intervals
        self._pending = np.zeros(len(self._TIMINGS))  # sums of the interval not yet closed
        self._pending_steps = 0
        self._norms = np.zeros(0, dtype=np.float32)
        self._n_norms = 0
        self._rows: list[tuple] = []  # the newest rows, in FIELDS order
        self._row_norms: list = []
        self.cuts: list[tuple[float, float, str]] = []
        self.reversals: list[tuple[float, float]] = []
        #: steps taken in batches of one kernel call (dda.compiled_run); their wall time is
        #: their batch's shared evenly, under ``solve_time``
        self.batched = 0
        #: seconds of the run in which numba compiled its kernels or loaded them from its
        #: cache (a process's first steps; the profile's parts include what fell in a step)
        self.kernel_time = 0.0

    def append(self, residual_norms=(), **row):
        """Add one step's row (every field of :attr:`FIELDS` by name)."""
        self.append_row(tuple(row[k] for k in self.FIELDS), residual_norms)

    def append_row(self, values: tuple, residual_norms=()) -> None:
        """Add one step's row, its values in :attr:`FIELDS` order."""
        self._rows.append(values)
        self._row_norms.append(residual_norms)
        if len(self._rows) >= self._BUFFER:
            self._flush()

    def _flush(self) -> None:
        """Move the buffered rows into the compact columns."""
        rows = self._rows
        if not rows:
            return
        b = len(rows)
        table = np.array(rows, dtype=np.float64)
        n, end = self._n, self._n + b
        if end > len(self._cols["time"]):
            size = max(256, end + end // 2)  # (grown by half: amortized, and less spare)
            for k, a in self._cols.items():
                self._cols[k] = _grown(a, size)
        index = {k: j for j, k in enumerate(self.FIELDS)}
        for k in self._FLOAT64 + self._FLOAT32:
            self._cols[k][n:end] = table[:, index[k]]
        for k in self._COUNTS:
            self._put_counts(k, n, table[:, index[k]])
        norms = [np.asarray(r, dtype=np.float32).ravel() for r in self._row_norms]
        self._put_counts("norm_count", n, np.array([len(r) for r in norms], dtype=np.float64))
        flat = np.concatenate(norms) if norms else np.zeros(0, np.float32)
        stop = self._n_norms + len(flat)
        if stop > len(self._norms):
            self._norms = _grown(self._norms, max(256, stop + stop // 2))
        self._norms[self._n_norms:stop] = flat
        self._n_norms = stop
        self._add_timings(table[:, [index[k] for k in self._TIMINGS]])
        self._n = end
        self._rows, self._row_norms = [], []

    def _put_counts(self, key, start, values):
        """Store counts, widening the column's unsigned type when it would not hold them."""
        col = self._cols[key]
        top = float(values.max()) if len(values) else 0.0
        if values.min(initial=0.0) < 0:
            raise ValueError(f"StepStats: {key} must not be negative")
        if top > np.iinfo(col.dtype).max:
            for dtype in (np.uint16, np.uint32, np.uint64):
                if top <= np.iinfo(dtype).max:
                    break
            col = self._cols[key] = col.astype(dtype)
        col[start:start + len(values)] = values

    def _add_timings(self, t: np.ndarray) -> None:
        """Sum the steps' timings into intervals of ``timing_every`` steps; keep each closed
        interval's mean."""
        every = self.timing_every
        take = min(every - self._pending_steps, len(t))
        self._pending += t[:take].sum(axis=0)
        self._pending_steps += take
        means = []
        if self._pending_steps == every:
            means.append(self._pending / every)
            self._pending = np.zeros(len(self._TIMINGS))
            self._pending_steps = 0
        rest = t[take:]
        full = len(rest) // every
        if full:
            means.extend(rest[:full * every].reshape(full, every, -1).mean(axis=1))
        tail = rest[full * every:]
        if len(tail):
            self._pending = tail.sum(axis=0)
            self._pending_steps = len(tail)
        if means:
            k, stop = self._n_timing, self._n_timing + len(means)
            if stop > len(self._timing):
                self._timing = _grown(self._timing, max(16, stop + stop // 2))
            self._timing[k:stop] = np.array(means)
            self._n_timing = stop

    def _timings(self) -> np.ndarray:
        """(n, len(_TIMINGS)) the timings per step (each interval's mean for its steps)."""
        out = np.repeat(self._timing[:self._n_timing].astype(np.float64), self.timing_every,
                        axis=0)
        if self._pending_steps:
            tail = np.repeat((self._pending / self._pending_steps)[None, :],
                             self._pending_steps, axis=0)
            out = np.concatenate([out, tail])
        return out

    @property
    def residual_norms(self) -> list[np.ndarray]:
        """Per step, the out-of-balance norms of its Newton iterations (empty for legacy)."""
        self._flush()
        counts = self._cols["norm_count"][:self._n].astype(np.int64)
        ends = np.cumsum(counts)
        norms = self._norms[:self._n_norms].astype(np.float64)
        return [norms[e - c:e] for c, e in zip(counts, ends, strict=True)]

    @property
    def nbytes(self) -> int:
        """Bytes the statistics' arrays hold (their capacity, grown by half as they fill)."""
        self._flush()
        return (sum(a.nbytes for a in self._cols.values()) + self._timing.nbytes
                + self._norms.nbytes + self._pending.nbytes)

    def __getitem__(self, key) -> np.ndarray:
        if key not in self.FIELDS:
            raise KeyError(f"no statistic {key!r}; there are {', '.join(self.FIELDS)}")
        self._flush()
        if key in self._TIMINGS:
            return self._timings()[:, self._TIMINGS.index(key)]
        a = self._cols[key][:self._n]
        return a.astype(np.int64) if key in self._COUNTS else a.astype(np.float64)

    def __getattr__(self, key):
        if key.startswith("_") or key not in self.FIELDS:
            raise AttributeError(key)
        return self[key]

    def __len__(self):
        return self._n + len(self._rows)

    def keys(self):
        return self.FIELDS

    def to_pandas(self):
        """The statistics as a :class:`pandas.DataFrame`: one row a step, one column a field.

        Needs the optional ``pandas`` (``pip install 'dda[data]'``). The index is ``step``
        (0 for the run's first step); the columns are :attr:`FIELDS` in their order: ``time``
        (s, at the end of the step) and ``dt`` (s) as float64, the counts as int64, the
        depths (m) and the seconds as float64. ``df.attrs["units"]`` gives each column's
        unit ("1" for a count). The timings are each interval of ``timing_every`` steps'
        mean (exact per step when every step is recorded). ``residual_norms`` and ``cuts``
        stay here: they are not one value a step.

        Examples
        --------
        >>> stats = StepStats()
        >>> stats.append(**{k: 1 for k in StepStats.FIELDS})
        >>> df = stats.to_pandas()
        >>> df[["time", "dt", "contacts"]].to_dict("records")
        [{'time': 1.0, 'dt': 1.0, 'contacts': 1}]
        >>> df.attrs["units"]["wall_time"], df.attrs["units"]["contacts"]
        ('s', '1')
        """
        from dda.data import stats_frame

        return stats_frame(self)

    def summary(self) -> str:
        if not len(self):
            return "no steps"
        wall = self["wall_time"]
        return (
            f"{len(self)} steps, {wall.sum():.3g} s wall ({1e3 * wall.mean():.3g} ms/step), "
            f"{self['iterations'].sum()} iterations, max {self['open_close_passes'].max()} "
            f"OPEN-CLOSE passes, {len(self.cuts)} dt cuts"
            + (f", {len(self.reversals)} steps ended at a slip reversal" if self.reversals
               else "")
        )


def _normal_and_shear(force: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(..., 2) normal and shear component of the pair forces ``force`` (..., 2) along the
    unit vector of ``normal`` (..., 2) and that vector turned clockwise by 90 degrees; zero
    where ``normal`` is zero (see :meth:`Result.joint_force`)."""
    norm = np.hypot(normal[..., 0], normal[..., 1])
    safe = np.where(norm == 0.0, 1.0, norm)
    nx, ny = normal[..., 0] / safe, normal[..., 1] / safe
    fx, fy = force[..., 0], force[..., 1]
    out = np.stack([fx * nx + fy * ny, fx * ny - fy * nx], axis=-1)
    out[norm == 0.0] = 0.0
    return out


def _grown(a: np.ndarray, size: int) -> np.ndarray:
    """``a`` in a new array of ``size`` rows, its rows first (``numpy.resize`` would keep a
    larger array alive behind its view)."""
    out = np.zeros((size, *a.shape[1:]), dtype=a.dtype)
    out[:len(a)] = a
    return out


class Result:
    """What a run recorded: times, block motions, joint forces and per-step statistics.

    Blocks are given by handle, name or index.
    """

    def __init__(self, scene, block_names, record_every: int = 1, settings=None,
                 initial_centroid=None):
        self._scene = scene
        self._names = list(block_names)
        # what the run was (dt, solver, ...) and where the blocks' centroids started: the
        # attributes and the initial_centroid of :meth:`to_xarray`
        self._settings = dict(settings or {})
        self._centroid0 = (None if initial_centroid is None
                           else np.array(initial_centroid, dtype=np.float64).reshape(-1, 2))
        self._time: list[float] = []
        self._disp: list[np.ndarray] = []
        self._rot: list[np.ndarray] = []
        self._vel: list[np.ndarray] = []
        self._stress: list[np.ndarray] = []
        self._pairs: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.stats = StepStats(timing_every=record_every)
        self.frames_written = 0
        self._bolt_rows: list[tuple[np.ndarray, np.ndarray]] = []  # per record, with bolts

    # ---------------------------------------------------------------- recording
    def record(self, time, displacement, rotation, velocity, stress, pair_keys, pair_force,
               pair_normal):
        """Keep one step: per block (n_blocks, ...) arrays, and the per-pair joint forces
        of :func:`dda.recorder.pair_forces`. The arrays are copied."""
        self._time.append(float(time))
        self._disp.append(np.array(displacement))
        self._rot.append(np.array(rotation))
        self._vel.append(np.array(velocity))
        self._stress.append(np.array(stress))
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
        key = int(pair_key(ia, ib, len(self._names)))
        force = np.zeros((len(self._time), 2))  # on the higher-index block from the other
        normal = np.zeros((len(self._time), 2))
        for i, (keys, f, n) in enumerate(self._pairs):
            pos = np.searchsorted(keys, key)
            if pos < len(keys) and keys[pos] == key:
                force[i], normal[i] = f[pos], n[pos]
        return _normal_and_shear(force, normal)

    def record_bolts(self, force, broken):
        """Keep the bolts' (n_bolts,) axial forces and broken flags of the step just
        recorded (:meth:`record`; a scene with bolts records them at every step)."""
        self._bolt_rows.append((np.array(force, dtype=float), np.array(broken, dtype=bool)))

    def _bolt_column(self, i, column) -> np.ndarray:
        n = len(self._scene.bolts)
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < n:
            raise ValueError(f"no bolt {i!r} (the scene has {n})")
        return np.array([row[column][int(i)] for row in self._bolt_rows])

    def bolt_force(self, i) -> np.ndarray:
        """(n,) axial force of bolt ``i`` (N per m of thickness), tension positive, at the
        recorded steps; 0 once it has broken."""
        return self._bolt_column(i, 0).astype(float).reshape(-1)

    def bolt_broken(self, i) -> np.ndarray:
        """(n,) bool, whether bolt ``i`` has broken by each recorded step."""
        return self._bolt_column(i, 1).astype(bool).reshape(-1)

    @property
    def scene(self):
        """The :class:`dda.Scene` that was run."""
        return self._scene

    def joint_pairs(self) -> list[tuple]:
        """Every pair of blocks (lower index first) that carried a force at some recorded
        step, as (Block, Block)."""
        keys = np.unique(np.concatenate([k for k, _, _ in self._pairs] + [np.zeros(0, int)]))
        n = len(self._names)
        return [(self._scene.blocks[int(k) // n], self._scene.blocks[int(k) % n])
                for k in keys]

    def profile(self) -> CostProfile:
        """Where the run's time went: seconds per part of the step and the work counts.

        ``print(result.profile())`` shows a table; ``result.profile().summary`` the
        one-line summary of :meth:`StepStats.summary`.
        """
        return CostProfile.from_stats(self.stats)

    def __repr__(self):
        return f"Result({len(self._time)} recorded steps, {len(self._names)} blocks)"

    # ---------------------------------------------------------------- as data
    def _history(self, rows: list, shape: tuple) -> np.ndarray:
        """(n, n_blocks, *shape) the recorded per-block arrays ``rows``, stacked."""
        if not rows:
            return np.zeros((0, len(self._names), *shape))
        return np.stack(rows).reshape(len(rows), len(self._names), *shape)

    def _joint_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """Every pair that carried a force at some recorded step: its sorted
        :func:`~dda.contact.contacts.pair_key` (m,) and its normal and shear force
        (n, m, 2), as :meth:`joint_force` gives them (zero where the pair carried none)."""
        n_time = len(self._time)
        counts = np.array([len(k) for k, _, _ in self._pairs], dtype=np.int64)
        if counts.sum() == 0:
            return np.zeros(0, dtype=np.int64), np.zeros((n_time, 0, 2))
        keys = np.concatenate([k for k, _, _ in self._pairs])
        unique, column = np.unique(keys, return_inverse=True)
        force = np.zeros((n_time, len(unique), 2))
        normal = np.zeros((n_time, len(unique), 2))
        row = np.repeat(np.arange(n_time), counts)
        force[row, column] = np.concatenate([f for _, f, _ in self._pairs]).reshape(-1, 2)
        normal[row, column] = np.concatenate([n for _, _, n in self._pairs]).reshape(-1, 2)
        return unique, _normal_and_shear(force, normal)

    def to_xarray(self):
        """The recorded history as an :class:`xarray.Dataset` (time x block x component).

        Needs the optional ``xarray`` (``pip install 'dda[data]'``). Every variable has
        ``units`` (SI) and ``long_name`` attributes; the dataset's attributes say what the run
        was (dt, solver, analysis, record_every, gravity, steps, dt cuts, dda version,
        creation time). ``ds.to_netcdf("run.nc")`` writes it (NetCDF3 through scipy when
        netCDF4 is not installed; block names survive as UTF-8 strings).

        Returns
        -------
        xarray.Dataset
            Dimensions ``time`` (s), ``block`` (the block names; ``block_id`` is their
            index), ``component`` (x, y), ``tensor_component`` (xx, yy, xy), ``pair`` (the
            block pairs that carried a force at some recorded step, labelled "a/b", with
            ``block_a``, ``block_b`` and their ids) and ``force_component`` (normal, shear).
            Variables: ``displacement``, ``rotation``, ``velocity``, ``angular_velocity``,
            ``strain_rate``, ``stress``, ``initial_centroid`` and ``joint_force``, and in a
            scene with bolts ``bolt_force`` and ``bolt_broken`` (time x ``bolt``); see
            :mod:`dda.data` for each one's meaning.

        Examples
        --------
        >>> import dda
        >>> from dda.materials import LinearElastic
        >>> scene = dda.Scene(gravity=9.81)
        >>> b = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
        ...                     LinearElastic(young=1e9, poisson=0.2, density=1000.0),
        ...                     name="falling")
        >>> ds = dda.Simulation(scene, dt=0.01).run(duration=0.1).to_xarray()
        >>> ds.displacement.dims, ds.displacement.attrs["units"]
        (('time', 'block', 'component'), 'm')
        >>> round(float(ds.displacement.sel(block="falling", component="y")[-1]), 6)
        -0.04905
        """
        from dda.data import result_dataset

        return result_dataset(self)


@dataclass
class CostProfile:
    """The cost of a run: seconds per part of the step and what the solver did.

    Attributes
    ----------
    steps : steps taken
    wall : wall time of the steps (s), retries included
    seconds : seconds per part (:data:`dda.profiling.SECTIONS`) and ``other`` (the rest:
        block matrices, Newmark update, bookkeeping)
    contacts_mean, contacts_max : tracked vertex-edge contacts per step
    open_close_passes, iterations, solves : totals over the run (iterations: Newton
        iterations after OPEN-CLOSE, or legacy's solves)
    cuts : dt cuts
    summary : the one-line summary (:meth:`StepStats.summary`)
    batched : steps taken in batches of one kernel call (:mod:`dda.compiled_run`), whose
        time is all under ``solve``
    kernel_time : seconds of the run in which numba compiled the kernels or loaded them
        from its cache (most of it inside the steps' ``wall``, in the parts that first called
        them)
    """

    steps: int
    wall: float
    seconds: dict
    contacts_mean: float
    contacts_max: int
    open_close_passes: int
    iterations: int
    solves: int
    cuts: int
    summary: str
    batched: int = 0
    kernel_time: float = 0.0

    @classmethod
    def from_stats(cls, stats: StepStats) -> CostProfile:
        n = len(stats)
        seconds = {name: float(stats[f"{name}_time"].sum()) if n else 0.0 for name in SECTIONS}
        wall = float(stats["wall_time"].sum()) if n else 0.0
        seconds["other"] = max(wall - sum(seconds.values()), 0.0)
        contacts = stats["contacts"] if n else np.zeros(1)
        return cls(
            steps=n, wall=wall, seconds=seconds, contacts_mean=float(contacts.mean()),
            contacts_max=int(contacts.max()),
            open_close_passes=int(stats["open_close_passes"].sum()) if n else 0,
            iterations=int(stats["iterations"].sum()) if n else 0,
            solves=int(stats["solves"].sum()) if n else 0, cuts=len(stats.cuts),
            summary=stats.summary(), batched=int(getattr(stats, "batched", 0)),
            kernel_time=float(getattr(stats, "kernel_time", 0.0)),
        )

    def fractions(self) -> dict:
        """Share of the wall time per part (sums to 1 when any time was spent)."""
        return {k: (v / self.wall if self.wall > 0 else 0.0) for k, v in self.seconds.items()}

    def __str__(self) -> str:
        lines = [self.summary]
        if not self.steps:
            return lines[0]
        per = 1e3 / self.steps
        lines.append(f"{'part':16s} {'s':>9s} {'ms/step':>9s} {'share':>7s}")
        for name, sec in self.seconds.items():
            lines.append(f"{name:16s} {sec:9.3f} {sec * per:9.3f} "
                         f"{100 * self.fractions()[name]:6.1f}%")
        lines.append(
            f"contacts {self.contacts_mean:.1f} on average (max {self.contacts_max}); "
            f"{self.open_close_passes / self.steps:.2f} OPEN-CLOSE passes, "
            f"{self.iterations / self.steps:.2f} iterations and "
            f"{self.solves / self.steps:.2f} linear solves per step")
        if self.batched:
            lines.append(f"{self.batched} of the {self.steps} steps in batches of one kernel "
                         "call (dda.compiled_run): their time is all under solve")
        if self.kernel_time >= KERNEL_NOTE * max(self.wall, 1e-9):
            lines.append(f"numba compiled its kernels or loaded them from its cache for "
                         f"{self.kernel_time:.3g} s of the run (a process's first steps; an "
                         "install's first run compiles them, once): the parts above include it "
                         "where it fell in them")
        return "\n".join(lines)
