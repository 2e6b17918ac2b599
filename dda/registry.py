"""One registry of the friction laws and the solvers, by name.

Scene files (``friction = { law = "coulomb", ... }``, ``[simulation] solver = "newton"``),
sweeps (``grid(study, solver=[...])``) and the ``dda`` command look names up here. Each class is
registered under its own ``name`` class attribute:

- friction laws: :class:`dda.contact.CoulombSingle` (``"coulomb"``),
  :class:`dda.contact.StaticDynamicTransition` (``"transition"``),
  :class:`dda.contact.BartonBandis` (``"barton"``);
- solvers: :class:`dda.solvers.LegacyPullBack` (``"legacy"``),
  :class:`dda.solvers.NewtonRaphson` (``"newton"``).

The keyword arguments a law or solver takes are those of its constructor
(:func:`parameters`), read from its signature.

A class of your own is used in two ways:

- ``register_law(MyLaw)`` (or ``register_solver``; both work as class decorators) adds it
  under ``MyLaw.name`` for the rest of the process. Worker processes of a sweep that are
  started fresh (not forked) must register it again: do it in the module that defines it.
- An import path ``"module:Class"`` (``"my_laws:BrittleCohesion"``,
  ``"pkg.laws:Outer.Inner"``) names it without registering: the module is imported with
  :func:`importlib.import_module` and the attributes after the colon are looked up one by one
  (no expression is evaluated; importing the module runs its code, as any import does).
  :func:`law_class` and :func:`solver_class` take an optional folder searched before
  ``sys.path`` (a scene file's folder).

Examples
--------
>>> from dda import registry
>>> registry.law_names()
('coulomb', 'transition', 'barton')
>>> registry.solver_names()
('legacy', 'newton')
>>> registry.parameters(registry.law_class("transition"))
('phi_static', 'phi_dynamic', 'onset')
>>> registry.make_law("coulomb", phi=30.0)
CoulombSingle(phi=30.0, cohesion=0.0)
>>> registry.make_solver("newton", max_iter=9)
NewtonRaphson(tol=1e-09, max_iter=9)
>>> try:
...     registry.solver_class("implicit")
... except registry.RegistryError as exc:
...     print(exc)
unknown solver 'implicit'; use one of legacy, newton or an import path 'module:Class'
"""

from __future__ import annotations

import importlib
import inspect
import sys
import threading
from pathlib import Path

__all__ = ["RegistryError", "import_class", "law_class", "law_names", "make_law", "make_solver",
           "parameters", "register_law", "register_solver", "solver_class", "solver_names",
           "takes_any_keyword", "unknown_keywords", "unregister_law", "unregister_solver"]


class RegistryError(ValueError):
    """A name or import path that gives no usable law or solver (the message says why)."""


# name -> class, in the order registered; the built-in classes come first and are added on
# first use (importing them here would import dda.contact and dda.solvers with this module)
_laws: dict[str, type] = {}
_solvers: dict[str, type] = {}
_builtin: set[type] = set()
_lock = threading.RLock()
_ready = False


def _ensure():
    global _ready
    if _ready:
        return
    with _lock:
        if _ready:
            return
        from dda.contact import BartonBandis, CoulombSingle, StaticDynamicTransition
        from dda.solvers import LegacyPullBack, NewtonRaphson

        for cls in (CoulombSingle, StaticDynamicTransition, BartonBandis):
            _laws[cls.name] = cls
        for cls in (LegacyPullBack, NewtonRaphson):
            _solvers[cls.name] = cls
        _builtin.update(_laws.values(), _solvers.values())
        _ready = True


def _law_base():
    from dda.contact.friction import FrictionLaw

    return FrictionLaw, "dda.contact.FrictionLaw"


def _solver_base():
    from dda.solvers.base import NonlinearSolver

    return NonlinearSolver, "dda.solvers.NonlinearSolver"


# ---------------------------------------------------------------------- names
def law_names() -> tuple[str, ...]:
    """The registered friction laws' names, the built-in ones first."""
    _ensure()
    return tuple(_laws)


def solver_names() -> tuple[str, ...]:
    """The registered solvers' names, the built-in ones first."""
    _ensure()
    return tuple(_solvers)


