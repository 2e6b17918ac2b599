"""A shaken two-block scene for the checkpoint tests, importable so its callables pickle.

``python -c "from tests.checkpoint_scene import main; main()" OUT`` runs it with a checkpoint
and a VTU writer and prints a line after every step (the test kills it mid-run).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic

DT = 2e-3
DURATION = 0.6
EVERY = 10


def table_acceleration(t):
    """Horizontal shaking of the base: 0.6 g at 2 Hz."""
    return (0.6 * 9.81 * np.sin(4.0 * np.pi * t), 0.0)


def build_scene():
    rock = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block([(0, 0), (2, 0), (2, 0.2), (0, 0.2)], rock, fixed=True, name="base")
    scene.add_block([(0.8, 0.2), (1.2, 0.2), (1.2, 0.4), (0.8, 0.4)], rock, name="block")
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=CoulombSingle(phi=25.0)))
    scene.shake(base, acceleration=table_acceleration)
    return scene


def simulation(writer=None):
    return dda.Simulation(build_scene(), dt=DT, solver=dda.solvers.LegacyPullBack(),
                          output=writer)


class Announce(dda.io.VTUWriter):
    """A VTU writer that says on stdout how many frames it has written, slowly enough for the
    test to interrupt the run in the middle."""

    def write(self, frame):
        super().write(frame)
        print(f"wrote {self._n}", flush=True)
        time.sleep(0.01)


class InterruptOnce(dda.io.VTUWriter):
    """A writer that writes nothing and interrupts the run (as Ctrl-C would) at its
    ``at``-th frame, once (a VTU writer, which is what a checkpoint keeps)."""

    def __init__(self, at, prefix):
        super().__init__(prefix)
        self.at, self.seen, self.armed = at, 0, True

    def write(self, frame):
        self.seen += 1
        self.last_time = frame.time
        if self.armed and self.seen == self.at:
            self.armed = False
            raise KeyboardInterrupt

    def close(self):
        pass


def main():
    out = Path(sys.argv[1])
    sim = simulation(Announce(out / "case"))
    sim.run(DURATION, checkpoint=out / "run.ckpt", checkpoint_every=EVERY)
