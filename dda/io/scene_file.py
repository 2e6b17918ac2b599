"""Scene files: a TOML description of everything the Python API can say about a run.

``dda.load_scene(path)`` reads one into a :class:`LoadedScene` (the :class:`dda.Scene`, its
blocks by name, the solver and run settings); ``loaded.simulation()`` builds the
:class:`dda.Simulation` and ``loaded.run()`` runs it with the file's output settings. An
error names the file, the line and the key, for example
``slope.toml, line 14, blocks[2].material: no material 'rok' (there are: rock)``.

The format (every table may be left out but ``[simulation]`` with its ``dt``, some
``[[blocks]]`` or ``[[cut]]``, and, with two blocks or more, ``[joints.default]`` or a
``[[joints.pair]]`` for every two blocks)::

    [scene]
    gravity = 9.81                        # 0 or absent: no gravity
    max_blocks = 1000000                  # optional limits (these are the defaults): a cut
    max_vertices = 100000                 # or a block past them is refused at once

    [materials.rock]                      # any number of named materials
    young = 10e9
    poisson = 0.25
    density = 2600.0
    plane = "stress"                      # or "strain"

    [joints.default]                      # the default joint; [[joints.pair]] for one pair
    normal_penalty = 5e10                 # or "auto", chosen from the scene and dt
    shear_penalty = 5e10
    friction = { law = "coulomb", phi = 35.0, cohesion = 0.0 }
    restitution = 0.0                     # optional impact dashpot: 0 (default) no bounce, 1 none
    shear_dashpot = true                  # optional: damp the shear springs too (default)
    # law = "transition": phi_static, phi_dynamic, onset ("face", or the papers' "contact")
    # law = "barton": jrc, jcs, phi_r, ...
    # law = "my_laws:BrittleCohesion": a law of your own, by import path (see below)

    [[joints.pair]]
    between = ["base", "top"]
    normal_penalty = 1e9
    shear_penalty = 1e9
    friction = { law = "coulomb", phi = 20.0 }

    [[blocks]]
    name = "base"
    material = "rock"
    vertices = [[0, 0], [4, 0], [4, 1], [0, 1]]
    fixed = true                          # also: rigid, velocity, angular_velocity,
                                          # stress = [sxx, syy, sxy] (Pa, tension +)

    [[cut]]                               # blocks cut from a domain by joint sets
    name = "rock"                         # blocks rock0, rock1, ... (bottom to top)
    material = "rock"
    domain = [[1, 1], [3, 1], [3, 3], [1, 3]]
    min_size = 0.05
    seed = 0
    joint_sets = [{ dip = 30, spacing = 0.5, offset = 0.1 },
                  { dip = -60, spacing = 0.7, persistence = 0.8, trace_length = 2.0 }]
    # openings = [[[1.8, 1.8], [2.2, 1.8], [2.2, 2.2], [1.8, 2.2]]]  # excavations taken
                                          # out before the cut (outlines of [x, y])

    [initial_stress]                      # optional: an in-situ stress (Pa, tension +)
    stress = [0, 0, 0]                    # at top, and per metre below it:
    per_depth = [-13000, -26000, 0]       # sxx, syy, sxy (k0 = 0.5, 2,650 kg/m^3)
    top = 3.0                             # blocks = ["rock0", ...] (default: all free ones)

    [[shake]]                             # a sine, a table, or a record file
    block = "base"
    sine = { amplitude = 2.94, frequency = 2.0, start = 0.0, direction = [1, 0] }
                                          # form = "from_rest" (the default: the first half
                                          # wave at half amplitude, the table shakes about a
                                          # fixed place) or "sine" (a plain sine, which
                                          # drifts at amplitude / (2 pi frequency) m/s)
    # times = [0, 0.1, ...]  values = [[ax, ay], ...]     or a file (beside the scene file):
    # file = "RSN6_ELC180.AT2"            # PEER NGA (g); K-NET/KiK-net .EW .NS .UD .EW1 ...
                                          # .UD2 (gal, scale factor and mean applied); or a
                                          # CSV of t, ax[, ay] (m/s^2). format = "at2", "knet"
                                          # or "csv" when the suffix does not tell
    # scale = 1.0                         # multiplies the record (and the vertical one)
    # direction = [1, 0]                  # a one-component record acts along this
    # vertical = "MYG0041103111446.UD"    # optional: a second record along (0, 1), at the
                                          # union of both records' sample times
    # baseline = "none"                   # or "mean", "linear", "quadratic": take a trend
                                          # away so the table ends at rest
                                          # (dda.io.records.baseline_correct)

    [[prescribe]]                         # a constant velocity; leave out x or y to free it
    block = "top"
    velocity = { x = 1e-3 }
    penalty = 1e12                        # optional, with points = [[x, y], ...]
    # or a displacement table (linear between samples, held after the last; zero at t = 0):
    # displacement = { times = [0, 1, 2], x = [0, 1e-3, 1e-3] }        (y left out: free)

    [[load]]
    block = "top"
    point = [2.0, 2.0]
    force = [0.0, -1e5]                   # or a table: { times = [0, 1], x = [0, 0],
                                          #               y = [0, -1e5] }  (held after 1 s)

    [[bolt]]                              # a rock bolt: an axial spring between two
    block_a = "top"                       # material points (one block may be fixed)
    point_a = [2.0, 1.8]
    block_b = "base"
    point_b = [2.0, 0.5]
    stiffness = 1e8                       # N/m per m of thickness
    pretension = 5e3                      # optional, N per m (default 0)
    strength = 2e5                        # optional: it breaks above this tension

    [[damping]]                           # Rayleigh damping C = mass M + stiffness K_e
    mass = 0.5                            # 1/s
    stiffness = 1e-4                      # s
    blocks = ["top"]                      # optional: default every block

    [water]                               # hydrostatic pressure on every edge below it
    table = 1.5                           # a level (m), or [[x, y], ...] with x increasing
    unit_weight = 9810.0                  # N/m^3 (the default)

    [simulation]
    dt = 1e-3                             # or "auto" (dda.auto_settings; dda info says why)
    duration = 1.0
    solver = "newton"                     # or "legacy" (see below); tol, max_iter,
                                          # unsettled_predictor: newton's;
                                          # cycle_local, cycle_memory: legacy's
    analysis = "dynamic"                  # also: velocity_carry, max_open_close,
                                          # record_every, max_displacement_ratio,
                                          # penetration_tolerance, locate_reversals
    start = "rest"                        # or "settled": at rest under the loads at t = 0
                                          # (Simulation's start; dda.settling)

    [output]
    prefix = "case"                       # files OUT/case_00000.vtu ... and OUT/case.pvd
    every = 10                            # write every 10th recorded step, or instead
                                          # interval = 0.01: a frame each 0.01 s simulated
                                          # (plain_names = false: units-only field names)
    dir = "out"                           # inside the scene file's folder; --out overrides
    checkpoint = "case.ckpt"              # optional, in the output folder; resume with
    checkpoint_every = 100                # dda.Simulation.resume (see Simulation.run)

Friction laws and solvers are named as :mod:`dda.registry` knows them, each class by its
``name`` attribute: ``law = "coulomb"`` (:class:`dda.contact.CoulombSingle`), ``"transition"``
(:class:`~dda.contact.StaticDynamicTransition`), ``"barton"`` (:class:`~dda.contact.BartonBandis`);
``solver = "newton"`` (:class:`dda.solvers.NewtonRaphson`, the default) or ``"legacy"``
(:class:`~dda.solvers.LegacyPullBack`). The keys beside ``law`` in a friction table, and a
solver's keys in ``[simulation]``, are the keyword arguments of the class's constructor (read
from its signature; an unknown key is an error that lists them). A class registered with
:func:`dda.registry.register_law` or :func:`~dda.registry.register_solver` before the file is
read is named the same way.

A friction law of your own needs no registering: name it by import path, ``"module:Class"``,
with its keyword arguments in the same table::

    friction = { law = "my_laws:BrittleCohesion", phi = 30, cohesion = 5e4 }

- ``my_laws`` is looked for first in the scene file's folder (``my_laws.py`` or a package
  ``my_laws/`` beside it; the folder is on ``sys.path`` only while the module is imported),
  then on the normal path. A dotted path after the colon reaches a nested attribute
  (``"pkg.laws:Outer.Inner"``); no expression is evaluated, but importing the module runs
  its code, as any import does: name only modules you trust.
- The class must be a subclass of :class:`dda.contact.FrictionLaw`. A module not found, an
  attribute not there, an object of another kind, an unknown key and an error raised by the
  constructor are each a :class:`SceneFileError` naming the line of the friction table.
- The module is imported once per process, as any import: an edited module needs a new
  process, and two scene files whose folders hold different modules of one name cannot be
  read in the same process (an error says so).
- A checkpoint of such a run refers to the class by its module: to resume it the module must
  be importable (``cd`` to the scene's folder and ``python -m dda run OUT/RUN.ckpt``, or put
  the folder on ``PYTHONPATH``).
"""

