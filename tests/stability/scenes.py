"""The hard cases of issue 7 as scene builders: each returns (scene, dt, duration, work)."""

from __future__ import annotations

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial, StaticDynamicTransition
from dda.materials import LinearElastic
from tests.conftest import box

E = 1e9
ROCK = LinearElastic(young=E, poisson=0.25, density=2500.0)


def _joint(scene, penalty=1e10, law=None):
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=law or CoulombSingle(phi=30.0)))


def _base(scene, width=4.0, x0=-2.0):
    return scene.add_block(box(x0, -0.5, width, 0.5), ROCK, fixed=True, name="base")


def _rotated(w, h, angle_deg, bottom_at, x_center):
    """A w x h box turned by ``angle_deg`` about its centre, its lowest point at ``bottom_at``."""
    p = np.array(box(-w / 2, -h / 2, w, h))
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    p = p @ np.array([[c, s], [-s, c]])
    return p + [x_center, bottom_at - p[:, 1].min()]


def stiff_penalty():
    """Penalty 1e3 x E with dt 1e-2: a block dropped 1 cm onto a base."""
    scene = dda.Scene(gravity=9.81)
    _base(scene)
    scene.add_block(box(-0.25, 0.01, 0.5, 0.5), ROCK)
    _joint(scene, penalty=1e3 * E)
    return scene, 1e-2, 1.0, None


def fast_impact():
    """A block hitting the base at 20 m/s."""
    scene = dda.Scene(gravity=9.81)
    _base(scene)
    scene.add_block(box(-0.25, 0.001, 0.5, 0.5), ROCK, velocity=(0.0, -20.0))
    _joint(scene, penalty=1e11)
    return scene, 1e-4, 0.05, None


def tower(n=20):
    """A tower of ``n`` blocks settling under gravity."""
    scene = dda.Scene(gravity=9.81)
    _base(scene)
    for i in range(n):
        scene.add_block(box(-0.1 + 0.002 * (i % 3), 0.2 * i, 0.2, 0.2), ROCK)
    _joint(scene, penalty=1e10)
    return scene, 1e-3, 0.3, None


def corner_impact(angle):
    """A box turned by ``angle`` degrees falls at 1 m/s with a corner onto a fixed box's
    upturned corner (turned 45 degrees): vertex to vertex."""
    scene = dda.Scene(gravity=9.81)
    lower = _rotated(0.3, 0.3, 45.0, -0.5, 0.0)
    scene.add_block(lower, ROCK, fixed=True, name="anvil")
    top = lower[:, 1].max()
    upper = _rotated(0.3, 0.3, angle, top + 0.001, 0.0)
    # put the falling box's lowest corner right above the anvil's top corner
    upper[:, 0] += lower[np.argmax(lower[:, 1]), 0] - upper[np.argmin(upper[:, 1]), 0]
    scene.add_block(upper, ROCK, velocity=(0.0, -1.0))
    _joint(scene, penalty=1e10)
    return scene, 1e-3, 0.15, None


def sliver(load=1e5):
    """A 1:100 sliver (1 m x 1 cm) on a base under a point load at its middle."""
    scene = dda.Scene(gravity=9.81)
    _base(scene)
    s = scene.add_block(box(-0.5, 0.0, 1.0, 0.01), ROCK)
    scene.add_point_load(s, (0.0, 0.01), (0.0, -load))
    _joint(scene, penalty=1e10)
    return scene, 1e-3, 0.2, (s, (0.0, -load))


def spinning():
    """A block spinning at 50 rad/s drops 5 cm onto the base."""
    scene = dda.Scene(gravity=9.81)
    _base(scene)
    scene.add_block(_rotated(0.2, 0.2, 0.0, 0.05 + 0.2 * (np.sqrt(2) - 1) / 2, 0.0), ROCK,
                    angular_velocity=50.0)
    _joint(scene, penalty=1e10)
    return scene, 1e-4, 0.2, None


def incline(law, kick=1.0, slope=30.0):
    """A block kicked down a 30 degree incline at ``kick`` m/s."""
    scene = dda.Scene(gravity=9.81)
    th = np.radians(slope)
    length = 3.0
    scene.add_block([(0, 0), (length * np.cos(th), 0), (length * np.cos(th), length * np.sin(th))],
                    ROCK, fixed=True, name="slope")
    t, n = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    foot = 2.0 * t
    block = [foot, foot + 0.3 * t, foot + 0.3 * t + 0.3 * n, foot + 0.3 * n]
    scene.add_block([tuple(p) for p in block], ROCK, velocity=tuple(-kick * t))
    _joint(scene, penalty=1e10, law=law)
    return scene, 1e-3, 0.4, None


def static_far_above_dynamic():
    return incline(StaticDynamicTransition(60.0, 5.0))


def frictionless():
    return incline(CoulombSingle(phi=0.0))


