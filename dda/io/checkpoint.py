"""Checkpoints of a run: the committed state, the scene, the settings and the writer, as data.

:meth:`dda.Simulation.run` writes one every ``checkpoint_every`` steps, on Ctrl-C or SIGTERM
and at the end; :meth:`dda.Simulation.resume` reads it back. A checkpoint is an ``.npz`` file
(numpy's zip of arrays, read with ``allow_pickle=False``) that holds:

- ``header``: JSON text (as bytes): the layout's version, the scene as data
  (:mod:`dda.io.scene_data`), the simulation's settings, its solver by registry name or
  import path and constructor parameters, the step control, the penalty advice's warnings,
  the writer (a :class:`dda.io.VTUWriter` or a subclass: its class's import path and its
  counters), and the run's end time and checkpoint settings;
- the arrays the header names: the scene's vertices and samples, and the committed state
  (vertices, velocities, stresses, contacts and their laws' histories, ...).

Reading one imports the modules that define the classes and functions it names (the scene's
laws, a writer subclass, named time-history functions), looks the names up attribute by
attribute, and checks each is what it must be (a friction law, a solver, a VTU writer, a plain
function) before using it. Nothing else in the file is run: no pickle is ever loaded, so a
file made to run code when unpickled (or any file that is not a checkpoint) only gives an
error saying what is wrong. A scene whose callables have no import path cannot be saved:
:class:`ValueError` at the start of the run, saying which input and what to give instead.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from dataclasses import asdict, fields, replace
from pathlib import Path

import numpy as np

from dda.io.scene_data import (
    ArrayStore,
    SceneDataError,
    _plain,
    scene_from_data,
    scene_to_data,
)

__all__ = ["CHECKPOINT_VERSION", "checkpoint_payload", "write_checkpoint", "read_checkpoint"]

# layout of the checkpoint files (2: Simulation.damping; 3: the penetration guard;
# 4: Model, StepState and StepControl; 5: data, not a pickle; 6: record_every's count)
CHECKPOINT_VERSION = 6
#: the layouts this version reads (5 resumes with record_every's count from 0)
READABLE_VERSIONS = (5, 6)
FORMAT = "dda checkpoint"

_STATE_ARRAYS = ("x", "velocity", "stress", "rotation", "centroid", "load_points",
                 "spring_points", "known_u")
_CONTACT_ARRAYS = {"vertex": np.int64, "edge": np.int64, "bj": np.int64, "bk": np.int64,
                   "state": np.int8, "xi0": float, "t_n": float, "t_s": float}
_WRITER_FIELDS = ("prefix", "every", "_entries", "_n", "_seen", "last_time")


class CheckpointError(ValueError):
    """A checkpoint that cannot be written or read (the message says why)."""


# ---------------------------------------------------------------------- writing
def checkpoint_payload(simulation, writer, end: float, path, every: int) -> bytes:
    """The bytes of a checkpoint; a ``ValueError`` saying what to do when the simulation
    cannot be saved (a callable of its scene without an import path, a writer that is not
    a VTU writer)."""
    store = ArrayStore()
    try:
        header = {
            "format": FORMAT, "version": CHECKPOINT_VERSION,
            "scene": scene_to_data(simulation.scene, store),
            "simulation": _simulation_to_data(simulation, store),
            "state": _state_to_data(simulation.committed, store,
                                    simulation.model.origin),
            "control": asdict(simulation.control),
            "warned": sorted(simulation.advisor.warned),
            "writer": _writer_to_data(writer, Path(path)),
            "written": _written_to_data(simulation._written, writer),
            "record_since": int(simulation._record_since),
            "end": float(end), "checkpoint": [str(path), int(every)],
        }
    except SceneDataError as exc:
        raise ValueError(f"Simulation.run: checkpoint cannot save this simulation: {exc}") \
            from None
    buffer = io.BytesIO()
    np.savez(buffer, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8),
             **{f"a/{k}": v for k, v in store.arrays.items()})
    return buffer.getvalue()


def write_checkpoint(path, payload: bytes) -> None:
    """Write ``payload`` to a temporary name and rename it: an interruption never leaves a
    half-written checkpoint."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(payload)
    os.replace(tmp, path)


