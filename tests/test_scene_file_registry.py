"""Scene files and the registry: laws named by import path, registered laws and solvers."""

import sys
import textwrap

import numpy as np
import pytest

from dda import registry
from dda.contact import CoulombSingle
from dda.io.scene_file import SceneFileError, load_scene
from dda.solvers import LegacyPullBack

SCENE = """
[materials.rock]
young = 1e9
poisson = 0.25
density = 2500.0

[joints.default]
normal_penalty = 1e9
shear_penalty = 1e9
friction = { law = "coulomb", phi = 30.0 }

[[joints.pair]]
between = ["base", "top"]
normal_penalty = 1e9
shear_penalty = 1e9
friction = { law = "user_laws:BrittleCohesion", phi = 30.0, cohesion = 5e4 }

[[blocks]]
name = "base"
material = "rock"
vertices = [[0, 0], [4, 0], [4, 1], [0, 1]]
fixed = true

[[blocks]]
name = "top"
material = "rock"
vertices = [[1, 1], [2, 1], [2, 2], [1, 2]]
velocity = [0.5, 0.0]

[scene]
gravity = 9.81

[simulation]
dt = 1e-3
duration = 0.01
solver = "legacy"
"""

LAWS = '''
import numpy as np

from dda.contact import CoulombSingle, FrictionLaw, FrictionTrial


class BrittleCohesion(CoulombSingle):
    """Coulomb with a cohesion (the same return map: only the name and a setting differ)."""

    name = "brittle"

    def __init__(self, phi, cohesion=0.0, residual=0.0):
        super().__init__(phi, cohesion)
        if residual > cohesion:
            raise ValueError(f"residual ({residual}) above the cohesion ({cohesion})")
        self.residual = residual


class Frictionless(FrictionLaw):
    """No shear force at all: the smallest law there is."""

    name = "frictionless"

    def return_map(self, committed, delta_g_s, t_n, shear_penalty, length):
        n = len(delta_g_s)
        state = {"g_se": np.zeros(n), "slip": committed["slip"] + np.abs(delta_g_s)}
        return FrictionTrial(np.zeros(n), np.ones(n, bool), np.zeros(n), state)

    def tangent(self, trial, normal_penalty, shear_penalty):
        return np.zeros_like(trial.t_s), np.zeros_like(trial.t_s)


class Fragile(CoulombSingle):
    name = "fragile"

    def __init__(self, phi):
        raise RuntimeError("no law today")


def not_a_law(phi):
    return phi
'''


@pytest.fixture(autouse=True)
def forget_user_modules():
    """Every test writes its own module: let none outlive it in sys.modules."""
    yield
    for name in [m for m in sys.modules if m.startswith("user_")]:
        del sys.modules[name]


def write(folder, text=SCENE, name="scene.toml", laws=LAWS):
    folder.mkdir(exist_ok=True)
    (folder / "user_laws.py").write_text(textwrap.dedent(laws))
    f = folder / name
    f.write_text(text)
    return f


def test_a_law_named_by_import_path_is_found_next_to_the_scene_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # not the scene's folder: the module is found all the same
    f = write(tmp_path / "case")
    path = list(sys.path)
    loaded = load_scene(f)
    assert sys.path == path
    law = loaded.scene.joint_for(0, 1).friction
    assert type(law).__name__ == "BrittleCohesion" and isinstance(law, CoulombSingle)
    assert (law.phi, law.cohesion, law.residual, law.name) == (30.0, 5e4, 0.0, "brittle")
    assert type(loaded.scene._joints.default.friction) is CoulombSingle
    assert "brittle" not in registry.law_names()  # named by path, not registered
    # the same return map as CoulombSingle: the same numbers as the registered name
    plain = write(tmp_path / "plain", SCENE.replace('"user_laws:BrittleCohesion"', '"coulomb"'))
    a, b = loaded.run(), load_scene(plain).run()
    assert np.abs(a.displacement("top")).max() > 0.0
    np.testing.assert_array_equal(a.displacement("top"), b.displacement("top"))


def test_a_minimal_friction_law_of_ones_own_runs(tmp_path):
    text = SCENE.replace('"user_laws:BrittleCohesion", phi = 30.0, cohesion = 5e4',
                         '"user_laws:Frictionless"')
    loaded = load_scene(write(tmp_path, text))
    assert type(loaded.scene.joint_for(0, 1).friction).__name__ == "Frictionless"
    result = loaded.run()
    assert np.isfinite(result.displacement("top")).all()


def test_a_module_on_the_normal_path_is_found_too(tmp_path, monkeypatch):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "user_path_laws.py").write_text(LAWS)
    monkeypatch.syspath_prepend(str(lib))
    text = SCENE.replace("user_laws:", "user_path_laws:")
    law = load_scene(write(tmp_path / "case", text)).scene.joint_for(0, 1).friction
    assert law.cohesion == 5e4