from __future__ import annotations

import csv
import difflib
import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dda import registry
from dda.effects import sampling_interval
from dda.plausibility import PlausibilityWarning, check_direction

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

__all__ = ["load_scene", "LoadedScene", "SceneFileError", "SineAcceleration",
           "ConstantVelocity"]


#: the largest scene file read (bytes): far above any real scene's text, it keeps a runaway
#: file from filling memory before it is even parsed
MAX_FILE_BYTES = 64 * 2**20


class SceneFileError(ValueError):
    """An error in a scene file: ``file, line N, key: what is wrong``."""


#: the forms of :class:`SineAcceleration`
SINE_FORMS = ("from_rest", "sine")


@dataclass(frozen=True)
class SineAcceleration:
    r"""A sine acceleration of ``amplitude`` (m/s^2) and ``frequency`` along ``direction``
    from ``start`` on, that shakes about a fixed place (``form="from_rest"``, the default) or
    a plain sine that drifts (``form="sine"``).

    A table that starts at rest and follows a plain sine, with :math:`\omega = 2\pi f` and
    :math:`\tau = t - t_0` the time since ``start``,

    .. math::

        a = A \sin\omega\tau, \qquad v = \frac{A}{\omega}(1 - \cos\omega\tau), \qquad
        u = \frac{A}{\omega}\Bigl(\tau - \frac{\sin\omega\tau}{\omega}\Bigr),

    moves on at the mean velocity :math:`A/\omega = A/(2\pi f)` and drifts without bound:
    0.55 m/s, 0.53 m in 0.9 s, for 0.7 g at 2 Hz. ``"from_rest"`` runs the first half period
    at half the amplitude,

    .. math::

        a = \tfrac{A}{2} \sin\omega\tau \quad (\tau < T/2), \qquad
        a = A \sin\omega\tau \quad (\tau \ge T/2), \qquad T = 1/f,

    so the velocity the half wave builds, :math:`A/\omega` at :math:`T/2`, is the one the
    full wave needs to have no mean:

    .. math::

        v = -\frac{A}{\omega}\cos\omega\tau, \qquad
        u = \frac{\pi A}{2\omega^2} - \frac{A}{\omega^2}\sin\omega\tau
        \qquad (\tau \ge T/2):

    the table starts at rest with zero acceleration, its acceleration is continuous, and
    after half a period it shakes with amplitude :math:`A/\omega^2` about the place
    :math:`\pi A/(2\omega^2)` from where it started (43 mm about 68 mm for 0.7 g at 2 Hz).
    The peak acceleration :math:`A` is reached from the second half period on.

    A module-level class, not a lambda, so a run from a scene file can be checkpointed. Its
    ``breakpoints`` (``start``, and ``start + T/2`` for ``"from_rest"``, where the
    acceleration has a kink) make :class:`dda.effects.AccelerationHistory` split a step there,
    so the table's motion is integrated exactly.

    Examples
    --------
    >>> table = SineAcceleration(amplitude=6.87, frequency=2.0)
    >>> table(0.125), table(0.375)                   # half, then full amplitude
    ((3.435, 0.0), (-6.87, -0.0))
    >>> round(6.87 / (2 * math.pi * 2.0), 3)          # a plain sine's drift (m/s)
    0.547
    """

    amplitude: float
    frequency: float
    start: float = 0.0
    direction: tuple = (1.0, 0.0)
    form: str = "from_rest"

    def __post_init__(self):
        if self.form not in SINE_FORMS:
            raise ValueError(f"SineAcceleration: form must be {' or '.join(map(repr, SINE_FORMS))}"
                             f", got {self.form!r}")

    @property
    def breakpoints(self) -> tuple:
        """Times where the acceleration has a kink: ``start`` (and ``start + T/2``)."""
        if self.form == "sine" or self.frequency <= 0.0:
            return (self.start,)
        return (self.start, self.start + 0.5 / self.frequency)

    @property
    def drift(self) -> float:
        """Mean velocity (m/s) the table moves on at: ``A / (2 pi f)`` for a plain sine, 0 for
        the default form."""
        if self.form == "sine":
            return self.amplitude / (2.0 * math.pi * self.frequency)
        return 0.0

    def __call__(self, t):
        tau = t - self.start
        if tau < 0.0:
            return (0.0, 0.0)
        a = self.amplitude * math.sin(2.0 * math.pi * self.frequency * tau)
        if self.form == "from_rest" and tau * self.frequency < 0.5:
            a *= 0.5
        return (a * self.direction[0], a * self.direction[1])


@dataclass(frozen=True)
class ConstantVelocity:
    """Displacement ``(vx t, vy t)``; a component given as None is left free."""

    vx: float | None
    vy: float | None

    def __call__(self, t):
        return (None if self.vx is None else self.vx * t,
                None if self.vy is None else self.vy * t)


# ---------------------------------------------------------------------- line numbers
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"""^\s*("[^"]*"|'[^']*'|[A-Za-z0-9_.-]+)\s*=""")


def _split_key(key: str) -> list[str]:
    return [p.strip().strip("\"'") for p in key.split(".")]