def _simulation_to_data(sim, store) -> dict:
    from dda import registry

    solver = sim.solver
    cls = type(solver)
    try:
        registered = registry.solver_class(getattr(cls, "name", "")) is cls
    except registry.RegistryError:
        registered = False
    if registered:
        name = cls.name
    elif cls.__module__ == "__main__" or "<" in cls.__qualname__:
        raise SceneDataError(f"the solver {cls.__name__} is defined in the script run as a "
                             "program; define it in a module you import")
    else:
        name = f"{cls.__module__}:{cls.__qualname__}"
    params = {}
    for p in registry.parameters(cls):
        if not hasattr(solver, p):
            raise SceneDataError(f"the solver {cls.__name__} does not keep its parameter {p!r} "
                                 "as an attribute of the same name")
        params[p] = _plain(getattr(solver, p), f"the solver's {p}")
    joints = sim.model.joints
    return {
        "dt": float(sim.dt), "solver": {"name": name, "parameters": params},
        "analysis": sim.analysis, "velocity_carry": float(sim.velocity_carry),
        "max_open_close": int(sim.max_open_close), "record_every": int(sim.record_every),
        "max_displacement_ratio": float(sim.max_displacement_ratio),
        "penetration_tolerance": float(sim.penetration_tolerance), "choices": sim.choices,
        "locate_reversals": bool(sim.locate_reversals), "start": sim.start,
        "settling": None if sim.settling is None else asdict(sim.settling),
        "normal_penalty": store.put("model/normal_penalty", joints.normal_penalty),
        "shear_penalty": store.put("model/shear_penalty", joints.shear_penalty),
    }


def _state_to_data(state, store, origin=None) -> dict:
    c = state.contacts
    for name, value in c.history.items():
        store.put(f"state/history/{name}", value)
    for name in _CONTACT_ARRAYS:
        store.put(f"state/contacts/{name}", getattr(c, name))
    store.put("state/contacts/held_ago", c.held_ago)
    for name in _STATE_ARRAYS:
        store.put(f"state/{name}", getattr(state, name))
    if len(state.bolt_broken):  # the bolts' ends and broken flags (a scene with bolts)
        store.put("state/bolt_points", state.bolt_points)
        store.put("state/bolt_broken", state.bolt_broken)
    shaking = []
    for s in state.shaking:
        if s is None:
            shaking.append(None)
        else:
            t, v, u = s
            shaking.append({"t": float(t), "v": [float(x) for x in v],
                            "u": [float(x) for x in u]})
    # the positions are in the model's coordinates, which start at its origin (a scene far
    # from (0, 0): dda.geometry.site_origin)
    origin = [0.0, 0.0] if origin is None else [float(v) for v in origin]
    return {"time": float(state.time), "last_move": float(state.last_move),
            "untracked": float(state.untracked), "penetration": float(state.penetration),
            "history": sorted(c.history), "shaking": shaking, "origin": origin}


def _writer_to_data(writer, checkpoint: Path) -> dict | None:
    from dda.io.vtu import VTUWriter

    if writer is None:
        return None
    cls = type(writer)
    if not isinstance(writer, VTUWriter):
        raise SceneDataError(
            f"its writer is a {cls.__name__}: a checkpoint keeps a dda.io.VTUWriter (or a "
            "subclass of it) or no writer")
    if cls.__module__ == "__main__" or "<" in cls.__qualname__:
        raise SceneDataError(f"its writer's class {cls.__name__} is defined in the script run "
                             "as a program; define it in a module you import")
    state = {k: v for k, v in vars(writer).items() if not k.startswith("_pvd")}
    extra = {}
    for k, v in state.items():
        if k not in _WRITER_FIELDS:
            extra[k] = _plain(v, f"its writer's attribute {k!r}")
    inside = None  # the prefix relative to the checkpoint's folder, when it is in it
    rel = os.path.relpath(os.path.abspath(writer.prefix), os.path.abspath(checkpoint.parent))
    if ".." not in Path(rel).parts and not os.path.isabs(rel):
        inside = Path(rel).as_posix()
    return {"class": f"{cls.__module__}:{cls.__qualname__}", "prefix": str(writer.prefix),
            "inside": inside,
            "every": int(writer.every),
            "entries": [[float(t), str(name)] for t, name in writer._entries],
            "n": int(writer._n), "seen": int(writer._seen),
            "last_time": None if writer.last_time is None else float(writer.last_time),
            "extra": extra}


