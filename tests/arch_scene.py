"""A semicircular arch of voussoirs on two springers (radius 5 m, 16 voussoirs, phi 40
degrees, "auto" joints): its limit thickness by the thrust line is t/R = 0.1071 (the
masonry review of 2026-12-07, by linear programming; a static analysis finds it between
0.107 and 0.1075)."""

from __future__ import annotations

import math

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic

STONE = LinearElastic(young=10e9, poisson=0.2, density=2000.0)
RADIUS = 5.0
VOUSSOIRS = 16


def build(thickness_ratio: float, phi: float = 40.0):
    """The scene and its crown voussoir (the one to the right of the crown joint)."""
    inner = RADIUS * (1.0 - thickness_ratio / 2.0)
    outer = RADIUS * (1.0 + thickness_ratio / 2.0)
    scene = dda.Scene(gravity=9.81)
    scene.add_block([(-outer - 1.0, -1.0), (-inner + 1.0, -1.0), (-inner + 1.0, 0.0),
                     (-outer - 1.0, 0.0)], STONE, fixed=True, name="left springer")
    scene.add_block([(inner - 1.0, -1.0), (outer + 1.0, -1.0), (outer + 1.0, 0.0),
                     (inner - 1.0, 0.0)], STONE, fixed=True, name="right springer")

    def at(r, a):
        x, y = r * math.cos(a), r * math.sin(a)
        return (0.0 if abs(x) < 1e-12 else x, 0.0 if abs(y) < 1e-12 else y)

    blocks = []
    for i in range(VOUSSOIRS):
        a, b = math.pi * i / VOUSSOIRS, math.pi * (i + 1) / VOUSSOIRS
        blocks.append(scene.add_block([at(inner, a), at(outer, a), at(outer, b), at(inner, b)],
                                      STONE, name=f"v{i}"))
    scene.set_joint(JointMaterial("auto", "auto", CoulombSingle(phi)))
    return scene, blocks[VOUSSOIRS // 2 - 1]