def key_lines(text: str) -> dict[tuple, int]:
    """Line (1-based) of every table and top-level key of a TOML text, by path.

    A path is a tuple of names and array-of-table indices, for example
    ``("blocks", 2, "material")``. Keys inside inline tables and multi-line arrays belong to
    the line of the key that opens them.
    """
    lines: dict[tuple, int] = {}
    counts: dict[tuple, int] = {}
    table: tuple = ()
    depth = 0  # open brackets of a multi-line value
    open_string = None  # the delimiter of a multi-line string the line starts inside
    for number, raw in enumerate(text.splitlines(), start=1):
        inside = open_string is not None
        line, open_string = _code_of(raw, open_string)
        if depth == 0 and not inside:
            m = _HEADER.match(raw)
            if m and not _KEY.match(raw):
                path = tuple(_split_key(m.group(2)))
                if m.group(1) == "[[":
                    i = counts.get(path, 0)
                    counts[path] = i + 1
                    table = (*path, i)
                else:
                    table = path
                lines.setdefault(table, number)
                continue
            m = _KEY.match(raw)
            if m:
                lines.setdefault((*table, *_split_key(m.group(1))), number)
        depth += line.count("[") + line.count("{") - line.count("]") - line.count("}")
        depth = max(depth, 0)
    return lines


def _code_of(raw: str, open_string: str | None = None) -> tuple[str, str | None]:
    """A TOML line's code: its strings emptied and its comment cut off, so that a bracket in
    either (``name = "base"  # see [Adachi 2017``) is not counted as one that opens a
    value (every later line lost its number). ``open_string`` is the delimiter of a
    multi-line string (''' or \"\"\") the line starts inside; returns the code and the
    delimiter of a multi-line string still open at its end (None if none)."""
    out, quote, i = [], open_string, 0
    while i < len(raw):
        if quote is None:
            ch = raw[i]
            if ch == "#":
                break
            if raw.startswith('"""', i) or raw.startswith("'''", i):
                quote, i = raw[i:i + 3], i + 3
                out.append(quote[0])
                continue
            if ch in "\"'":
                quote = ch
            out.append(ch)
        elif raw[i] == "\\" and quote[0] == '"':
            i += 1  # an escaped character of a basic string
        elif raw.startswith(quote, i):
            run = len(quote)
            if run == 3:  # a multi-line string ends at the last three of 3 to 5 quotes
                while run < 5 and raw.startswith(quote[0], i + run):
                    run += 1
            i += run - 1
            quote = None
            out.append(raw[i])
        i += 1
    if quote is not None and len(quote) == 1:  # a one-line string left open: not TOML
        quote = None
    return "".join(out), quote