def _written_to_data(written, writer) -> dict | None:
    last_writer, time = written
    if last_writer is None or time is None:
        return None
    # the writer of the last frame written is the one saved, or an earlier run's (not kept)
    return {"same_writer": last_writer is writer, "time": float(time)}


# ---------------------------------------------------------------------- reading
def read_checkpoint(path, allow_outside_output: bool = False) -> dict:
    """The checkpoint's contents: ``simulation``, ``writer``, ``end`` and ``checkpoint``.

    The run goes on writing its checkpoint to ``path`` (not to where the file says it was
    written), and its VTU series where it was, relative to ``path``'s folder: a writer whose
    files were not in that folder (or below it) is refused unless ``allow_outside_output``,
    so a checkpoint from someone else writes nowhere but beside itself."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"Simulation.resume: no checkpoint file {path}")
    try:
        header, store = _open(path)
        data = _restore(header, store, path, allow_outside_output)
        return data
    except CheckpointError as exc:
        raise ValueError(f"Simulation.resume: {path}: {exc}") from None
    except SceneDataError as exc:
        raise ValueError(f"Simulation.resume: {path}: {exc}") from None


def _open(path: Path):
    """The header and the arrays of a checkpoint file, checked for their layout."""
    if not zipfile.is_zipfile(path):
        raise CheckpointError(
            "not a checkpoint of this version of dda: not an .npz file (a checkpoint written "
            f"by dda before layout {READABLE_VERSIONS[0]} was a pickle, which is never loaded: "
            "it could run any code; start the run again)")
    try:
        with np.load(path, allow_pickle=False) as f:
            arrays = {k: f[k] for k in f.files}
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
        raise CheckpointError(f"not a readable checkpoint ({exc})") from None
    raw = arrays.pop("header", None)
    if raw is None or raw.dtype != np.uint8 or raw.ndim != 1:
        raise CheckpointError("not a checkpoint: it has no header")
    try:
        header = json.loads(raw.tobytes().decode())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CheckpointError(f"not a checkpoint: its header is not JSON ({exc})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise CheckpointError("not a checkpoint: its header is not a dda checkpoint's")
    version = header.get("version")
    if type(version) is not int or version not in READABLE_VERSIONS:
        raise CheckpointError(f"not a checkpoint of this version of dda (layout "
                              f"{version!r}, this version reads "
                              f"{' and '.join(map(str, READABLE_VERSIONS))})")
    keys = {"format", "version", "scene", "simulation", "state", "control", "warned",
            "writer", "written", "end", "checkpoint"}
    if version >= 6:
        keys.add("record_since")
    # (layout 5 as written by the commits that began record_since may carry it)
    if set(header) != keys and not (version == 5 and set(header) == keys | {"record_since"}):
        missing, extra = sorted(keys - set(header)), sorted(set(header) - keys)
        raise CheckpointError(f"its header is incomplete or has more than a checkpoint's "
                              f"(missing {missing}, unknown {extra})")
    store = ArrayStore({k[2:]: v for k, v in arrays.items() if k.startswith("a/")})
    return header, store


def _restore(header: dict, store: ArrayStore, path: Path, outside: bool) -> dict:
    from dda.settling import Settling
    from dda.simulation import Simulation

    scene = scene_from_data(header["scene"], store)
    s = header["simulation"]
    if isinstance(s, dict):  # a checkpoint written before slip reversals were located, or
        # before a settled start
        s = {"locate_reversals": False, "start": "rest", "settling": None, **s}
    _expect(s, "simulation", {"dt", "solver", "analysis", "velocity_carry", "max_open_close",
                              "record_every", "max_displacement_ratio",
                              "penetration_tolerance", "choices", "normal_penalty",
                              "shear_penalty", "locate_reversals", "start", "settling"})
    if not isinstance(s["locate_reversals"], bool):
        raise CheckpointError("simulation.locate_reversals: not true or false")
    settling = s["settling"]
    if settling is not None:
        try:
            settling = Settling.from_data(settling)
        except ValueError as exc:
            raise CheckpointError(f"simulation.settling: {exc}") from None
    try:
        sim = Simulation(scene, dt=s["dt"], solver=_solver(s["solver"]),
                         analysis=s["analysis"], velocity_carry=s["velocity_carry"],
                         max_open_close=s["max_open_close"], record_every=s["record_every"],
                         max_displacement_ratio=s["max_displacement_ratio"],
                         penetration_tolerance=s["penetration_tolerance"],
                         locate_reversals=s["locate_reversals"], start=s["start"])
    except (TypeError, ValueError) as exc:
        raise CheckpointError(f"its simulation's settings: {exc}") from None
    joints = sim.model.joints
    n = len(joints.normal_penalty)
    pn = store.get(s["normal_penalty"], "simulation.normal_penalty", shape=(n,))
    ps = store.get(s["shear_penalty"], "simulation.shear_penalty", shape=(n,))
    # the penalties chosen for "auto" joints when the run started (the same choice again
    # for a given dt, but the run may have chosen dt too)
    sim.model.joints = replace(joints, normal_penalty=pn, shear_penalty=ps)
    if not isinstance(s["choices"], str):
        raise CheckpointError("simulation.choices: not a text")
    sim.choices = s["choices"]
    sim.settling = settling  # (a settled start is not settled again)
    sim.committed = _state(header["state"], store, sim.model, sim.committed)
    sim.control = _control(header["control"], sim.control)
    warned = header["warned"]
    if not (isinstance(warned, list) and all(w in ("soft", "stiff") for w in warned)):
        raise CheckpointError("warned: not a list of the penalty advice's warnings")
    sim.advisor.warned = set(warned)
    writer = _writer(header["writer"], path, outside)
    sim._written = _written(header["written"], writer)
    since = header.get("record_since", 0)  # (none in a layout 5 checkpoint)
    if isinstance(since, bool) or not isinstance(since, int) or not 0 <= since < sim.record_every:
        raise CheckpointError(f"record_since: not a count of steps below record_every "
                              f"({sim.record_every})")
    sim._record_since = since
    end = header["end"]
    ck = header["checkpoint"]
    if (isinstance(end, bool) or not isinstance(end, (int, float)) or not np.isfinite(end)
            or not (isinstance(ck, list) and len(ck) == 2 and isinstance(ck[0], str)
                    and isinstance(ck[1], int) and not isinstance(ck[1], bool) and ck[1] >= 1)):
        raise CheckpointError("end / checkpoint: not a time and [path, every]")
    return {"simulation": sim, "writer": writer, "end": float(end),
            "checkpoint": (str(path), ck[1])}


def _expect(data, where: str, keys: set) -> dict:
    if not isinstance(data, dict) or set(data) != keys:
        got = sorted(data) if isinstance(data, dict) else type(data).__name__
        raise CheckpointError(f"{where}: expected the keys {sorted(keys)}, got {got}")
    return data


def _solver(data):
    from dda import registry

    _expect(data, "simulation.solver", {"name", "parameters"})
    if not isinstance(data["name"], str) or not isinstance(data["parameters"], dict):
        raise CheckpointError("simulation.solver: not a name and parameters")
    try:  # the registry checks the class is a NonlinearSolver before making one
        return registry.make_solver(data["name"], **data["parameters"])
    except (registry.RegistryError, TypeError, ValueError) as exc:
        raise CheckpointError(f"simulation.solver: {exc}") from None


def _state(data, store, model, initial):
    from dda.contact.contacts import HELD_NEVER, ContactSet
    from dda.step import StepState

    # a checkpoint written before models had an origin holds the scene's coordinates
    data = {"origin": [0.0, 0.0], **data}
    _expect(data, "state", {"time", "last_move", "untracked", "penetration", "history",
                            "shaking", "origin"})
    raw = data["origin"]
    if not (isinstance(raw, list) and len(raw) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in raw)):
        raise CheckpointError("state.origin: not a point")
    saved = np.array(raw, dtype=float)
    if not np.all(np.isfinite(saved)):
        raise CheckpointError("state.origin: not a point")
    shift = saved - model.origin
    arrays = {}
    for name in _STATE_ARRAYS:
        like = getattr(initial, name)
        arrays[name] = store.get({"array": f"state/{name}"}, f"state.{name}",
                                 shape=tuple(like.shape))
    c = {name: store.get({"array": f"state/contacts/{name}"}, f"state.contacts.{name}",
                         dtype=dtype, shape=(None,))
         for name, dtype in _CONTACT_ARRAYS.items()}
    m = len(c["vertex"])
    if any(len(a) != m for a in c.values()):
        raise CheckpointError("state.contacts: its arrays differ in length")
    n_vertices, n_blocks = len(model.topo.block), model.n_blocks
    for name, top in (("vertex", n_vertices), ("edge", n_vertices), ("bj", n_blocks),
                      ("bk", n_blocks)):
        if m and (c[name].min() < 0 or c[name].max() >= top):
            raise CheckpointError(f"state.contacts.{name}: out of the scene's range")
    if m and (c["state"].min() < 0 or c["state"].max() > 2):
        raise CheckpointError("state.contacts.state: not open, stick or slip")
    names = data["history"]
    if not (isinstance(names, list) and all(isinstance(k, str) for k in names)):
        raise CheckpointError("state.history: not a list of names")
    history = {k: store.get({"array": f"state/history/{k}"}, f"state.history.{k}",
                            shape=(m,)) for k in names}
    shaking = []
    raw = data["shaking"]
    if not isinstance(raw, list) or len(raw) != len(model.shakes):
        raise CheckpointError("state.shaking: one entry per shaken block expected")
    for i, s in enumerate(raw):
        if s is None:
            shaking.append(None)
            continue
        _expect(s, f"state.shaking[{i}]", {"t", "v", "u"})
        try:
            shaking.append((float(s["t"]), np.array(s["v"], dtype=float).reshape(2),
                            np.array(s["u"], dtype=float).reshape(2)))
        except (TypeError, ValueError):
            raise CheckpointError(f"state.shaking[{i}]: not a time and two pairs") from None
    numbers = {}
    for k in ("time", "last_move", "untracked", "penetration"):
        v = data[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise CheckpointError(f"state.{k}: not a number")
        numbers[k] = float(v)
    ago = None  # (a checkpoint written before the cycle rule's memory: never held)
    if "state/contacts/held_ago" in store.arrays:
        ago = store.get({"array": "state/contacts/held_ago"}, "state.contacts.held_ago",
                        dtype=np.int64, shape=(m,))
        if m and (ago.min() < 1 or ago.max() > HELD_NEVER):
            raise CheckpointError("state.contacts.held_ago: not a count of steps")
    contacts = ContactSet(c["vertex"], c["edge"], c["bj"], c["bk"], c["state"], c["xi0"],
                          c["t_n"], c["t_s"], history, ago)
    if model.bolts is not None:
        n_bolts = len(model.bolts)
        arrays["bolt_points"] = store.get({"array": "state/bolt_points"}, "state.bolt_points",
                                          shape=(n_bolts, 2, 2))
        broken = store.get({"array": "state/bolt_broken"}, "state.bolt_broken",
                           dtype=np.int8, shape=(n_bolts,))
        if broken.min(initial=0) < 0 or broken.max(initial=0) > 1:
            raise CheckpointError("state.bolt_broken: not true or false")
        arrays["bolt_broken"] = broken.astype(bool)
    if shift.any():  # the saved positions into this model's coordinates
        for name in ("x", "centroid", "load_points", "spring_points", "bolt_points"):
            if name in arrays:
                arrays[name] = arrays[name] + shift
    return StepState(contacts=contacts, shaking=tuple(shaking), **arrays, **numbers)


def _control(data, initial):
    from dda.step_control import StepControl

    names = {f.name for f in fields(StepControl)}
    if isinstance(data, dict):
        # a checkpoint written before the control remembered the size that failed, before
        # slip reversals were located, or before the natural step (the scene's, as now)
        data = {"ceiling": 0.0, "reversal_wait": 0, "natural_dt": initial.natural_dt, **data}
    _expect(data, "control", names)
    for k, v in data.items():
        kind = type(getattr(initial, k))
        ok = (isinstance(v, bool) if kind is bool else
              isinstance(v, (int, float)) and not isinstance(v, bool))
        if not ok:
            raise CheckpointError(f"control.{k}: {v!r} is not a {kind.__name__}")
    return StepControl(**data)


def _writer(data, checkpoint: Path, outside: bool):
    from dda.io.vtu import VTUWriter
    from dda.registry import RegistryError, import_class

    if data is None:
        return None
    _expect(data, "writer", {"class", "prefix", "inside", "every", "entries", "n", "seen",
                             "last_time", "extra"})
    try:
        cls = import_class(data["class"]) if isinstance(data["class"], str) else None
    except (RegistryError, ImportError) as exc:
        raise CheckpointError(f"writer: {exc}") from None
    if not (isinstance(cls, type) and issubclass(cls, VTUWriter)):
        raise CheckpointError(f"writer: {data['class']!r} is not a dda.io.VTUWriter")
    entries = data["entries"]
    ints = [data[k] for k in ("every", "n", "seen")]
    if not (isinstance(data["prefix"], str)
            and all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in ints)
            and isinstance(entries, list) and all(
                isinstance(e, list) and len(e) == 2 and isinstance(e[1], str)
                and isinstance(e[0], (int, float)) and "/" not in e[1] and "\\" not in e[1]
                for e in entries)
            and ints[0] >= 1 and ints[1] <= len(entries)
            and isinstance(data["extra"], dict)):
        raise CheckpointError("writer: its fields are not a VTU writer's")
    prefix = _writer_prefix(data, checkpoint, outside)
    writer = cls.__new__(cls)  # its state set as it was, without running its __init__
    writer.__dict__.update({k: v for k, v in data["extra"].items()
                            if isinstance(k, str) and not k.startswith("_")})
    writer.prefix = prefix
    writer.every = ints[0]
    writer._entries = [(float(t), name) for t, name in entries]
    writer._n, writer._seen = ints[1], ints[2]
    last = data["last_time"]
    writer.last_time = None if last is None else float(last)
    writer.prefix.parent.mkdir(parents=True, exist_ok=True)
    return writer


def _writer_prefix(data, checkpoint: Path, outside: bool) -> Path:
    """Where the resumed writer's files go: in the checkpoint's folder as they were; a
    writer that was outside it only with ``outside``."""
    inside = data["inside"]
    if inside is not None:
        rel = Path(inside) if isinstance(inside, str) else None
        if (rel is None or rel.is_absolute() or rel.drive or ".." in rel.parts
                or not rel.parts):
            raise CheckpointError(f"writer: {inside!r} is not a path inside the checkpoint's "
                                  "folder")
        folder = checkpoint.parent.resolve()
        prefix = checkpoint.parent / rel
        if folder not in prefix.parent.resolve().parents and prefix.parent.resolve() != folder:
            raise CheckpointError(f"writer: {inside!r} leads out of the checkpoint's folder")
        return prefix
    if not outside:
        raise CheckpointError(
            f"its VTU series was written to {data['prefix']!r}, outside the checkpoint's folder; "
            "resume with Simulation.resume(path, allow_outside_output=True) (dda run "
            "--allow-outside-output) to go on writing there")
    return Path(data["prefix"])


def _written(data, writer):
    if data is None:
        return (None, None)
    _expect(data, "written", {"same_writer", "time"})
    return (writer if data["same_writer"] else None, float(data["time"]))
