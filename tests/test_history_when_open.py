"""A law's history through a contact that opens (FrictionLaw.kept_when_open): every field
starts again by default; the fields a law keeps follow the contact while it is open."""

import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial, check_friction_law
from dda.materials import LinearElastic
from dda.registry import make_solver

ROCK = LinearElastic(young=10e9, poisson=0.25, density=2500.0)


class SlipKept(CoulombSingle):
    """Coulomb that keeps its accumulated slip while a contact is open (the numpy path)."""

    def __repr__(self):
        return f"SlipKept(phi={self.phi})"

    def kept_when_open(self):
        return ("slip",)


def hop(law, solver):
    """A 1 x 0.5 m block sliding down a 38 degree slope at phi 25, lifted off it for 20 ms at
    t = 0.5 s by a point load of twice its weight's normal part: (simulation, slide along
    the slope in m at the hop's start, and at the end)."""
    th = np.radians(38.0)
    t, n = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    weight = 2500 * 0.5 * 9.81
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(0, 0), (4, 0), (4, 4 * np.tan(th))], ROCK, fixed=True, name="slope")
    foot = 1.5 * t + 1e-6 * n
    block = scene.add_block([tuple(p) for p in (foot, foot + t, foot + t + 0.5 * n,
                                                foot + 0.5 * n)], ROCK, name="block")
    lift = tuple(2 * weight * np.cos(th) * n)
    scene.add_point_load(block, point=tuple(2.0 * t + 0.25 * n),
                         force=lambda s: lift if 0.5 <= s < 0.52 else (0.0, 0.0))
    scene.set_joint(JointMaterial(1e10, 1e10, friction=law))
    sim = dda.Simulation(scene, dt=1e-3, solver=make_solver(solver))
    result = sim.run(0.6, progress=False)
    slide = -result.displacement(block) @ t
    return sim, float(np.interp(0.5, result.time, slide)), float(slide[-1])


@pytest.mark.parametrize("solver", ["legacy", "newton"])
def test_a_kept_field_follows_a_contact_through_a_hop(solver):
    """The block slides 0.30 m before the hop, flies, and slides on after it lands: with the
    field kept its contacts' plastic slip at the end is the slip since the landing (all that
    the default keeps, 13 mm) plus the 0.30 m before the hop and what it slid while lifting."""
    check_friction_law(SlipKept(phi=25.0))
    kept, before, end = hop(SlipKept(phi=25.0), solver)
    plain, before_plain, end_plain = hop(CoulombSingle(phi=25.0), solver)
    assert (before, end) == pytest.approx((before_plain, end_plain), rel=1e-9)  # no feedback
    assert before == pytest.approx(0.5 * 9.81 * (np.sin(np.radians(38.0)) - np.tan(
        np.radians(25.0)) * np.cos(np.radians(38.0))) * 0.5**2, rel=0.01)  # a rigid block
    closed = kept.committed.contacts.state != 0
    assert np.count_nonzero(closed) == 2
    since_landing = plain.committed.contacts.history["slip"][closed]
    assert np.all((since_landing > 0.005) & (since_landing < 0.05))
    # all the slip before the hop is there, and what each contact slid between t = 0.5 s and
    # its opening (the load lifts the block over a few ms; 2 and 11 mm measured)
    extra = kept.committed.contacts.history["slip"][closed] - since_landing
    assert np.all((extra > before) & (extra < before + 0.02)), (extra, before)


def test_a_law_keeps_only_its_own_fields():
    class Bad(CoulombSingle):
        def kept_when_open(self):
            return ("damage",)

    with pytest.raises(AssertionError, match=r"kept_when_open\(\) names \['damage'\]"):
        check_friction_law(Bad(phi=30.0))