# ---------------------------------------------------------------------- reading
@dataclass
class _Reader:
    """Typed access to the parsed TOML with errors that name the file, line and key."""

    name: str
    lines: dict
    #: the path of the table that made each block, by block name (for errors about blocks)
    origin: dict = field(default_factory=dict)

    def error(self, path: tuple, message: str) -> SceneFileError:
        line = None
        for n in range(len(path), -1, -1):
            if path[:n] in self.lines:
                line = self.lines[path[:n]]
                break
            # a table written only through its subtables ([joint.default]): their first line
            below = [v for k, v in self.lines.items() if n and k[:n] == path[:n]]
            if below:
                line = min(below)
                break
        key = _format_path(path)
        where = f"{self.name}, line {line}" if line else self.name
        return SceneFileError(f"{where}, {key}: {message}" if key else f"{where}: {message}")

    def table(self, data, path, known):
        if not isinstance(data, dict):
            raise self.error(path, f"must be a table, got {type(data).__name__}")
        for key in data:
            if key not in known:
                near = difflib.get_close_matches(str(key), list(known), n=1)
                hint = f"did you mean {near[0]!r}? " if near else ""
                raise self.error((*path, key), f"unknown key ({hint}known here: "
                                 f"{', '.join(sorted(known))})")
        return data

    def number(self, data, path, key, default=None, positive=False):
        if key not in data:
            if default is None:
                raise self.error(path, f"needs '{key}'")
            return default
        v = data[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.error((*path, key), f"must be a finite number, got {v!r}")
        if positive and v <= 0:
            raise self.error((*path, key), f"must be positive, got {v!r}")
        return float(v)

    def number_or_auto(self, data, path, key):
        """A positive number, or the string "auto" (chosen by the simulation)."""
        if data.get(key) == "auto":
            return "auto"
        if isinstance(data.get(key), str):
            raise self.error((*path, key), f"must be a positive number or \"auto\", got "
                             f"{data[key]!r}")
        return self.number(data, path, key, positive=True)

    def points(self, data, path, key, count=None):
        if key not in data:
            raise self.error(path, f"needs '{key}'")
        try:
            a = np.array(data[key], dtype=float)
        except (TypeError, ValueError):
            a = None
        if a is None or a.ndim != 2 or a.shape[1] != 2 or (count and len(a) != count):
            raise self.error((*path, key), "must be a list of [x, y] pairs")
        return a

    def pair(self, data, path, key, default):
        if key not in data:
            return default
        v = data[key]
        if (not isinstance(v, list) or len(v) != 2
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
            raise self.error((*path, key), f"must be [x, y], got {v!r}")
        return (float(v[0]), float(v[1]))

    def call(self, path, fn, *args, **kwargs):
        """Call an API function and turn its ValueError/TypeError into this file's error, and
        its plausibility warnings into warnings that name the file, line and key."""
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PlausibilityWarning)
            try:
                out = fn(*args, **kwargs)
            except SceneFileError:
                raise
            except (ValueError, TypeError) as exc:
                raise self.error(path, str(exc)) from None
        for w in caught:
            if issubclass(w.category, PlausibilityWarning):
                warnings.warn(str(self.error(path, str(w.message))), PlausibilityWarning,
                              stacklevel=3)
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return out


def _format_path(path) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


@dataclass
class LoadedScene:
    """A scene file read into the API's objects.

    Attributes
    ----------
    scene : dda.Scene
    blocks : dict of name -> dda.Block
    solver : the solver named by ``[simulation] solver``
    settings : keyword arguments of :class:`dda.Simulation` (dt, analysis, ...)
    duration : simulated time of ``[simulation] duration`` (None when left out)
    output_dir, prefix, every, interval, plain_names : the ``[output]`` table (output_dir
        None: no files; the last three as :class:`dda.io.VTUWriter` takes them)
    path : the file read
    effects : what the scene holds, in words (gravity, shaking of ..., damping, ...)
    checkpoint, checkpoint_every : the ``[output]`` checkpoint file name (None: none)
    """

    scene: object
    blocks: dict
    solver: object
    settings: dict
    duration: float | None
    output_dir: Path | None
    prefix: str
    every: int
    path: Path
    effects: list = field(default_factory=list)
    checkpoint: str | None = None
    checkpoint_every: int = 100
    interval: float | None = None
    plain_names: bool = True

    def simulation(self):
        """The :class:`dda.Simulation` of this scene with the file's settings.

        Its plausibility warnings were given when the file was read, with the file's line:
        they are not repeated here."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlausibilityWarning)
            return self._new_simulation()

    def _new_simulation(self):
        from dda.simulation import Simulation

        return Simulation(self.scene, solver=self.solver, **self.settings)

    def run(self, duration=None, out=None, progress=None):
        """Run the scene for ``duration`` (default: the file's), writing to ``out`` or the
        file's ``[output] dir``; returns the :class:`dda.Result`."""
        duration = self.duration if duration is None else duration
        if duration is None:
            raise SceneFileError(f"{self.path.name}: give [simulation] duration (or a "
                                 "duration)")
        return self.simulation().run(duration, output=self.writer(out), progress=progress,
                                     **self.checkpoint_settings(out))

    def output_folder(self, out=None) -> Path | None:
        """The folder files go to: ``out``, else the file's ``[output] dir`` (None: none)."""
        return Path(out) if out is not None else self.output_dir

    def checkpoint_settings(self, out=None) -> dict:
        """``checkpoint`` and ``checkpoint_every`` keyword arguments of
        :meth:`dda.Simulation.run` (empty without ``[output] checkpoint``)."""
        if self.checkpoint is None:
            return {}
        folder = self.output_folder(out)
        path = Path(self.checkpoint) if folder is None else folder / self.checkpoint
        return {"checkpoint": path, "checkpoint_every": self.checkpoint_every}

    def writer(self, out=None):
        """The VTU writer of the ``[output]`` table (``out`` overrides its folder)."""
        from dda.io.vtu import VTUWriter

        folder = self.output_folder(out)
        if folder is None:
            return None
        return VTUWriter(folder / self.prefix, every=self.every, interval=self.interval,
                         plain_names=self.plain_names)


#: the tables of a scene file, in the order they are read
_TABLES = ("scene", "materials", "blocks", "cut", "initial_stress", "joints", "shake",
           "prescribe", "load", "bolt", "damping", "water", "simulation", "output")


def load_scene(path, allow_outside_output: bool = False) -> LoadedScene:
    """Read a TOML scene file (format in :mod:`dda.io.scene_file`).

    ``[output] dir`` must stay inside the scene file's folder (a scene file from someone
    else cannot write elsewhere) unless ``allow_outside_output``; ``prefix`` and
    ``checkpoint`` are file names in it. An explicit output folder given to
    :meth:`LoadedScene.run` (``dda run --out``) goes wherever it says.

    Raises
    ------
    SceneFileError
        Naming the file, the line and the key of the first error.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "drop.toml"
    >>> _ = f.write_text('''
    ... [scene]
    ... gravity = 9.81
    ... [materials.rock]
    ... young = 1e9
    ... poisson = 0.2
    ... density = 2500.0
    ... [[blocks]]
    ... name = "stone"
    ... material = "rock"
    ... vertices = [[0, 0], [1, 0], [1, 1], [0, 1]]
    ... [simulation]
    ... dt = 0.01
    ... duration = 0.1
    ... solver = "legacy"
    ... ''')
    >>> loaded = load_scene(f)
    >>> result = loaded.run()
    >>> round(float(result.displacement(loaded.blocks["stone"])[-1, 1]), 5)
    -0.04905
    """
    path, data, r = _read_file(path)
    scene, effects = _read_scene(r, data)
    materials = _read_materials(r, data)
    # [[blocks]], [simulation] and [output] mirror the arguments of Scene.add_block,
    # Simulation and Simulation.run: their keys are listed here, where a test checks that
    # every setting of the API has one
    blocks = _read_blocks(r, data, materials, scene.add_block, keys={
        "name", "material", "vertices", "fixed", "rigid", "velocity", "angular_velocity",
        "stress"})
    blocks.update(_read_cuts(r, data, materials, scene.add_block))
    if not blocks:
        raise r.error((), "no blocks: add [[blocks]] or [[cut]] tables")
    _read_initial_stress(r, data, blocks, scene.set_initial_stress)
    _read_joints(r, data, blocks, scene.set_joint, path.parent)
    effects += _read_shaking(r, data, blocks, scene.shake, path.parent)
    effects += _read_motions(r, data, blocks, scene.prescribe_motion)
    effects += _read_loads(r, data, blocks, scene.add_point_load)
    effects += _read_bolts(r, data, blocks, scene.add_bolt)
    _read_damping(r, data, blocks, scene.set_damping)
    if scene.damping_coefficients() is not None:
        effects.append("damping")
    effects += _read_water(r, data, scene.set_water_table)
    solver, settings, duration = _read_simulation(r, data, settings=(
        "dt", "analysis", "velocity_carry", "max_open_close", "record_every",
        "max_displacement_ratio", "penetration_tolerance", "locate_reversals", "start"))
    output = _read_output(r, data, path, keys={"dir", "prefix", "every", "interval",
                                               "plain_names", "checkpoint",
                                               "checkpoint_every"},
                          outside=allow_outside_output)
    loaded = LoadedScene(scene, blocks, solver, settings, duration, path=path, effects=effects,
                         **output)
    n = len(scene.block_inputs)
    if n > 1 and scene.default_joint is None and len(scene.pair_joints) < n * (n - 1) // 2:
        raise r.error(("joints",), f"no [joints.default], and [[joints.pair]] for "
                      f"{len(scene.pair_joints)} of the {n * (n - 1) // 2} block pairs: any "
                      "two blocks may touch during a run; add [joints.default] with "
                      "normal_penalty, shear_penalty and friction (or a pair for every two "
                      "blocks)")
    # the Simulation checks the rest (dt, analysis, ...): its messages get the file's line
    r.call(("simulation",), _at_block_lines, r, loaded._new_simulation)
    return loaded


def _at_block_lines(r, make):
    """``make()``, with an overlap of blocks at the start reported at the second block's
    table, the first's line named too."""
    from dda.errors import OverlapError

    try:
        return make()
    except OverlapError as exc:
        first, second = (r.origin.get(b.name) for b in exc.blocks)
        if second is None:
            raise
        line = r.lines.get(first) if first is not None else None
        also = f" ('{exc.blocks[0].name}' is at line {line})" if line else ""
        raise r.error(second, f"{exc}{also}") from None


# ---------------------------------------------------------------------- one reader a table
def _read_file(path):
    """The path, the parsed TOML and a :class:`_Reader` of the file at ``path``."""
    path = Path(path)
    if not path.is_file():
        raise SceneFileError(f"no scene file {path}")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise SceneFileError(f"{path.name}: {size:,} bytes, more than a scene file's "
                             f"{MAX_FILE_BYTES:,} (give large data as a CSV record or cut "
                             "blocks from joint sets)")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SceneFileError(f"{path.name}: not UTF-8 text ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneFileError(f"{path.name}: not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneFileError(f"{path.name}: not a scene file: its arrays or tables nest too "
                             "deeply to read") from None
    r = _Reader(path.name, key_lines(text))
    r.table(data, (), set(_TABLES))
    return path, data, r


def _read_scene(r, data):
    """``[scene]``: the :class:`dda.Scene` and the effects it has (gravity)."""
    from dda.scene import Scene

    sc = r.table(data.get("scene", {}), ("scene",), {"gravity", "max_blocks", "max_vertices"})
    gravity = r.number(sc, ("scene",), "gravity", default=0.0)
    limits = {k: sc[k] for k in ("max_blocks", "max_vertices") if k in sc}
    scene = r.call(("scene",), Scene, gravity=gravity or None, **limits)
    return scene, ["gravity"] if gravity else []


def _read_materials(r, data) -> dict:
    """``[materials.NAME]``: the materials by name."""
    from dda.materials import LinearElastic

    materials = {}
    for name, m in r.table(data.get("materials", {}), ("materials",), set(
            data.get("materials", {}))).items():
        p = ("materials", name)
        r.table(m, p, {"young", "poisson", "density", "plane"})
        kwargs = {k: r.number(m, p, k) for k in ("young", "poisson", "density")}
        if "plane" in m:
            kwargs["plane"] = m["plane"]
        materials[name] = r.call(p, LinearElastic, **kwargs)
    return materials


def _material(r, materials, spec, p):
    """The material a block or cut table names."""
    if "material" not in spec:
        raise r.error(p, "needs 'material'")
    name = spec["material"]
    if name not in materials:
        raise r.error((*p, "material"), f"no material {name!r} (there are: "
                      f"{', '.join(materials) or 'none; add a [materials.NAME] table'})")
    return materials[name]


def _read_blocks(r, data, materials, add_block, keys) -> dict:
    """``[[blocks]]``, each added with ``add_block``: the handles by name."""
    blocks = {}
    for i, b in enumerate(_array(r, data, "blocks")):
        p = ("blocks", i)
        r.table(b, p, keys)
        kwargs = {"fixed": _bool(r, b, p, "fixed"), "rigid": _bool(r, b, p, "rigid"),
                  "velocity": r.pair(b, p, "velocity", (0.0, 0.0)),
                  "angular_velocity": r.number(b, p, "angular_velocity", default=0.0)}
        if "stress" in b:
            kwargs["stress"] = _stress(r, b, p)
        h = r.call(p, add_block, r.points(b, p, "vertices"), _material(r, materials, b, p),
                   name=b.get("name"), **kwargs)
        blocks[h.name] = h
        r.origin[h.name] = p
    return blocks


def _stress(r, table, p) -> tuple:
    """A table's ``stress = [sxx, syy, sxy]`` (Pa, tension positive)."""
    v = table["stress"]
    if (not isinstance(v, list) or len(v) != 3
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
        raise r.error((*p, "stress"), f"must be [sxx, syy, sxy] in Pa, got {v!r}")
    return tuple(float(x) for x in v)


def _read_initial_stress(r, data, blocks, set_initial_stress) -> None:
    """``[initial_stress]``: ``stress = [sxx, syy, sxy]`` (Pa, tension positive) plus, with
    ``per_depth = [a, b, c]`` (Pa/m) and ``top`` (m), ``per_depth x (top - y)`` at each
    block's centroid (an in-situ field that grows with depth); on ``blocks`` (names), by
    default every block that is neither fixed nor rigid (:meth:`dda.Scene.set_initial_stress`).
    It is read after ``[[blocks]]`` and ``[[cut]]`` and replaces their ``stress`` on the
    blocks it covers."""
    if "initial_stress" not in data:
        return
    p = ("initial_stress",)
    t = r.table(data["initial_stress"], p, {"stress", "per_depth", "top", "blocks"})
    base = np.array(_stress(r, t, p) if "stress" in t else (0.0, 0.0, 0.0))
    if ("per_depth" in t) != ("top" in t):
        raise r.error(p, "per_depth and top go together (the stress grows by per_depth "
                         "for each metre below top)")
    if "per_depth" in t:
        grad = np.array(_stress(r, {"stress": t["per_depth"]}, (*p, "per_depth")))
        top = r.number(t, p, "top")
        above = []

        def stress(x, y):
            if y > top:
                above.append(y)
            return tuple(base + grad * (top - y))
    else:
        stress = tuple(base)
    chosen = None
    if "blocks" in t:
        if not isinstance(t["blocks"], list):
            raise r.error((*p, "blocks"), "must be a list of block names")
        chosen = [_block_of(r, blocks, {"block": n}, (*p, "blocks")) for n in t["blocks"]]
    r.call(p, set_initial_stress, stress, chosen)
    if "per_depth" in t and above:
        warnings.warn(str(r.error((*p, "top"), (
            f"{len(above)} block(s) have their centroid above top = {top:g} m (the highest "
            f"at y = {max(above):g} m): per_depth gives them the opposite stress there, "
            "tension for a compressive field"))), PlausibilityWarning, stacklevel=4)


def _read_cuts(r, data, materials, add_block) -> dict:
    """``[[cut]]``: a domain cut by joint sets, each piece added with ``add_block``; the
    handles by name."""
    from dda.cutting import cut_blocks

    blocks = {}
    for i, c in enumerate(_array(r, data, "cut")):
        p = ("cut", i)
        r.table(c, p, {"name", "material", "domain", "joint_sets", "min_size", "seed",
                       "fixed", "rigid", "openings", "stress"})
        stress = {"stress": _stress(r, c, p)} if "stress" in c else {}
        sets = _joint_sets(r, c, p)
        kwargs = {}
        if "openings" in c:
            if not isinstance(c["openings"], list):
                raise r.error((*p, "openings"), "must be a list of outlines, each a list of "
                                                "[x, y] pairs")
            outlines = dict(enumerate(c["openings"]))
            kwargs["openings"] = [r.points(outlines, (*p, "openings"), k) for k in outlines]
        if "min_size" in c:
            kwargs["min_size"] = r.number(c, p, "min_size")
        if "seed" in c:
            kwargs["seed"] = int(r.number(c, p, "seed"))
        scene = add_block.__self__  # the scene's block limit bounds the cut too
        kwargs["max_blocks"] = scene.max_blocks - len(scene.blocks)
        polys = r.call(p, cut_blocks, r.points(c, p, "domain"), sets, **kwargs)
        prefix = c.get("name", f"cut{i}_")
        mat = _material(r, materials, c, p)
        for k, poly in enumerate(polys):
            h = r.call(p, add_block, poly, mat, name=f"{prefix}{k}",
                       fixed=_bool(r, c, p, "fixed"), rigid=_bool(r, c, p, "rigid"), **stress)
            blocks[h.name] = h
            r.origin[h.name] = p
    return blocks


def _joint_sets(r, c, p) -> list:
    """The ``joint_sets`` of a ``[[cut]]`` table."""
    from dda.cutting import JointSet

    if not isinstance(c.get("joint_sets"), list):
        raise r.error(p, "needs 'joint_sets', a list of tables {dip, spacing, ...}")
    sets = []
    for j, js in enumerate(c["joint_sets"]):
        q = (*p, "joint_sets", j)
        r.table(js, q, {"dip", "spacing", "offset", "persistence", "trace_length"})
        sets.append(r.call(q, JointSet, **js))
    return sets


def _block_of(r, blocks, spec, p, key="block"):
    """The block a table names under ``key``."""
    if key not in spec:
        raise r.error(p, f"needs '{key}'")
    name = spec[key]
    if name not in blocks:
        raise r.error((*p, key), f"no block {name!r}")
    return blocks[name]


def _read_joints(r, data, blocks, set_joint, folder):
    """``[joints.default]`` and ``[[joints.pair]]``, each given to ``set_joint`` (a law's
    module named by import path is looked for in ``folder`` first)."""
    joints = r.table(data.get("joints", {}), ("joints",), {"default", "pair"})
    if "default" in joints:
        set_joint(_joint(r, joints["default"], ("joints", "default"), folder))
    for i, jp in enumerate(_array(r, joints, "pair", ("joints", "pair"))):
        p = ("joints", "pair", i)
        if not isinstance(jp.get("between"), list) or len(jp["between"]) != 2:
            raise r.error(p, "needs between = [block, block]")
        for name in jp["between"]:
            if name not in blocks:
                raise r.error((*p, "between"), f"no block {name!r}")
        a, b = (blocks[name] for name in jp["between"])
        r.call(p, set_joint, _joint(r, jp, p, folder, extra=("between",)), between=(a, b))


def _joint(r, spec, p, folder, extra=()):
    """The :class:`dda.contact.JointMaterial` of a joint table."""
    from dda.contact import JointMaterial

    r.table(spec, p, {"normal_penalty", "shear_penalty", "friction", "restitution",
                      "shear_dashpot", *extra})
    law = _read_friction(r, spec.get("friction"), (*p, "friction"), folder)
    optional = {k: spec[k] for k in ("restitution", "shear_dashpot") if k in spec}
    return r.call(p, JointMaterial,
                  normal_penalty=r.number_or_auto(spec, p, "normal_penalty"),
                  shear_penalty=r.number_or_auto(spec, p, "shear_penalty"),
                  friction=law, **optional)


def _read_friction(r, fr, p, folder):
    """The friction law of a joint's ``friction`` table (``p`` is its path): a name of
    :func:`dda.registry.law_names` or an import path ``"module:Class"`` (its module looked for
    in ``folder`` first), with the law's keyword arguments beside it."""
    names = registry.law_names()
    law = fr.get("law") if isinstance(fr, dict) else None
    if not isinstance(law, str) or (law not in names and ":" not in law):
        given = (f"law = {law!r} is none of them: " if isinstance(law, str)
                 else "" if law is None else f"law = {law!r} is not a name: ")
        near = difflib.get_close_matches(law, names, n=1) if isinstance(law, str) else []
        raise r.error(p, f"{given}must be a table with law = "
                      f"{' or '.join(repr(k) for k in names)}, or an import path "
                      "'module:Class'" + (f" (did you mean {near[0]!r}?)" if near else ""))
    try:
        cls = registry.law_class(law, folder=folder)
    except registry.RegistryError as exc:
        raise r.error(p, str(exc)) from None
    args = {k: v for k, v in fr.items() if k != "law"}
    for k in registry.unknown_keywords(cls, args):
        known = ", ".join(sorted(registry.parameters(cls))) or "none"
        raise r.error(p, f"unknown key '{k}' for law {law!r} (known: {known})")
    if law in names:
        return r.call(p, cls, **args)
    try:  # a class of the user's: whatever it raises gets the file's line
        return cls(**args)
    except Exception as exc:
        raise r.error(p, f"law {law!r} raised {type(exc).__name__}: {exc}") from None


_RECORD_KEYS = ("format", "scale", "direction", "vertical", "baseline")


def _read_shaking(r, data, blocks, shake, folder) -> list:
    """``[[shake]]``, each given to ``shake`` (a record file relative to ``folder``); the
    effects."""
    effects = []
    for i, s in enumerate(_array(r, data, "shake")):
        p = ("shake", i)
        r.table(s, p, {"block", "sine", "times", "values", "file", *_RECORD_KEYS})
        h = _block_of(r, blocks, s, p)
        given = [k for k in ("sine", "times", "file") if k in s]
        if len(given) != 1:
            raise r.error(p, "give one of sine = {...}, times + values, or file")
        if "file" not in s:
            for k in _RECORD_KEYS:
                if k in s:
                    raise r.error((*p, k), "goes with file = \"...\" (a record file)")
        if "sine" in s:
            r.call(p, shake, h, acceleration=_sine(r, s["sine"], (*p, "sine")))
        elif "times" in s:
            if "values" not in s:
                raise r.error(p, "times needs values")
            r.call(p, shake, h, acceleration=s["values"], times=s["times"])
        else:
            t, a = _shake_file(r, s, p, folder)
            r.call(p, shake, h, acceleration=a, times=t)
        effects.append(f"shaking of {h}")
    return effects


def _shake_file(r, s, p, folder):
    """Times and (n, 2) accelerations of a ``[[shake]]`` table's ``file`` (and ``vertical``):
    a PEER ``.AT2``, K-NET / KiK-net or CSV file (:mod:`dda.io.records`), scaled by ``scale``,
    its one component along ``direction``, a ``vertical`` one along (0, 1)."""
    from dda.io import records

    fmt = s.get("format")
    if fmt is not None and fmt not in ("at2", "knet", "csv"):
        raise r.error((*p, "format"), f'must be "at2", "knet" or "csv", got {fmt!r}')
    baseline = s.get("baseline", "none")
    if baseline not in records.BASELINES:
        raise r.error((*p, "baseline"), "must be "
                      f"{', '.join(repr(b) for b in records.BASELINES)}, got {baseline!r}")
    scale = r.number(s, p, "scale", default=1.0)
    if scale == 0.0:
        raise r.error((*p, "scale"), "must not be zero")
    t, a = _record_file(r, (*p, "file"), folder, s["file"], fmt, baseline)
    if a.shape[1] == 2:
        for k in ("direction", "vertical"):
            if k in s:
                raise r.error((*p, k), f"{s['file']} has two components (ax, ay): {k} is "
                                       "for a record of one")
        return t, scale * a
    direction = r.pair(s, p, "direction", (1.0, 0.0))
    if direction == (0.0, 0.0):
        raise r.error((*p, "direction"), "must not be [0, 0]")
    check_direction("direction", direction, f"{r.name}, {_format_path((*p, 'direction'))}")
    a = scale * a[:, 0:1] * np.array(direction)[None, :]
    if "vertical" in s:
        tv, av = _record_file(r, (*p, "vertical"), folder, s["vertical"], fmt, baseline)
        if av.shape[1] != 1:
            raise r.error((*p, "vertical"), f"{s['vertical']} has two components: vertical "
                                            "takes a record of one")
        coarser = max(sampling_interval(t), sampling_interval(tv))
        if abs(tv[-1] - t[-1]) > coarser * (1.0 + 1e-9):  # (a sample's difference is none)
            # the shaking covers the time both cover: a run past it is refused, and that
            # message knows only the shaken block
            short, end, other = (("vertical", tv[-1], t[-1]) if tv[-1] < t[-1]
                                 else ("file", t[-1], tv[-1]))
            warnings.warn(str(r.error((*p, short), (
                f"{s[short]} ends at t = {end:g} s, {other - end:.3g} s before "
                f"{s['vertical' if short == 'file' else 'file']}: the shaking covers the "
                f"{end:g} s both records cover"))), PlausibilityWarning, stacklevel=4)
        t, a, av = records.on_common_times(t, a, tv, av)
        a[:, 1] += scale * av[:, 0]
    return t, a


def _record_file(r, path, folder, name, fmt, baseline):
    """Times and (n, k) accelerations of one record file (``name``, relative to ``folder``):
    its format ``fmt`` or the one its suffix tells, its ``baseline`` corrected."""
    from dda.io import records

    if not isinstance(name, str) or not name.strip():
        raise r.error(path, f"must be a file name, got {name!r}")
    file = folder / name
    fmt = fmt or records.guess_format(file)
    if fmt is None:
        raise r.error(path, f"cannot tell the format of {name!r} from its suffix (.AT2; "
                            ".EW .NS .UD, .EW1 ... .UD2; .csv): give format = \"at2\", "
                            "\"knet\" or \"csv\"")
    if fmt == "csv":
        t, a = _read_record(r, path, file)
        return t, r.call(path, records.baseline_correct, t, a, baseline)
    try:
        rec = records.read_record(file, fmt, baseline=baseline)
    except records.RecordError as exc:
        raise r.error(path, str(exc)) from None
    return rec.times, rec.acceleration[:, None]


def _sine(r, spec, q) -> SineAcceleration:
    """The ``sine = {...}`` of a ``[[shake]]`` table (``q`` is its path)."""
    sine = r.table(spec, q, {"amplitude", "frequency", "start", "direction", "form"})
    check_direction("direction", r.pair(sine, q, "direction", (1.0, 0.0)),
                    f"{r.name}, {_format_path(q)}")
    form = sine.get("form", "from_rest")
    if form not in SINE_FORMS:
        raise r.error((*q, "form"), f"must be {' or '.join(map(repr, SINE_FORMS))} (the plain "
                      f"sine drifts at amplitude / (2 pi frequency)), got {form!r}")
    return SineAcceleration(r.number(sine, q, "amplitude"),
                            r.number(sine, q, "frequency", positive=True),
                            r.number(sine, q, "start", default=0.0),
                            r.pair(sine, q, "direction", (1.0, 0.0)), form)


def _read_motions(r, data, blocks, prescribe_motion) -> list:
    """``[[prescribe]]``, each given to ``prescribe_motion``; the effects."""
    effects = []
    for i, m in enumerate(_array(r, data, "prescribe")):
        p = ("prescribe", i)
        r.table(m, p, {"block", "velocity", "displacement", "penalty", "points"})
        h = _block_of(r, blocks, m, p)
        if ("velocity" in m) == ("displacement" in m):
            raise r.error(p, "give one of velocity = {x, y} or displacement = {times, x, y}")
        if "velocity" in m:
            q = (*p, "velocity")
            vel = r.table(m["velocity"], q, {"x", "y"})
            motion = ConstantVelocity(r.number(vel, q, "x") if "x" in vel else None,
                                      r.number(vel, q, "y") if "y" in vel else None)
        else:
            motion = _time_table(r, m["displacement"], (*p, "displacement"),
                                 f"prescribe_motion of {h}")
        kwargs = {}
        if "penalty" in m:
            kwargs["penalty"] = r.number(m, p, "penalty", positive=True)
        if "points" in m:
            kwargs["points"] = r.points(m, p, "points")
        r.call(p, prescribe_motion, h, motion, **kwargs)
        effects.append(f"prescribed motion of {h}")
    return effects


def _read_loads(r, data, blocks, add_point_load) -> list:
    """``[[load]]``, each given to ``add_point_load``; the effects."""
    effects = []
    for i, ld in enumerate(_array(r, data, "load")):
        p = ("load", i)
        r.table(ld, p, {"block", "point", "force"})
        h = _block_of(r, blocks, ld, p)
        if "point" not in ld or "force" not in ld:
            raise r.error(p, "needs point and force")
        if isinstance(ld["force"], dict):
            force = _time_table(r, ld["force"], (*p, "force"), f"point load on {h}",
                                both=True)
        else:
            force = r.pair(ld, p, "force", None)
        r.call(p, add_point_load, h, r.pair(ld, p, "point", None), force)
        effects.append(f"point load on {h}")
    return effects


def _read_bolts(r, data, blocks, add_bolt) -> list:
    """``[[bolt]]``, each given to ``add_bolt`` (:meth:`dda.Scene.add_bolt`); the effects."""
    effects = []
    for i, b in enumerate(_array(r, data, "bolt")):
        p = ("bolt", i)
        r.table(b, p, {"block_a", "point_a", "block_b", "point_b", "stiffness", "pretension",
                       "strength"})
        ha, hb = _block_of(r, blocks, b, p, "block_a"), _block_of(r, blocks, b, p, "block_b")
        for key in ("point_a", "point_b"):
            if key not in b:
                raise r.error(p, f"needs '{key}'")
        stiffness = r.number(b, p, "stiffness")
        pretension = r.number(b, p, "pretension", default=0.0)
        strength = r.number(b, p, "strength") if "strength" in b else None
        index = r.call(p, add_bolt, ha, r.pair(b, p, "point_a", None), hb,
                       r.pair(b, p, "point_b", None), stiffness, pretension=pretension,
                       strength=strength)
        more = f", pretension {pretension:g} N/m" if pretension else ""
        more += "" if strength is None else f", strength {strength:g} N/m"
        effects.append(f"bolt {index} from {ha} to {hb} ({stiffness:g} N/m{more})")
    return effects


def _read_damping(r, data, blocks, set_damping):
    """``[[damping]]`` (or one ``[damping]`` table), each given to ``set_damping``."""
    damping = data.get("damping", [])
    for i, dm in enumerate([damping] if isinstance(damping, dict) else
                           _array(r, data, "damping")):
        p = ("damping",) if isinstance(damping, dict) else ("damping", i)
        r.table(dm, p, {"mass", "stiffness", "blocks"})
        names = dm.get("blocks")
        if names is not None:
            if not isinstance(names, list):
                raise r.error((*p, "blocks"), "must be a list of block names")
            for name in names:
                if name not in blocks:
                    raise r.error((*p, "blocks"), f"no block {name!r}")
        r.call(p, set_damping, mass=r.number(dm, p, "mass", default=0.0),
               stiffness=r.number(dm, p, "stiffness", default=0.0),
               blocks=None if names is None else [blocks[n] for n in names])


def _read_water(r, data, set_water_table) -> list:
    """``[water]``: ``table`` (a level, or [[x, y], ...]) and ``unit_weight``."""
    if "water" not in data:
        return []
    p = ("water",)
    w = r.table(data["water"], p, {"table", "unit_weight"})
    if "table" not in w:
        raise r.error(p, "needs 'table': a level (m) or a polyline [[x, y], ...]")
    table = w["table"]
    table = r.number(w, p, "table") if not isinstance(table, list) else r.points(w, p, "table")
    r.call(p, set_water_table, table,
           unit_weight=r.number(w, p, "unit_weight", default=9810.0, positive=True))
    return ["water table"]


def _read_simulation(r, data, settings):
    """``[simulation]``: the solver, the :class:`dda.Simulation` keyword arguments (the keys
    ``settings`` that are given; dt always) and the duration (None when left out)."""
    p = ("simulation",)
    solver_keys = _solver_keys(settings)
    sim = r.table(data.get("simulation", {}), p, {*settings, "duration", "solver",
                                                   *solver_keys})
    solver = _read_solver(r, sim, p, solver_keys)
    kwargs = {"dt": r.number_or_auto(sim, p, "dt")}
    for k in settings:
        if k != "dt" and k in sim:
            kwargs[k] = sim[k]
    duration = r.number(sim, p, "duration", positive=True) if "duration" in sim else None
    return solver, kwargs, duration


def _solver_keys(settings) -> list:
    """The keys of ``[simulation]`` that set a registered solver (tol, max_iter, ...)."""
    keys = {}
    for name in registry.solver_names():
        for k in registry.parameters(registry.solver_class(name)):
            keys.setdefault(k)
    return [k for k in keys if k not in settings and k not in ("duration", "solver")]


def _read_solver(r, sim, p, solver_keys):
    """The solver of the ``[simulation]`` table ``sim``: a name of
    :func:`dda.registry.solver_names` (default "newton") with its settings beside it."""
    names = registry.solver_names()
    name = sim.get("solver", "newton")
    if not isinstance(name, str) or name not in names:
        shown = " or ".join(repr(n) for n in ("newton", *(n for n in names if n != "newton")))
        raise r.error((*p, "solver"), f"must be {shown}, got {name!r}")
    cls = registry.solver_class(name)
    wrong = [k for k in registry.unknown_keywords(cls, sim) if k in solver_keys]
    if wrong:
        takes = ", ".join(registry.parameters(cls)) or "none"
        what = "is not a setting" if len(wrong) == 1 else "are not settings"
        raise r.error(p, f"{' and '.join(wrong)} {what} of solver = {name!r} (it takes: "
                      f"{takes})")
    return r.call(p, cls, **{k: sim[k] for k in solver_keys if k in sim})


def _read_output(r, data, path, keys, outside=False) -> dict:
    """``[output]``: the :class:`LoadedScene` fields of the output files and checkpoint.

    ``dir`` is a folder relative to the scene file's (the output root), which it may not
    leave (no ``..`` past it, no absolute path, no link that leads out) unless ``outside``;
    ``prefix`` and ``checkpoint`` are file names in it (no folders)."""
    out = r.table(data.get("output", {}), ("output",), keys)
    folder = None
    if "dir" in out:
        folder = _output_dir(r, out["dir"], path.parent, outside)
    fields = {"output_dir": folder,
              "prefix": _file_name(r, out.get("prefix", path.stem), "prefix"),
              "every": _count(r, out, ("output",), "every", 1)}
    checkpoint = out.get("checkpoint")
    if checkpoint is not None:
        checkpoint = _file_name(r, checkpoint, "checkpoint")
    fields["checkpoint"] = checkpoint
    fields["checkpoint_every"] = _count(r, out, ("output",), "checkpoint_every", 100)
    if "interval" in out:
        if "every" in out:
            raise r.error(("output", "interval"), "give every or interval, not both")
        fields["interval"] = r.number(out, ("output",), "interval", positive=True)
    fields["plain_names"] = _bool(r, {"plain_names": True, **out}, ("output",), "plain_names")
    return fields


def _output_dir(r, value, root: Path, outside: bool) -> Path:
    """The ``[output] dir`` folder, inside the scene file's folder unless ``outside``."""
    where = ("output", "dir")
    if not isinstance(value, str) or not value.strip():
        raise r.error(where, f"must be a folder name, got {value!r}")
    folder = Path(value)
    if outside:
        return root / folder
    hint = ("; output stays in the scene file's folder unless the command is given "
            "--allow-outside-output (load_scene(..., allow_outside_output=True))")
    if folder.is_absolute() or folder.drive:
        raise r.error(where, f"{value!r} is an absolute path{hint}")
    if ".." in folder.parts:
        raise r.error(where, f"{value!r} goes up out of the folder with '..'{hint}")
    resolved, top = (root / folder).resolve(), root.resolve()
    if resolved != top and top not in resolved.parents:
        raise r.error(where, f"{value!r} leads out of the scene file's folder (to "
                             f"{resolved}){hint}")
    return root / folder


def _file_name(r, value, key: str) -> str:
    """A file name of ``[output]`` (no folder part, nothing that climbs out)."""
    if (not isinstance(value, str) or not value.strip() or value in (".", "..")
            or "/" in value or "\\" in value or Path(value).name != value):
        raise r.error(("output", key), f"must be a file name (no folders), got {value!r}")
    return value


# ---------------------------------------------------------------------- helpers
def _array(r, data, key, path=None):
    path = path or (key,)
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise r.error(path, f"must be an array of tables ([[{'.'.join(map(str, path))}]])")
    return value


def _count(r, data, path, key, default):
    """A whole number of at least 1."""
    v = data.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise r.error((*path, key), f"must be a whole number of at least 1, got {v!r}")
    return v


def _time_table(r, spec, path, name, both=False):
    """A :class:`dda.effects.TimeTable` from ``{times, x, y}`` or ``{times, values}``; with
    ``both`` a direction left out is zero (a force), else it is free (a motion)."""
    from dda.effects import TimeTable

    r.table(spec, path, {"times", "x", "y", "values"})
    if "times" not in spec:
        raise r.error(path, "needs times = [...] and x = [...], y = [...] or values")
    if "values" in spec:
        if "x" in spec or "y" in spec:
            raise r.error(path, "give values = [[x, y], ...] or x and y columns, not both")
        values = r.points(spec, path, "values")
        x, y = values[:, 0], values[:, 1]
    else:
        x, y = spec.get("x"), spec.get("y")
        if both and (x is None) != (y is None):  # a force: the direction left out is zero
            given = x if x is not None else y
            zeros = [0.0] * len(given) if isinstance(given, list) else None
            x, y = (zeros, y) if x is None else (x, zeros)
    return r.call(path, TimeTable, spec["times"], x, y, name=name)


def _bool(r, data, path, key):
    v = data.get(key, False)
    if not isinstance(v, bool):
        raise r.error((*path, key), f"must be true or false, got {v!r}")
    return v


def _read_record(r, path, file):
    """Times and accelerations (columns t, ax[, ay]) of a CSV file; '#' starts a comment."""
    if not file.is_file():
        raise r.error(path, f"no file {file}")
    rows = []
    with file.open(newline="") as fh:
        for row in csv.reader(line for line in fh if not line.lstrip().startswith("#")):
            if not row:
                continue
            try:
                rows.append([float(v) for v in row])
            except ValueError:
                if rows:  # a header is fine, a bad number later is not
                    raise r.error(path, f"{file.name}: not a number in row {row}") from None
    a = np.array(rows) if rows else np.zeros((0, 0))
    if a.ndim != 2 or a.shape[1] not in (2, 3) or len(a) < 2:
        raise r.error(path, f"{file.name} must have columns t, ax[, ay] and 2 rows or more")
    return a[:, 0], a[:, 1:]
