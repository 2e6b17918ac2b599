"""The registry of friction laws and solvers: names, keywords, user classes, import paths."""

import subprocess
import sys

import pytest

from dda import registry
from dda.contact import BartonBandis, CoulombSingle, FrictionLaw, StaticDynamicTransition
from dda.solvers import LegacyPullBack, NewtonRaphson


def test_the_built_in_classes_are_keyed_by_their_own_names():
    assert registry.law_names() == ("coulomb", "transition", "barton")
    assert registry.solver_names() == ("legacy", "newton")
    for cls in (CoulombSingle, StaticDynamicTransition, BartonBandis):
        assert registry.law_class(cls.name) is cls
    for cls in (LegacyPullBack, NewtonRaphson):
        assert registry.solver_class(cls.name) is cls


def test_keywords_come_from_the_signature():
    assert registry.parameters(CoulombSingle) == ("phi", "cohesion")
    assert set(registry.parameters(BartonBandis)) == {
        "jrc", "jcs", "phi_r", "mobilized", "slip_at_peak", "block_size", "dilation",
        "max_angle"}
    assert registry.parameters(LegacyPullBack) == ("cycle_local", "cycle_memory")
    assert registry.parameters(NewtonRaphson) == ("tol", "max_iter", "unsettled_predictor")
    law = registry.make_law("barton", jrc=10.0, jcs=50e6, phi_r=28.0, dilation=True)
    assert isinstance(law, BartonBandis) and law.dilation
    solver = registry.make_solver("newton", tol=1e-8)
    assert isinstance(solver, NewtonRaphson) and solver.tol == 1e-8
    with pytest.raises(TypeError, match=r"unknown keyword 'tol' for solver 'legacy' "
                                        r"\(it takes: cycle_local, cycle_memory\)"):
        registry.make_solver("legacy", tol=1e-8)


def test_unknown_names_list_the_registered_ones():
    with pytest.raises(registry.RegistryError,
                       match="unknown friction law 'mohr'; use one of coulomb, transition, "
                             "barton or an import path"):
        registry.law_class("mohr")
    with pytest.raises(ValueError, match="unknown solver 'implicit'; use one of legacy, "
                                         "newton"):
        registry.make_solver("implicit")
    with pytest.raises(registry.RegistryError, match="unknown solver"):
        registry.solver_class(["newton"])


class Sticky(CoulombSingle):
    name = "sticky"


class NoName(CoulombSingle):
    pass


class Quick(LegacyPullBack):
    name = "quick"

    def __init__(self, passes=1):
        self.passes = passes


def test_registering_a_class_of_ones_own():
    try:
        assert registry.register_law(Sticky) is Sticky
        assert registry.register_law(Sticky) is Sticky  # again: no error
        assert registry.law_names()[-1] == "sticky"
        assert registry.make_law("sticky", phi=10.0).phi == 10.0
        registry.register_solver(Quick)
        assert registry.make_solver("quick", passes=3).passes == 3
        assert registry.solver_names() == ("legacy", "newton", "quick")
    finally:
        registry.unregister_law("sticky")
        registry.unregister_solver("quick")
    assert "sticky" not in registry.law_names() and "quick" not in registry.solver_names()


def test_bad_registrations_are_refused():
    with pytest.raises(ValueError, match="own class attribute name"):
        registry.register_law(NoName)
    with pytest.raises(TypeError, match="subclass of dda.contact.FrictionLaw"):
        registry.register_law(Quick)
    with pytest.raises(TypeError, match="subclass of dda.solvers.NonlinearSolver"):
        registry.register_solver(Sticky)

    class Impostor(StaticDynamicTransition):
        name = "coulomb"

    with pytest.raises(ValueError, match="name 'coulomb' is taken by "
                                         "dda.contact.friction.CoulombSingle"):
        registry.register_law(Impostor)
    with pytest.raises(ValueError, match="built-in"):
        registry.unregister_law("coulomb")
    with pytest.raises(registry.RegistryError, match="no solver 'fast'"):
        registry.unregister_solver("fast")
    assert registry.law_class("coulomb") is CoulombSingle


@pytest.fixture(autouse=True)
def forget_test_modules():
    """Each test writes its own law modules: let none outlive it in sys.modules."""
    yield
    for name in [m for m in sys.modules if m.startswith("reg_")]:
        del sys.modules[name]


LAW_MODULE = '''
from dda.contact import CoulombSingle


class BrittleCohesion(CoulombSingle):
    name = "brittle"

    def __init__(self, phi, cohesion=0.0, residual=0.0):
        super().__init__(phi, cohesion)
        self.residual = residual


class Holder:
    Inner = BrittleCohesion


def helper():
    return 1
'''