def law_class(name: str, folder=None) -> type:
    """The friction law class registered as ``name``, or named by an import path
    ``"module:Class"`` (its module looked for in ``folder`` first, then on ``sys.path``).

    Raises
    ------
    RegistryError
        For an unknown name, a module or attribute not found, a module that fails to import
        and an object that is not a subclass of :class:`dda.contact.FrictionLaw`.
    """
    return _lookup(_laws, name, folder, "friction law", _law_base)


def solver_class(name: str, folder=None) -> type:
    """The solver class registered as ``name``, or named by an import path ``"module:Class"``
    (as :func:`law_class`; a subclass of :class:`dda.solvers.NonlinearSolver`)."""
    return _lookup(_solvers, name, folder, "solver", _solver_base)


def _lookup(table, name, folder, kind, base):
    _ensure()
    if isinstance(name, str) and ":" in name:
        cls = import_class(name, folder)
        required, label = base()
        if not (isinstance(cls, type) and issubclass(cls, required)):
            raise RegistryError(f"{name!r} is {_describe(cls)}, not a subclass of {label}")
        return cls
    try:
        return table[name]
    except (KeyError, TypeError):
        raise RegistryError(f"unknown {kind} {name!r}; use one of {', '.join(table)} or an "
                            "import path 'module:Class'") from None


def _describe(obj) -> str:
    if isinstance(obj, type):
        return f"the class {obj.__module__}.{obj.__qualname__}"
    return f"a {type(obj).__name__}"


# ---------------------------------------------------------------------- import paths
def import_class(spec: str, folder=None):
    """The object an import path ``"module:attr.attr"`` names (any object; the callers check
    its type). ``folder`` is put at the front of ``sys.path`` while the module is imported."""
    module, _, attrs = spec.partition(":")
    names = attrs.split(".")
    if (not all(p.isidentifier() for p in module.split("."))
            or not all(p.isidentifier() for p in names)):
        raise RegistryError(f"{spec!r} is not an import path 'module:Class' (module names "
                            "and attributes separated by dots, one colon between)")
    obj = _import(module, folder)
    for i, attr in enumerate(names):
        try:
            obj = getattr(obj, attr)
        except AttributeError:
            raise RegistryError(f"module {module!r} has no attribute "
                                f"{'.'.join(names[:i + 1])!r}") from None
    return obj


def _import(module: str, folder):
    with _lock:  # sys.path is changed while importing: one import at a time
        return _import_locked(module, folder)


def _import_locked(module: str, folder):
    entry = None if folder is None else str(Path(folder).resolve())
    if entry is not None:
        sys.path.insert(0, entry)
    try:
        importlib.invalidate_caches()  # a file written since the last import is seen
        mod = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name and (module == exc.name or module.startswith(exc.name + ".")):
            where = f"in {entry} or on sys.path" if entry else "on sys.path"
            raise RegistryError(f"no module {module!r} {where}") from None
        raise RegistryError(f"importing module {module!r} failed: {exc}") from exc
    except Exception as exc:
        raise RegistryError(f"importing module {module!r} raised {type(exc).__name__}: "
                            f"{exc}") from exc
    finally:
        if entry is not None:
            _remove(sys.path, entry)
    if entry is not None:
        _check_origin(module, Path(entry))
    return mod


def _remove(path_list, entry):
    """Take out the entry put first (the same string object), else the first equal one."""
    for i, p in enumerate(path_list):
        if p is entry:
            del path_list[i]
            return
    if entry in path_list:
        path_list.remove(entry)


def _check_origin(module, folder: Path):
    """A module of the same name imported earlier from elsewhere would hide the folder's."""
    top = module.split(".")[0]
    own = [f for f in (folder / f"{top}.py", folder / top / "__init__.py") if f.is_file()]
    loaded = getattr(sys.modules.get(top), "__file__", None)
    if own and loaded and Path(loaded).resolve() != own[0].resolve():
        raise RegistryError(f"module {top!r} is already imported from {loaded}, not from "
                            f"{folder}; give one of them another name")


# ---------------------------------------------------------------------- construction
def parameters(cls) -> tuple[str, ...]:
    """The keyword arguments ``cls(...)`` takes, in order, from its signature.

    A constructor with ``**kwargs`` takes any keyword besides these (see :func:`make_law`).
    """
    return tuple(p.name for p in _signature(cls).parameters.values()
                 if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))


