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