def pile(n=1000, columns=25):
    """``n`` blocks dropped in loose rows into a box, settling under gravity."""
    scene = dda.Scene(gravity=9.81)
    w = 0.1
    width = columns * w * 1.2
    scene.add_block(box(0, -0.2, width, 0.2), ROCK, fixed=True, name="floor")
    scene.add_block(box(-0.2, -0.2, 0.2, 8.0), ROCK, fixed=True, name="left")
    scene.add_block(box(width, -0.2, 0.2, 8.0), ROCK, fixed=True, name="right")
    rng = np.random.default_rng(1)
    for i in range(n):
        row, col = divmod(i, columns)
        x = col * w * 1.2 + 0.01 + 0.005 * rng.random()
        scene.add_block(box(x, 0.001 + row * (w + 0.02), w, w), ROCK)
    _joint(scene, penalty=1e10)
    return scene, 1e-3, 0.5, None


def _table(t):
    """0.3 g at 2 Hz after 0.05 s of settling (module level: the scene stays picklable)."""
    return (0.0, 0.0) if t < 0.05 else (0.3 * 9.81 * np.sin(4.0 * np.pi * (t - 0.05)), 0.0)


def shaken_cut_slope():
    """A 6 m slope cut by two joint sets (as examples/jointed_slope.py, smaller) on a base and
    against a back wall that shake together: energy comes in through the shaken blocks."""
    from dda.geometry import JointSet, cut_blocks

    scene = dda.Scene(gravity=9.81)
    rock = LinearElastic(young=10e9, poisson=0.25, density=2600.0)
    base = scene.add_block(box(0.0, -1.0, 18.0, 1.0), rock, fixed=True, name="base")
    back = scene.add_block(box(16.0, 0.0, 2.0, 7.0), rock, fixed=True, name="back")
    mass = [(4.0, 0.0), (16.0, 0.0), (16.0, 6.0), (8.0, 6.0)]
    sets = [JointSet(dip=-25.0, spacing=1.0, offset=0.3),
            JointSet(dip=70.0, spacing=1.6, persistence=0.8, trace_length=3.0)]
    for i, poly in enumerate(cut_blocks(mass, sets, min_size=0.1, seed=0)):
        scene.add_block(poly, rock, name=f"rock{i}")
    scene.set_joint(JointMaterial(normal_penalty=5e10, shear_penalty=5e10,
                                  friction=CoulombSingle(phi=35.0)))
    scene.shake(base, acceleration=_table)
    scene.shake(back, acceleration=_table)
    return scene, 2e-3, 0.3, None


# ---------------------------------------------------------------- issue 17: contact integrity
IMPACT_E = 1e10
IMPACT_ROCK = LinearElastic(young=IMPACT_E, poisson=0.25, density=2500.0)


def _impact_joint(scene, penalty):
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=CoulombSingle(phi=30.0)))


def _incline(scene, dip=45.0, length=2.0):
    th = np.radians(dip)
    scene.add_block([(0, 0), (length * np.cos(th), 0), (length * np.cos(th), length * np.sin(th))],
                    IMPACT_ROCK, fixed=True, name="slope")
    return np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])


def stopper_impact(penalty=1e13, stopper_height=0.3):
    """A 0.2 m square sent at 5 m/s down a 45 degree incline (phi 30, E 1e10 Pa) into a
    stopper: a fixed wall at the incline's toe, built touching the incline. A wall lower than
    the block (``stopper_height`` 0.03 m) trips it over its top corner."""
    scene = dda.Scene(gravity=9.81)
    t, n = _incline(scene)
    h = stopper_height
    scene.add_block([(-0.3, -0.3), (0.0, -0.3), (0.0, 0.0), (0.0, h), (-0.3, h)], IMPACT_ROCK,
                    fixed=True, name="stopper")
    foot = 0.3 * t
    scene.add_block([tuple(p) for p in (foot, foot + 0.2 * t, foot + 0.2 * t + 0.2 * n,
                                        foot + 0.2 * n)], IMPACT_ROCK, velocity=tuple(-5 * t),
                    name="block")
    _impact_joint(scene, penalty)
    return scene, 0.3


