"""A scene as plain data and back: what a checkpoint keeps instead of pickled objects.

:func:`scene_to_data` turns a :class:`dda.Scene` into a JSON-able dict (numbers, strings,
lists) whose arrays go into an :class:`ArrayStore` (saved as ``.npz`` arrays, never as
pickles); :func:`scene_from_data` replays the scene's calls (``add_block``, ``set_joint``,
``shake``, ...) from it, so every input is checked again as it is read.

What a scene holds that is not data is named, never pickled:

- friction laws by their registry name (``"coulomb"``) or import path (``"my_laws:Brittle"``)
  and the constructor parameters they keep as attributes (a law is rebuilt by its class,
  which must be a :class:`dda.contact.FrictionLaw`: :mod:`dda.registry`);
- time histories (shaking, prescribed motion, loads) as their samples when they have them (a
  recorded accelerogram, :class:`dda.effects.TimeTable`, the scene file's sine and constant
  velocity), and a function by its import path ``"package.module:function"``: a plain Python
  function defined at a module's top level, looked up attribute by attribute when read (the
  module is imported, as any import runs its code; nothing else in the file is run).

A lambda, a function defined inside another or in ``__main__`` (a script run as a program), or
a callable object of another class has no such name: :func:`scene_to_data` raises
:class:`SceneDataError` saying which input it is and what to give instead.
"""

from __future__ import annotations

import importlib
import types

import numpy as np

from dda.contact.friction import FrictionLaw
from dda.contact.joint import JointMaterial
from dda.effects import TimeTable
from dda.materials import LinearElastic

__all__ = ["ArrayStore", "SceneDataError", "function_path", "resolve_function",
           "scene_from_data", "scene_to_data"]


class SceneDataError(ValueError):
    """A scene that cannot be kept as data, or data that is not a scene (says which part)."""


class ArrayStore:
    """Named arrays beside the JSON data (what an ``.npz`` file holds)."""

    def __init__(self, arrays=None):
        self.arrays: dict[str, np.ndarray] = dict(arrays or {})

    def put(self, name: str, value) -> dict:
        """Keep ``value`` as the array ``name``; the reference the data holds instead."""
        a = np.asarray(value)
        if a.dtype == object:
            raise SceneDataError(f"{name}: not an array of numbers")
        self.arrays[name] = a
        return {"array": name}

    def get(self, ref, where: str, dtype=float, shape=None) -> np.ndarray:
        """The array a reference names, of ``dtype`` and (a tuple with None for any size)
        ``shape``."""
        if not (isinstance(ref, dict) and set(ref) == {"array"}
                and isinstance(ref["array"], str)):
            raise SceneDataError(f"{where}: expected an array reference, got {ref!r}")
        a = self.arrays.get(ref["array"])
        if a is None:
            raise SceneDataError(f"{where}: the array {ref['array']!r} is missing")
        if a.dtype == object or a.dtype.kind not in "biuf":
            raise SceneDataError(f"{where}: the array {ref['array']!r} is not numeric")
        a = np.asarray(a, dtype=dtype)
        if shape is not None and (a.ndim != len(shape) or any(
                s is not None and s != n for s, n in zip(shape, a.shape, strict=True))):
            raise SceneDataError(f"{where}: the array {ref['array']!r} has shape {a.shape}")
        return a


# ---------------------------------------------------------------------- named functions
def function_path(f, where: str) -> str:
    """``"module:qualname"`` of a plain module-level function, which :func:`resolve_function`
    gives back; :class:`SceneDataError` for anything else."""
    hint = ("A checkpoint names functions by their import path; define it at the "
            "top level of a module you can import (not in the script run as a program, not "
            "as a lambda or inside another function), or give the history as samples "
            "(dda.effects.TimeTable, or times and values for shaking)")
    if not isinstance(f, types.FunctionType):
        raise SceneDataError(f"{where}: {f!r} is not a plain function. " + hint)
    module, name = getattr(f, "__module__", None), f.__qualname__
    if not module or module == "__main__" or "<" in name:
        raise SceneDataError(f"{where}: {module}.{name} has no import path. " + hint)
    try:
        back = resolve_function(f"{module}:{name}", where)
    except SceneDataError:
        back = None
    if back is not f:
        raise SceneDataError(f"{where}: {module}:{name} does not name this function. " + hint)
    return f"{module}:{name}"