def takes_any_keyword(cls) -> bool:
    """True when the constructor of ``cls`` has ``**kwargs``."""
    return any(p.kind is p.VAR_KEYWORD for p in _signature(cls).parameters.values())


def _signature(cls):
    try:
        return inspect.signature(cls)
    except (TypeError, ValueError):  # no signature to read: take any keyword
        return inspect.Signature([inspect.Parameter("kwargs", inspect.Parameter.VAR_KEYWORD)])


def unknown_keywords(cls, keywords) -> list[str]:
    """The keywords of ``keywords`` that ``cls(...)`` does not take."""
    if takes_any_keyword(cls):
        return []
    known = set(parameters(cls))
    return [k for k in keywords if k not in known]


def _make(cls, name, kind, kw):
    bad = unknown_keywords(cls, kw)
    if bad:
        raise TypeError(f"unknown keyword {bad[0]!r} for {kind} {name!r} (it takes: "
                        f"{', '.join(parameters(cls)) or 'none'})")
    return cls(**kw)


def make_law(name: str, **kw):
    """The friction law ``name`` (registered, or ``"module:Class"``) built with ``kw``.

    >>> make_law("transition", phi_static=35.0, phi_dynamic=25.0).name
    'transition'
    >>> make_law("coulomb", mu=0.5)
    Traceback (most recent call last):
    ...
    TypeError: unknown keyword 'mu' for friction law 'coulomb' (it takes: phi, cohesion)
    """
    return _make(law_class(name), name, "friction law", kw)


def make_solver(name: str, **kw):
    """The solver ``name`` (registered, or ``"module:Class"``) built with ``kw``."""
    return _make(solver_class(name), name, "solver", kw)


# ---------------------------------------------------------------------- registration
def register_law(cls):
    """Add a :class:`dda.contact.FrictionLaw` subclass under its own ``name`` attribute.

    Returns the class, so this works as a decorator. Registering a class again (or a class of
    the same module and qualified name, as when a notebook cell runs twice) replaces it; a
    name taken by another class is an error.

    >>> from dda.contact import CoulombSingle
    >>> @register_law
    ... class Sticky(CoulombSingle):
    ...     name = "sticky"
    >>> make_law("sticky", phi=40.0).mu > 0.8
    True
    >>> unregister_law("sticky")
    """
    return _register(_laws, cls, "friction law", _law_base)


def register_solver(cls):
    """Add a :class:`dda.solvers.NonlinearSolver` subclass under its own ``name`` attribute
    (as :func:`register_law`)."""
    return _register(_solvers, cls, "solver", _solver_base)


def _register(table, cls, kind, base):
    _ensure()
    required, label = base()
    if not (isinstance(cls, type) and issubclass(cls, required)):
        raise TypeError(f"register: a {kind} must be a subclass of {label}, got "
                        f"{_describe(cls)}")
    name = cls.__dict__.get("name")
    if not isinstance(name, str) or not name.strip() or ":" in name:
        raise ValueError(f"register: {cls.__qualname__} needs its own class attribute name = "
                         "'...' (a word without ':'), the key it is registered under")
    with _lock:
        held = table.get(name)
        if held is not None and held is not cls and (
                held in _builtin or (held.__module__, held.__qualname__)
                != (cls.__module__, cls.__qualname__)):
            raise ValueError(f"register: the {kind} name {name!r} is taken by "
                             f"{held.__module__}.{held.__qualname__}")
        table[name] = cls
    return cls


def unregister_law(name: str) -> None:
    """Remove a friction law added with :func:`register_law` (the built-in ones stay)."""
    _unregister(_laws, name, "friction law")


def unregister_solver(name: str) -> None:
    """Remove a solver added with :func:`register_solver` (the built-in ones stay)."""
    _unregister(_solvers, name, "solver")


def _unregister(table, name, kind):
    _ensure()
    with _lock:
        if name not in table:
            raise RegistryError(f"no {kind} {name!r} is registered")
        if table[name] in _builtin:
            raise ValueError(f"the built-in {kind} {name!r} cannot be removed")
        del table[name]