def block_on_block(penalty=1e10):
    """A 0.2 m square dropped at 3 m/s onto a free slab resting on a floor."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.3, 2, 0.3), IMPACT_ROCK, fixed=True, name="floor")
    scene.add_block(box(-0.3, 0.0, 0.6, 0.2), IMPACT_ROCK, name="slab")
    scene.add_block(box(-0.05, 0.3, 0.2, 0.2), IMPACT_ROCK, name="brick", velocity=(0.0, -3.0))
    _impact_joint(scene, penalty)
    return scene, 0.3


def corner_on_corner(penalty=1e10):
    """A box turned 30 degrees falls at 3 m/s with a corner onto a fixed box's upturned
    corner."""
    scene = dda.Scene(gravity=9.81)
    lower = _rotated(0.3, 0.3, 45.0, -0.5, 0.0)
    scene.add_block(lower, IMPACT_ROCK, fixed=True, name="anvil")
    upper = _rotated(0.3, 0.3, 30.0, lower[:, 1].max() + 0.01, 0.0)
    upper[:, 0] += lower[np.argmax(lower[:, 1]), 0] - upper[np.argmin(upper[:, 1]), 0]
    scene.add_block(upper, IMPACT_ROCK, velocity=(0.0, -3.0), name="box")
    _impact_joint(scene, penalty)
    return scene, 0.3


def notch(penalty=1e10):
    """A 0.2 m square, turned 11 degrees, thrown at (1, -3) m/s into a 0.22 m wide, 0.3 m
    deep notch of a fixed (non-convex) block: it strikes the notch's wall and its floor."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-1, -0.5), (1, -0.5), (1, 0.3), (0.11, 0.3), (0.11, 0.0), (-0.11, 0.0),
                     (-0.11, 0.3), (-1, 0.3)], IMPACT_ROCK, fixed=True, name="notched")
    p = np.array(box(-0.1, -0.1, 0.2, 0.2))
    c, s = np.cos(0.2), np.sin(0.2)
    scene.add_block(p @ np.array([[c, s], [-s, c]]) + [0.0, 0.5], IMPACT_ROCK,
                    velocity=(1.0, -3.0), name="peg")
    _impact_joint(scene, penalty)
    return scene, 0.3


def ell_on_a_step(penalty=1e10):
    """An L-shaped (non-convex) block, its leg down and its inner corner facing down and to
    the right, thrown at (2, -1) m/s so that a fixed step's top corner goes into the inner
    corner: the leg strikes the step's side and the top bar its top."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(-1, -0.3, 2, 0.3), IMPACT_ROCK, fixed=True, name="floor")
    scene.add_block(box(0.0, 0.0, 0.3, 0.3), IMPACT_ROCK, fixed=True, name="step")
    ell = [(-0.2, 0.05), (-0.1, 0.05), (-0.1, 0.35), (0.3, 0.35), (0.3, 0.45), (-0.2, 0.45)]
    scene.add_block(ell, IMPACT_ROCK, velocity=(2.0, -1.0), name="ell")
    _impact_joint(scene, penalty)
    return scene, 0.3


def lip(penalty=1e10):
    """The README demo's lip, short: a block slides at 1 m/s down a 15 degree face into the
    concave corner of a lip on the same (fixed) block, and rebounds back onto the face."""
    scene = dda.Scene(gravity=9.81)
    dip = np.radians(15.0)
    t, n = np.array([np.cos(dip), -np.sin(dip)]), np.array([np.sin(dip), np.cos(dip)])

    def face(x):
        return 0.15 - x * np.tan(dip)

    x_stop = 0.5
    scene.add_block([(0, -0.1), (x_stop + 0.05, -0.1), (x_stop + 0.05, face(x_stop) + 0.04),
                     (x_stop, face(x_stop) + 0.04), (x_stop, face(x_stop)), (0, face(0))],
                    IMPACT_ROCK, fixed=True, name="lower")
    # the block's toe 2 cm from the corner
    toe = np.array([x_stop, face(x_stop)]) - 0.02 * t
    heel = toe - 0.2 * t
    scene.add_block([tuple(p) for p in (heel, toe, toe + 0.1 * n, heel + 0.1 * n)], IMPACT_ROCK,
                    velocity=tuple(1.0 * t), name="upper")
    _impact_joint(scene, penalty)
    return scene, 0.3


IMPACTS = {
    "stopper": stopper_impact,
    "low stopper": lambda penalty: stopper_impact(penalty, stopper_height=0.03),
    "block on block": block_on_block,
    "corner on corner": corner_on_corner,
    "notch": notch,
    "L on a step": ell_on_a_step,
    "lip": lip,
}


def box_tipping_off_a_step(penalty=1e9):
    """A 0.2 x 0.6 m box turned 30 degrees clockwise, dropped 0.1 m onto the upper tread of
    a fixed step (riser 0.1 m at x = 0.6) so that it overhangs the riser's top corner by
    0.1 m and tips off it; phi 25. Its step: 0.5 s, static."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-0.5, -0.5), (1.5, -0.5), (1.5, 0.1), (0.6, 0.1), (0.6, 0.0),
                     (-0.5, 0.0)], ROCK, fixed=True, name="stairs")
    p = np.array(box(0.5, 0.1, 0.2, 0.6))
    c = p.mean(axis=0)
    turn = np.radians(-30.0)
    rot = np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])
    p = (p - c) @ rot + c
    p[:, 1] += 0.2 - p[:, 1].min()
    scene.add_block([tuple(q) for q in p], ROCK, name="box")
    scene.set_joint(JointMaterial(penalty, penalty, CoulombSingle(phi=25.0)))
    return scene