def resolve_function(path: str, where: str):
    """The plain function an import path ``"module:qualname"`` names (the module is imported,
    the names after the colon looked up one by one; nothing is evaluated)."""
    if not isinstance(path, str) or path.count(":") != 1:
        raise SceneDataError(f"{where}: expected an import path 'module:function', got {path!r}")
    module_name, _, qualname = path.partition(":")
    parts = qualname.split(".")
    if not module_name or not all(p.isidentifier() for p in parts) or not all(
            p.isidentifier() for p in module_name.split(".")):
        raise SceneDataError(f"{where}: {path!r} is not an import path 'module:function'")
    try:
        obj = importlib.import_module(module_name)
    except ImportError as exc:
        raise SceneDataError(f"{where}: cannot import {module_name!r} for {path!r} ({exc}); "
                             "run from the folder the run was started in, or put the "
                             "module's folder on PYTHONPATH") from None
    for p in parts:
        obj = getattr(obj, p, None)
    if not isinstance(obj, types.FunctionType) or obj.__module__ != module_name:
        raise SceneDataError(f"{where}: {path!r} names no function defined in {module_name}")
    return obj


# ---------------------------------------------------------------------- plain values
def _plain(value, where: str):
    """A parameter as JSON data (numbers, strings, booleans, None and lists of them)."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v, where) for v in (value.tolist() if isinstance(value, np.ndarray)
                                           else value)]
    raise SceneDataError(f"{where}: {value!r} is not a number, string or list of them")


def _number(data, key, where, allow_none=False, allow_auto=False):
    value = data.get(key) if isinstance(data, dict) else None
    if value is None and allow_none:
        return None
    if allow_auto and value == "auto":
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneDataError(f"{where}: {key} must be a number, got {value!r}")
    return float(value)


def _table(data, where: str, keys: set, required: set = frozenset()) -> dict:
    if not isinstance(data, dict):
        raise SceneDataError(f"{where}: expected a table, got {type(data).__name__}")
    unknown = set(data) - keys
    if unknown:
        raise SceneDataError(f"{where}: unknown keys {sorted(unknown)}")
    missing = set(required) - set(data)
    if missing:
        raise SceneDataError(f"{where}: missing keys {sorted(missing)}")
    return data


def _list(data, where: str) -> list:
    if not isinstance(data, list):
        raise SceneDataError(f"{where}: expected a list, got {type(data).__name__}")
    return data


# ---------------------------------------------------------------------- histories
def _history_to_data(f, store, name, where):
    """A callable history as data (its samples, or its function's import path)."""
    from dda.io.scene_file import ConstantVelocity, SineAcceleration

    if isinstance(f, TimeTable):
        return {"time_table": {
            "times": store.put(f"{name}/times", f.times),
            "x": None if f.x is None else store.put(f"{name}/x", f.x),
            "y": None if f.y is None else store.put(f"{name}/y", f.y),
            "name": str(f.name)}}
    if type(f) is SineAcceleration:
        return {"sine": {"amplitude": float(f.amplitude), "frequency": float(f.frequency),
                         "start": float(f.start),
                         "direction": [float(v) for v in f.direction], "form": str(f.form)}}
    if type(f) is ConstantVelocity:
        return {"constant_velocity": {"vx": None if f.vx is None else float(f.vx),
                                      "vy": None if f.vy is None else float(f.vy)}}
    return {"function": function_path(f, where)}


def _history_from_data(data, store, where):
    from dda.io.scene_file import SINE_FORMS, ConstantVelocity, SineAcceleration

    _table(data, where, {"time_table", "sine", "constant_velocity", "function"})
    if len(data) != 1:
        raise SceneDataError(f"{where}: expected one kind of history, got {sorted(data)}")
    kind, spec = next(iter(data.items()))
    w = f"{where}.{kind}"
    if kind == "function":
        return resolve_function(spec, w)
    if kind == "time_table":
        _table(spec, w, {"times", "x", "y", "name"}, {"times"})
        t = store.get(spec["times"], w + ".times", shape=(None,))
        cols = [None if spec.get(k) is None else store.get(spec[k], f"{w}.{k}", shape=(None,))
                for k in ("x", "y")]
        return TimeTable(t, *cols, name=str(spec.get("name", "time table")))
    if kind == "sine":
        _table(spec, w, {"amplitude", "frequency", "start", "direction", "form"},
               {"amplitude", "frequency", "start", "direction"})
        direction = _list(spec["direction"], w + ".direction")
        if len(direction) != 2:
            raise SceneDataError(f"{w}.direction: expected two numbers")
        form = spec.get("form", "sine")  # data written before the forms: a plain sine
        if form not in SINE_FORMS:
            raise SceneDataError(f"{w}.form: expected one of {list(SINE_FORMS)}, got {form!r}")
        return SineAcceleration(_number(spec, "amplitude", w), _number(spec, "frequency", w),
                                _number(spec, "start", w),
                                tuple(_number({"v": v}, "v", w) for v in direction), form)
    _table(spec, w, {"vx", "vy"}, {"vx", "vy"})
    return ConstantVelocity(_number(spec, "vx", w, allow_none=True),
                            _number(spec, "vy", w, allow_none=True))


# ---------------------------------------------------------------------- laws and joints
def law_to_data(law: FrictionLaw, where: str) -> dict:
    """A friction law as its class's registry name or import path and its parameters."""
    from dda import registry

    cls = type(law)
    name = getattr(cls, "name", None)
    try:
        registered = name is not None and registry.law_class(name) is cls
    except registry.RegistryError:
        registered = False
    if registered:
        law_name = name
    else:
        module, qualname = cls.__module__, cls.__qualname__
        if module == "__main__" or "<" in qualname:
            raise SceneDataError(
                f"{where}: the friction law {cls.__name__} is defined in the script run as a "
                "program (or inside a function); a checkpoint names a law's class by its "
                "import path: define it in a module you import")
        law_name = f"{module}:{qualname}"
    params = {}
    for p in registry.parameters(cls):
        if not hasattr(law, p):
            raise SceneDataError(
                f"{where}: the friction law {cls.__name__} does not keep its parameter {p!r} "
                "as an attribute of the same name; a checkpoint rebuilds a law from them")
        params[p] = _plain(getattr(law, p), f"{where}: {cls.__name__}.{p}")
    return {"law": law_name, "parameters": params}


def law_from_data(data, where: str) -> FrictionLaw:
    from dda import registry

    _table(data, where, {"law", "parameters"}, {"law", "parameters"})
    if not isinstance(data["law"], str):
        raise SceneDataError(f"{where}: law must be a name or import path")
    params = _table(data["parameters"], where + ".parameters", set(data["parameters"]))
    try:  # the registry checks the class is a FrictionLaw before making one
        return registry.make_law(data["law"], **params)
    except (registry.RegistryError, TypeError, ValueError) as exc:
        raise SceneDataError(f"{where}: {exc}") from None


def joint_to_data(joint: JointMaterial, where: str) -> dict:
    return {"normal_penalty": _plain(joint.normal_penalty, where),
            "shear_penalty": _plain(joint.shear_penalty, where),
            "restitution": float(joint.restitution), "shear_dashpot": bool(joint.shear_dashpot),
            "friction": law_to_data(joint.friction, where)}


def joint_from_data(data, where: str) -> JointMaterial:
    _table(data, where, {"normal_penalty", "shear_penalty", "restitution", "shear_dashpot",
                         "friction"},
           {"normal_penalty", "shear_penalty", "restitution", "shear_dashpot", "friction"})
    if not isinstance(data["shear_dashpot"], bool):
        raise SceneDataError(f"{where}: shear_dashpot must be true or false")
    try:
        return JointMaterial(_number(data, "normal_penalty", where, allow_auto=True),
                             _number(data, "shear_penalty", where, allow_auto=True),
                             law_from_data(data["friction"], where + ".friction"),
                             restitution=_number(data, "restitution", where),
                             shear_dashpot=data["shear_dashpot"])
    except (TypeError, ValueError) as exc:
        if isinstance(exc, SceneDataError):
            raise
        raise SceneDataError(f"{where}: {exc}") from None


# ---------------------------------------------------------------------- the scene
_SCENE_KEYS = {"gravity", "max_blocks", "max_vertices", "materials", "blocks", "joints",
               "shakes", "motions", "loads", "damping"}
# keys a scene's data has only when the scene has what they hold
_OPTIONAL_KEYS = {"bolts", "water"}
_BOLT_KEYS = {"block_a", "point_a", "block_b", "point_b", "stiffness", "pretension",
              "strength"}


def scene_to_data(scene, store: ArrayStore) -> dict:
    """The scene as JSON-able data, its arrays put in ``store`` (module docstring)."""
    blocks = scene.block_inputs
    names = [h.name for h in scene.blocks]
    materials: list[LinearElastic] = []
    material_of = []
    for b in blocks:
        if b.material not in materials:
            materials.append(b.material)
        material_of.append(materials.index(b.material))
    verts, offsets = scene.vertex_arrays()
    data = {
        "gravity": float(scene.gravity), "max_blocks": int(scene.max_blocks),
        "max_vertices": int(scene.max_vertices),
        "materials": [{"young": float(m.young), "poisson": float(m.poisson),
                       "density": float(m.density), "plane": str(m.plane)}
                      for m in materials],
        "blocks": {
            "names": names, "material": material_of,
            "fixed": [bool(b.fixed) for b in blocks], "rigid": [bool(b.rigid) for b in blocks],
            "vertices": store.put("scene/vertices", verts),
            "offsets": store.put("scene/offsets", offsets),
            "velocity": store.put("scene/velocity",
                                  np.array([b.velocity for b in blocks]).reshape(-1, 2)),
            "angular_velocity": store.put(
                "scene/angular_velocity", np.array([b.angular_velocity for b in blocks])),
        },
        "joints": {
            "default": (None if scene.default_joint is None
                        else joint_to_data(scene.default_joint, "the default joint")),
            "pairs": [[int(a), int(b), joint_to_data(j, f"the joint of {names[a]!r} and "
                                                        f"{names[b]!r}")]
                      for (a, b), j in scene.pair_joints.items()],
        },
        "shakes": [],
        "motions": [],
        "loads": [],
        "damping": [{"blocks": None if d.blocks is None else [int(i) for i in d.blocks],
                     "mass": float(d.mass), "stiffness": float(d.stiffness)}
                    for d in scene.damping_settings],
    }
    if scene.water is not None:
        data["water"] = scene.water.as_data()
    if scene.bolts:
        data["bolts"] = [{"block_a": int(b.block_a), "point_a": [float(v) for v in b.point_a],
                          "block_b": int(b.block_b), "point_b": [float(v) for v in b.point_b],
                          "stiffness": float(b.stiffness), "pretension": float(b.pretension),
                          "strength": None if b.strength is None else float(b.strength)}
                         for b in scene.bolts]
    for k, s in enumerate(scene.shakes):
        where = f"the shaking of block {names[s.block]!r}"
        record = s.history.record
        if record is None:
            acc = _history_to_data(s.history.function, store, f"scene/shake{k}", where)
        else:
            acc = {"record": {"times": store.put(f"scene/shake{k}/times", record[0]),
                              "values": store.put(f"scene/shake{k}/values", record[1])}}
        data["shakes"].append({"block": int(s.block), "acceleration": acc})
    for k, m in enumerate(scene.motions):
        where = f"the prescribed motion of block {names[m.block]!r}"
        data["motions"].append({
            "block": int(m.block),
            "displacement": _history_to_data(m.displacement.function, store,
                                             f"scene/motion{k}", where),
            "penalty": None if m.penalty is None else float(m.penalty),
            "points": None if m.points is None else store.put(f"scene/motion{k}/points",
                                                              m.points)})
    for k, ld in enumerate(scene.point_loads):
        where = f"the point load {k} on block {names[ld.block]!r}"
        force = ld.force
        data["loads"].append({
            "block": int(ld.block), "point": [float(v) for v in ld.point],
            "force": ([float(v) for v in force.value] if force.constant
                      else _history_to_data(force.function, store, f"scene/load{k}", where))})
    stress = np.array([b.stress for b in blocks], dtype=float).reshape(-1, 3)
    if np.any(stress != 0.0):  # (only then: a scene without one reads as before)
        data["blocks"]["stress"] = store.put("scene/stress", stress)
    return data


def scene_from_data(data, store: ArrayStore):
    """The :class:`dda.Scene` of :func:`scene_to_data`'s data (every input checked again)."""
    from dda.scene import Scene

    _table(data, "scene", _SCENE_KEYS | _OPTIONAL_KEYS, _SCENE_KEYS)
    try:
        limits = {k: data[k] for k in ("max_blocks", "max_vertices")}
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in limits.values()):
            raise SceneDataError("scene: max_blocks and max_vertices must be whole numbers")
        scene = Scene(gravity=_number(data, "gravity", "scene"), **limits)
        materials = [LinearElastic(**_table(m, f"scene.materials[{i}]",
                                            {"young", "poisson", "density", "plane"},
                                            {"young", "poisson", "density", "plane"}))
                     for i, m in enumerate(_list(data["materials"], "scene.materials"))]
        b = _table(data["blocks"], "scene.blocks",
                   {"names", "material", "fixed", "rigid", "vertices", "offsets", "velocity",
                    "angular_velocity", "stress"},
                   {"names", "material", "fixed", "rigid", "vertices", "offsets", "velocity",
                    "angular_velocity"})
        names = _list(b["names"], "scene.blocks.names")
        n = len(names)
        verts = store.get(b["vertices"], "scene.blocks.vertices", shape=(None, 2))
        offsets = store.get(b["offsets"], "scene.blocks.offsets", dtype=np.int64,
                            shape=(n + 1,))
        if offsets[0] != 0 or offsets[-1] != len(verts) or np.any(np.diff(offsets) < 3):
            raise SceneDataError("scene.blocks.offsets: not the offsets of the vertices")
        velocity = store.get(b["velocity"], "scene.blocks.velocity", shape=(n, 2))
        omega = store.get(b["angular_velocity"], "scene.blocks.angular_velocity", shape=(n,))
        stress = (store.get(b["stress"], "scene.blocks.stress", shape=(n, 3)) if "stress" in b
                  else np.zeros((n, 3)))
        columns = [_list(b[k], f"scene.blocks.{k}") for k in ("material", "fixed", "rigid")]
        if any(len(c) != n for c in columns):
            raise SceneDataError("scene.blocks: its lists differ in length")
        for i in range(n):
            m = columns[0][i]
            if not isinstance(m, int) or isinstance(m, bool) or not 0 <= m < len(materials):
                raise SceneDataError(f"scene.blocks.material[{i}]: no material {m!r}")
            if not (isinstance(columns[1][i], bool) and isinstance(columns[2][i], bool)):
                raise SceneDataError(f"scene.blocks[{i}]: fixed and rigid must be true or false")
            if not isinstance(names[i], str):
                raise SceneDataError(f"scene.blocks.names[{i}]: not a name")
            scene.add_block(verts[offsets[i]:offsets[i + 1]], materials[m],
                            fixed=columns[1][i], name=names[i], velocity=velocity[i],
                            angular_velocity=float(omega[i]), rigid=columns[2][i],
                            stress=stress[i] if np.any(stress[i] != 0.0) else None)
        joints = _table(data["joints"], "scene.joints", {"default", "pairs"},
                        {"default", "pairs"})
        if joints["default"] is not None:
            scene.set_joint(joint_from_data(joints["default"], "scene.joints.default"))
        for i, pair in enumerate(_list(joints["pairs"], "scene.joints.pairs")):
            if not isinstance(pair, list) or len(pair) != 3:
                raise SceneDataError(f"scene.joints.pairs[{i}]: expected [a, b, joint]")
            scene.set_joint(joint_from_data(pair[2], f"scene.joints.pairs[{i}]"),
                            between=(pair[0], pair[1]))
        for i, s in enumerate(_list(data["shakes"], "scene.shakes")):
            w = f"scene.shakes[{i}]"
            _table(s, w, {"block", "acceleration"}, {"block", "acceleration"})
            acc = s["acceleration"]
            if isinstance(acc, dict) and "record" in acc:
                rec = _table(acc["record"], w + ".record", {"times", "values"},
                             {"times", "values"})
                scene.shake(s["block"], acceleration=store.get(rec["values"], w + ".values",
                                                               shape=(None, 2)),
                            times=store.get(rec["times"], w + ".times", shape=(None,)))
            else:
                scene.shake(s["block"], acceleration=_history_from_data(acc, store, w))
        for i, m in enumerate(_list(data["motions"], "scene.motions")):
            w = f"scene.motions[{i}]"
            _table(m, w, {"block", "displacement", "penalty", "points"},
                   {"block", "displacement", "penalty", "points"})
            points = (None if m["points"] is None
                      else store.get(m["points"], w + ".points", shape=(None, 2)))
            scene.prescribe_motion(m["block"], _history_from_data(m["displacement"], store, w),
                                   penalty=_number(m, "penalty", w, allow_none=True),
                                   points=points)
        for i, ld in enumerate(_list(data["loads"], "scene.loads")):
            w = f"scene.loads[{i}]"
            _table(ld, w, {"block", "point", "force"}, {"block", "point", "force"})
            force = ld["force"]
            if isinstance(force, dict):
                force = _history_from_data(force, store, w)
            scene.add_point_load(ld["block"], ld["point"], force)
        for i, d in enumerate(_list(data["damping"], "scene.damping")):
            w = f"scene.damping[{i}]"
            _table(d, w, {"blocks", "mass", "stiffness"}, {"blocks", "mass", "stiffness"})
            scene.set_damping(mass=_number(d, "mass", w), stiffness=_number(d, "stiffness", w),
                              blocks=d["blocks"])
        if "water" in data:
            w = _table(data["water"], "scene.water", {"table", "unit_weight"},
                       {"table", "unit_weight"})
            scene.set_water_table(w["table"], unit_weight=_number(w, "unit_weight",
                                                                  "scene.water"))
        for i, b in enumerate(_list(data.get("bolts", []), "scene.bolts")):
            w = f"scene.bolts[{i}]"
            _table(b, w, _BOLT_KEYS, _BOLT_KEYS)
            scene.add_bolt(b["block_a"], _list(b["point_a"], w + ".point_a"), b["block_b"],
                           _list(b["point_b"], w + ".point_b"), _number(b, "stiffness", w),
                           pretension=_number(b, "pretension", w),
                           strength=_number(b, "strength", w, allow_none=True))
    except SceneDataError:
        raise
    except (TypeError, ValueError, KeyError, IndexError) as exc:
        raise SceneDataError(f"scene: {exc}") from None
    return scene
