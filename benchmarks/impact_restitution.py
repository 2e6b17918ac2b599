"""How a one-step impact rebounds: Newmark's velocity update (gamma = 1) against dt and penalty.

A 0.2 m square (E 1e10 Pa, 2500 kg/m^3) falls at 2 m/s from 1 mm onto a fixed floor, no
gravity, for 0.05 s, under both solvers, penalties E/1e4 to 1000 E and dt 1e-4 to 1e-2 s. The
step's velocity is ``v_{n+1} = 2 d / dt - v_n`` (METHOD.md section 2). When the contact closes
and settles within one step (a stiff penalty, a long step), the step's displacement is about
the 1 mm gap, so the block leaves at ``2 gap / dt - v_n``: an apparent coefficient of
restitution ``1 - 2 gap / (|v_n| dt)`` (0.90 at dt 1e-2) that is the step size's, not the
rock's. Resolved over several steps the spring is damped by gamma = 1 instead, and the
rebound depends on dt / (the spring's period). No setting gains energy: the largest kinetic
energy is the one before the impact.

Those columns are original DDA's penalty impact (``restitution=1``, no dashpot). The last
column is the same drop with the joint's default impact dashpot (``restitution=0``,
:mod:`dda.contact.dashpot`): where the impact is resolved over several steps it rebounds as
the dashpot says, whatever dt; an impact within one step still rebounds as the step's
formula says (the dashpot only damps a penetration the step resolves).

Prints one row per run; writes ``benchmarks/results/impact_restitution.md``.
Run:  python benchmarks/impact_restitution.py   (about a minute)
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic

E = 1e10
SPEED, GAP = 2.0, 1e-3


def drop(penalty: float, dt: float, solver: str, restitution: float = 1.0):
    rock = LinearElastic(young=E, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=0.0)
    scene.add_block([(-1, -0.3), (1, -0.3), (1, 0), (-1, 0)], rock, fixed=True, name="floor")
    brick = scene.add_block([(-0.1, GAP), (0.1, GAP), (0.1, GAP + 0.2), (-0.1, GAP + 0.2)],
                            rock, name="brick", velocity=(0.0, -SPEED))
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=CoulombSingle(phi=30.0), restitution=restitution))
    solver_ = dda.solvers.NewtonRaphson() if solver == "newton" else dda.solvers.LegacyPullBack()
    sim = dda.Simulation(scene, dt=dt, solver=solver_)
    e0 = sim.energy().total
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dda.PenaltyWarning)
        result = sim.run(0.05)
    v = result.velocity(brick)[:, 1]
    return v[-1] / SPEED, float(np.max(v**2) / SPEED**2), sim.energy().total / e0


def main():
    rows = ["| solver | penalty (N/m) | dt (s) | restitution | one-step formula | "
            "largest KE / KE before | energy end / start | restitution, default dashpot |",
            "|---|---|---|---|---|---|---|---|"]
    for solver in ("newton", "legacy"):
        for penalty in (E / 1e4, E / 100, E, 1000 * E):
            for dt in (1e-4, 1e-3, 1e-2):
                e, ke, energy = drop(penalty, dt, solver)
                damped, _, _ = drop(penalty, dt, solver, restitution=0.0)
                # the formula holds where the gap is closed well within one step
                one_step = SPEED * dt >= 4 * GAP
                formula = f"{1 - 2 * GAP / (SPEED * dt):.3f}" if one_step else "-"
                row = (f"| {solver} | {penalty:.0e} | {dt:.0e} | {e:.3f} | "
                       f"{formula} | {ke:.4f} | {energy:.4f} | {damped:.3f} |")
                print(row, flush=True)
                rows.append(row)
    out = Path(__file__).parent / "results" / "impact_restitution.md"
    out.write_text("\n".join(rows) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