def test_import_paths_name_a_class_without_registering(tmp_path):
    (tmp_path / "reg_laws_a.py").write_text(LAW_MODULE)
    cls = registry.law_class("reg_laws_a:BrittleCohesion", folder=tmp_path)
    assert cls.__name__ == "BrittleCohesion" and issubclass(cls, FrictionLaw)
    assert registry.law_class("reg_laws_a:Holder.Inner", folder=tmp_path) is cls
    assert str(tmp_path) not in sys.path and "brittle" not in registry.law_names()
    assert registry.parameters(cls) == ("phi", "cohesion", "residual")
    # once imported, the module is found without the folder too (as any import)
    assert registry.make_law("reg_laws_a:BrittleCohesion", phi=30.0, residual=1.0).residual == 1


@pytest.mark.parametrize("spec, words", [
    ("reg_nowhere:Law", "no module 'reg_nowhere' in "),
    ("reg_laws_b:Missing", "module 'reg_laws_b' has no attribute 'Missing'"),
    ("reg_laws_b:Holder.Missing", "has no attribute 'Holder.Missing'"),
    ("reg_laws_b:helper", "is a function, not a subclass of dda.contact.FrictionLaw"),
    ("reg_laws_b:Holder", "is the class reg_laws_b.Holder, not a subclass"),
    ("reg_laws_b:", "not an import path"),
    ("reg_laws_b:a-b", "not an import path"),
    (":Law", "not an import path"),
    ("reg_broken:Law", "importing module 'reg_broken' raised ZeroDivisionError"),
    ("reg_needs:Law", "importing module 'reg_needs' failed: No module named "
                      "'reg_not_installed'"),
])
def test_import_path_errors(tmp_path, spec, words):
    (tmp_path / "reg_laws_b.py").write_text(LAW_MODULE)
    (tmp_path / "reg_broken.py").write_text("x = 1 / 0\n")
    (tmp_path / "reg_needs.py").write_text("import reg_not_installed\n")
    with pytest.raises(registry.RegistryError) as info:
        registry.law_class(spec, folder=tmp_path)
    assert words in str(info.value), str(info.value)
    assert str(tmp_path) not in sys.path


def test_a_module_of_the_same_name_from_another_folder_is_an_error(tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    for folder in (one, two):
        folder.mkdir()
        (folder / "reg_laws_c.py").write_text(LAW_MODULE)
    registry.law_class("reg_laws_c:BrittleCohesion", folder=one)
    assert registry.law_class("reg_laws_c:BrittleCohesion", folder=one)  # same file: fine
    with pytest.raises(registry.RegistryError, match="'reg_laws_c' is already imported from"):
        registry.law_class("reg_laws_c:BrittleCohesion", folder=two)


def test_the_registry_imports_cleanly_first_and_loads_the_classes_on_first_use():
    code = ("import dda.registry as r; print(r.law_names(), r.solver_names())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert "('coulomb', 'transition', 'barton') ('legacy', 'newton')" in out.stdout
    with open(registry.__file__) as fh:
        top = [line for line in fh if line.startswith(("import ", "from "))]
    assert not [line for line in top if "dda" in line], top


def test_the_sweep_takes_its_solvers_from_the_registry(tmp_path, monkeypatch):
    from dda.studies import sweep
    from dda.studies.sweep import SOLVERS, make_solver

    assert SOLVERS == registry.solver_names() == ("legacy", "newton")
    assert isinstance(make_solver("legacy"), LegacyPullBack)
    assert make_solver("newton", max_iter=7).max_iter == 7
    try:
        registry.register_solver(Quick)
        assert sweep.SOLVERS == ("legacy", "newton", "quick")
        assert isinstance(make_solver("quick"), Quick)
    finally:
        registry.unregister_solver("quick")
    with pytest.raises(ValueError, match="unknown solver 'quick'; use one of legacy, newton"):
        make_solver("quick")
    # an import path works in fresh worker processes too (nothing to register there)
    (tmp_path / "reg_solvers.py").write_text(
        "from dda.solvers import LegacyPullBack\n\n\nclass Plain(LegacyPullBack):\n"
        "    name = 'plain'\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert type(make_solver("reg_solvers:Plain")).__name__ == "Plain"
    with pytest.raises(AttributeError, match="no attribute 'NOTHING'"):
        sweep.NOTHING  # noqa: B018


def test_a_simulation_takes_its_solver_by_name():
    import dda
    from dda.materials import LinearElastic

    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
                    LinearElastic(young=1e9, poisson=0.2, density=1000.0))
    for name, cls in (("legacy", LegacyPullBack), ("newton", NewtonRaphson)):
        sim = dda.Simulation(scene, dt=0.01, solver=name)
        assert type(sim.solver) is cls
    # the same run as with the instance
    by_name = dda.Simulation(scene, dt=0.01, solver="legacy").run(0.05, progress=False)
    by_instance = dda.Simulation(scene, dt=0.01, solver=LegacyPullBack()).run(
        0.05, progress=False)
    assert (by_name.displacement(0) == by_instance.displacement(0)).all()
    with pytest.raises(registry.RegistryError,
                       match="Simulation: unknown solver 'newtn'; use one of legacy, newton"):
        dda.Simulation(scene, dt=0.01, solver="newtn")
    with pytest.raises(TypeError, match="solver must be a NonlinearSolver, got 3"):
        dda.Simulation(scene, dt=0.01, solver=3)