@pytest.mark.parametrize("law, words", [
    ('"user_nowhere:BrittleCohesion", phi = 30.0', "no module 'user_nowhere' in "),
    ('"user_laws:Brittle", phi = 30.0', "module 'user_laws' has no attribute 'Brittle'"),
    ('"user_laws:not_a_law", phi = 30.0',
     "'user_laws:not_a_law' is a function, not a subclass of dda.contact.FrictionLaw"),
    ('"user_laws:np", phi = 30.0', "is a module, not a subclass of dda.contact.FrictionLaw"),
    ('"user_laws:BrittleCohesion", phi = 30.0, mu = 0.5',
     "unknown key 'mu' for law 'user_laws:BrittleCohesion' (known: cohesion, phi, residual)"),
    ('"user_laws:BrittleCohesion", phi = 30.0, residual = 1e5',
     "law 'user_laws:BrittleCohesion' raised ValueError: residual (100000.0) above the "
     "cohesion (0.0)"),
    ('"user_laws:Fragile", phi = 30.0',
     "law 'user_laws:Fragile' raised RuntimeError: no law today"),
    ('"user_laws:BrittleCohesion"', "law 'user_laws:BrittleCohesion' raised TypeError: "),
    ('"user_laws:FrictionLaw"', "raised TypeError: Can't instantiate abstract class"),
    ('"user_laws:"', "is not an import path 'module:Class'"),
    ('"mohr", phi = 30.0', "law = 'mohr' is none of them: must be a table with law = "
                           "'coulomb' or 'transition' or 'barton', or an import path"),
    ('"colomb", phi = 30.0', "'module:Class' (did you mean 'coulomb'?)"),
])
def test_import_path_errors_name_the_line_and_the_key(tmp_path, law, words):
    text = SCENE.replace('"user_laws:BrittleCohesion", phi = 30.0, cohesion = 5e4', law)
    path = list(sys.path)
    with pytest.raises(SceneFileError) as info:
        load_scene(write(tmp_path, text))
    assert sys.path == path
    msg = str(info.value)
    assert msg.startswith("scene.toml, line 16, joints.pair[0].friction: "), msg
    assert text.splitlines()[15].startswith("friction = ")
    assert words in msg, msg


def test_a_registered_law_is_named_like_the_built_in_ones(tmp_path):
    class Sticky(CoulombSingle):
        name = "user_sticky"

    text = SCENE.replace('"user_laws:BrittleCohesion", phi = 30.0, cohesion = 5e4',
                         '"user_sticky", phi = 40.0')
    with pytest.raises(SceneFileError, match="'barton', or an import path"):
        load_scene(write(tmp_path, text))
    registry.register_law(Sticky)
    try:
        law = load_scene(write(tmp_path, text)).scene.joint_for(0, 1).friction
        assert type(law) is Sticky and law.phi == 40.0
        bad = text.replace("phi = 40.0", "phi = 40.0, mu = 1")
        with pytest.raises(SceneFileError, match=r"unknown key 'mu' for law 'user_sticky' "
                                                 r"\(known: cohesion, phi\)"):
            load_scene(write(tmp_path, bad))
        text = text.replace('law = "coulomb"', 'law = "mohr"')
        with pytest.raises(SceneFileError, match="'coulomb' or 'transition' or 'barton' or "
                                                 "'user_sticky', or an import path"):
            load_scene(write(tmp_path, text))
    finally:
        registry.unregister_law("user_sticky")


class Patient(LegacyPullBack):
    name = "user_patient"

    def __init__(self, patience=1):
        self.patience = patience


def test_solvers_come_from_the_registry(tmp_path):
    text = SCENE.replace('solver = "legacy"', 'solver = "user_patient"\npatience = 3')
    with pytest.raises(SceneFileError) as info:
        load_scene(write(tmp_path, text))
    assert "unknown key (known here:" in str(info.value)
    no_key = text.replace("patience = 3\n", "")
    with pytest.raises(SceneFileError, match=r"simulation.solver: must be 'newton' or "
                                             r"'legacy', got 'user_patient'"):
        load_scene(write(tmp_path, no_key))
    registry.register_solver(Patient)
    try:
        solver = load_scene(write(tmp_path, text)).solver
        assert type(solver) is Patient and solver.patience == 3
        with pytest.raises(SceneFileError, match=r"simulation: patience is not a setting of "
                                                 r"solver = 'newton' \(it takes: tol, max_iter"):
            load_scene(write(tmp_path, text.replace('"user_patient"', '"newton"')))
        with pytest.raises(SceneFileError, match="must be 'newton' or 'legacy' or "
                                                 "'user_patient', got 'implicit'"):
            load_scene(write(tmp_path, text.replace('"user_patient"', '"implicit"')))
    finally:
        registry.unregister_solver("user_patient")


def test_newton_settings_under_the_legacy_solver_are_named(tmp_path):
    text = SCENE.replace('solver = "legacy"', 'solver = "legacy"\ntol = 1e-8\nmax_iter = 9')
    with pytest.raises(SceneFileError, match=r"line 33, simulation: tol and max_iter are not "
                                             r"settings of solver = 'legacy' \(it takes: "
                                             r"cycle_local, cycle_memory\)"):
        load_scene(write(tmp_path, text))


def test_legacy_dda_takes_its_cycle_limit_from_a_scene_file(tmp_path):
    text = SCENE.replace('solver = "legacy"', 'solver = "legacy"\ncycle_local = true')
    solver = load_scene(write(tmp_path, text)).solver
    assert type(solver) is LegacyPullBack and solver.cycle_local is True
    assert load_scene(write(tmp_path, SCENE)).solver.cycle_local is None
    with pytest.raises(SceneFileError, match="cycle_local"):
        load_scene(write(tmp_path, text.replace("cycle_local = true", 'cycle_local = "yes"')))

