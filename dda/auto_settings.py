"""Choosing the contact penalty and the time step from the scene (``"auto"``).

``JointMaterial(normal_penalty="auto", shear_penalty="auto", ...)`` and
``Simulation(scene, dt="auto")`` leave the choice to :func:`choose`, which
:class:`dda.Simulation` calls once, before the first step; ``sim.choices`` (and ``dda info``)
says what it chose and why. The rule, and the measurements it comes from
(``benchmarks/auto_settings.py`` runs them again):

1. **The time step resolves the shaking.** ``dt = 1 / (N f)``, with ``f`` the frequency below
   which 99% of the shaking's spectral energy lies (the acceleration sampled at 1 kHz, or at
   its record's own spacing, over its first ``PROBE_SECONDS``) and ``N`` steps a period,

   ``N = auto_steps_per_period + ceil(auto_steps_per_drop * drop)``,

   167 + 475 drop for the fully implicit method and 400 + 4,100 drop for legacy DDA, whose
   friction is explicit, first order in dt. ``drop`` is the largest share ``1 - mu_d / mu_s`` of its
   strength that a law of the scene loses at the onset of slip
   (:meth:`dda.contact.FrictionLaw.onset_drop`, 0 for Coulomb and Barton-Bandis). A slip
   history's error comes from the instants at which the friction force jumps, found only at
   the end of the step in which they fall. Where a slip starts from rest under a law without
   a drop, the force grows from zero and a late onset costs little. With a drop the block
   was meant to accelerate at once (by ``g (mu_s - mu_d) cos(dip)`` on a plane), and loses
   that speed times the delay for the whole slip that follows; legacy DDA, whose contact
   that starts a step sticking sticks for the whole step, loses up to a step of it, so its
   error goes as ``(a + b drop) / N``. Newton's return map lets a contact slide in the very
   step whose end finds it over its strength: at 300 steps a period it needed no more for a
   drop (0.02-0.60% over the five drops below, both lengths, N within 10%). At the 167 that
   serve it where the strength does not drop (its stiffer springs, rule 2) the drop shows:
   0.07 / 0.49 / 0.34 / 1.18 / 1.05% at the five drops (the worst of N within 10% and both
   lengths), so it takes 475 more per unit of drop, 300 at the rock slope's 0.28. The rock
   slope of ``examples/rock_slope.py`` (the face-onset transition law, phi_s 40.5 degrees,
   phi_d from 40.5 to 25: drops 0 / 0.052 / 0.149 / 0.280 / 0.454; the tests' 4 s, 0.5 s a
   level, and the example's 16 s, 2 s a level; ``p`` the solver's ``auto_kappa`` x the
   inertia, the joints' default dashpots) erred, against the rigid block until the stopper
   (``benchmarks/auto_settings.py --scan``):

   =====  ============================================  =======================================
   drop   legacy: N 0.9x / rule / 1.1x; 4 s; 16 s       Newton: N 0.9x / rule / 1.1x; 4 s; 16 s
   =====  ============================================  =======================================
   0      360 / **400** / 440: 0.22 / **0.16** / 0.13;  150 / **167** / 183: 0.07 / **0.05** /
          0.08 / **0.05** / 0.05%                       0.02; 0.05 / **0.06** / 0.02%
   0.052  551 / **613** / 674: 0.47 / **0.39** / 0.38;  172 / **192** / 211: 0.27 / **0.10** /
          0.44 / **0.39** / 0.53%                       0.05; 0.32 / **0.20** / 0.10%
   0.149  911 / **1,013** / 1,114: 0.63 / **0.45** /    214 / **238** / 261: 0.16 / **0.32** /
          0.40; 0.70 / **0.68** / 0.63%                 0.06; 0.52 / **0.19** / 0.20%
   0.280  1,392 / **1,547** / 1,701: 0.57 / **0.53** /  270 / **300** / 330: 0.16 / **0.22** /
          0.51; 0.71 / **0.61** / 0.43%                 0.23; 0.30 / **0.12** / 0.10%
   0.454  2,035 / **2,262** / 2,488: 0.41 / **0.35** /  344 / **383** / 421: 0.26 / **0.11** /
          0.28; 0.57 / **0.57** / 0.34%                 0.36; 0.30 / **0.30** / 0.57%
   =====  ============================================  =======================================

   Legacy DDA's error times ``N`` is 20-80% without a drop and 450-1,300% at the drops of
   0.15-0.45; ``max(700, 5,500 drop)``, an earlier form, gave 700 steps up to a drop of
   0.127, where it erred about 1%.

   The moving base (a block on a flat table, Coulomb tan 36.4 = 0.737; 2 Hz; the rule's
   runs: Newton / legacy DDA) errs 0.74 / 0.34% at 0.8 g (1.4 mm of slip), 0.12 / 0.25%
   at 0.9 g, 0.16 / 0.090% at 1 g (0.16 / 0.091% at 1 Hz and at 5 Hz), 0.10 / 0.076% at
   1.18 and 1.3 g, 0.11 / 0.39% at 1.47 g, 0.081 / 0.15% at 1.5 g and 0.042 / 0.072% at
   1.84 g. **Slip that
   reverses without sticking**: from about 1.3 g (1.8 times the friction) the block slides
   back and forth without stopping between, and at each reversal the friction force flips by
   ``2 mu N``. Found only at the end of its step, it let the velocity err by up to ``2 mu g
   dt`` until the next reversal, by a share that depended on where in its step the reversal
   fell: Newton at 150 / 200 / 250 / 300 / 400 / 600 / 1,200 steps a period erred 2.5 / 2.2
   / 1.9 / 2.1 / 1.5 / 0.34 / 0.36% at 1.5 g; legacy DDA at 300 / 400 / 500 / 700 / 900 /
   1,200 1.5 / 3.2 / 1.2 / 0.95 / 0.35 / 0.37%. The rule does not see it; the simulation
   ends such a step at the reversal (:mod:`dda.slip_events`, scenes of up to 10 free blocks),
   which the numbers here include. With reversals located, the table shaken at 0.8, 0.9, 1,
   1.18, 1.3, 1.47, 1.5 and 1.84 g, each at the base ``N`` and 5% either side, erred at
   most (the 24 runs; 0.8 g the largest but where named; ``benchmarks/auto_settings.py
   --scan``; the penalty ``kappa`` times the inertia, rule 2):

   =======  ===============================  ==================  ========================
   N        legacy DDA, kappa 3              Newton, kappa 10    Newton, kappa 3
   =======  ===============================  ==================  ========================
   150      4.07% (0.9 g 1.69, 1 g 1.13)     1.06%               2.51% (1.3 g 1.76)
   167                                       0.74%               2.06% (1.3 g 1.37)
   200      2.14% (0.9 g 1.21)               0.46%               1.41% (1.3 g 0.75)
   300      1.15% (1.47 g 0.60)              0.25%               0.69% (1.47 g 0.37)
   400      0.64% (1.47 g 0.40)
   500      0.46%
   700      0.25%
   =======  ===============================  ==================  ========================

   so legacy DDA's base is 400 (700 before reversals were located, where 400 erred 3.2% at
   1.5 g) and Newton's 167 with springs of ten times the inertia (300 with three, 250 of
   which erred 0.91%): the table barely above its friction, whose slip of 1.4 mm is the
   scale, binds it through the stick springs' own give, ``mu g dt^2 / (2 kappa)``, 1% of it
   at 150 steps with kappa 3 and 0.3% with kappa 10. Legacy DDA gains less from stiffer
   springs (kappa 10: 1.50 / 0.62 / 0.47% at 250 / 300 / 400 steps), and on the cut slope,
   where rule 4 sets the penalty and kappa dt, a longer dt costs its first-order friction
   (below); it keeps kappa 3. Legacy's drop term grew from 3,000 to 4,100 to keep about the
   1,540 steps the rock slope's drop of 0.28 had (1,547 now), where 1,392 erred 0.71% over
   16 s.

   Without shaking (and as a cap with it) a
   block starting from rest may move ``TARGET_DEPTH`` (1%) of its half-width ``h = 2 area /
   perimeter`` in one step under gravity and the shaking's peak: ``dt = sqrt(2 TARGET_DEPTH
   h / (g + a_max))``.
2. **The penalty is a multiple of Newmark's inertia of the lightest free block**,
   ``p_n = kappa 2 m / dt^2``, ``kappa`` the solver's ``auto_kappa``: 10 for the fully
   implicit method, 3 (``KAPPA``) for legacy DDA and a solver that does not say. Stiff
   enough against the block's own mass
   that a contact is not a soft spring the block bounces on, soft enough that OPEN-CLOSE
   settles (the step's matrix is not dominated by the springs, see
   :mod:`dda.penalty_advice`). On the block on a moving base (``benchmarks/accuracy_cost.py``'s
   case, 1 s of 1 g at 2 Hz, the joints' default dashpots) the error against the analytical
   slip was, with ``p = kappa 2 m / dt^2`` and ``dt = 0.5 s / N``:

   =====  ==============================  ==============================
   N      legacy DDA, kappa 3 / 10 / 30   Newton, kappa 3 / 10 / 30
   =====  ==============================  ==============================
   75     2.8 / 2.0 / 2.3%                1.7 / 0.88 / 0.72%
   100    2.2 / 2.6 / 0.54%               0.95 / 0.27 / 0.14%
   150    0.30 / 0.48 / 0.33%             0.40 / 0.18 / 0.22%
   200    0.44 / 0.52 / 0.25%             0.20 / 0.068 / 0.056%
   300    0.13 / 0.17 / 0.16%             0.086 / 0.025 / 0.025%
   =====  ==============================  ==============================

   Before slip reversals were located legacy DDA wanted the softer springs (kappa 30 erred
   15.4 / 13.1 / 3.3 / 0.81% at 75 / 100 / 200 / 300 steps: its stick is explicit, and a
   stiff one rang); with them located the three are within 0.3% of each other from 150
   steps on. Newton gains most from stiffer springs where the steps are few (kappa 10
   against 3: 0.18 / 0.40% at 150 steps, 0.27 / 0.95% at 100), and takes 10 with its 167
   steps a period (rule 1: 0.16% at 1 g, 0.74% at most over the table's amplitudes);
   legacy DDA's 3 serves it at 400 (0.090%).
3. **No contact sinks deeper than 1% of its half-width under its load**: the penalty is raised
   to ``F / (TARGET_DEPTH h)`` where a block's load ``F`` (per vertex contact, two sharing a
   face) is its weight, the weight of the free blocks above it (each by the share of its
   width that lies over the block) and its point loads, times ``1 + a_max / g`` under
   shaking. When that is more than ``kappa`` times the inertia and dt is "auto" too, dt is
   shortened until it is not.
4. **A jointed mass is not softer than its rock**: where free blocks rest on free blocks,
   the penalty is at least ``MASS_STIFFNESS`` (2) times the smallest Young's modulus of the
   blocks that carry others, and an "auto" dt is shortened to keep it at ``kappa`` times the
   inertia. Joints softer than the rock make the whole mass softer and change its answer: on
   the cut slope of ``examples/jointed_slope.py`` (E 1e10 Pa) the face blocks' median motion
   after 0.3 s was 55 mm at 0.22 E (the first three rules' 2.2e9 N/m; 57 and 61 mm at dt
   3.6e-4 and 1.8e-4: not the step), 38 mm at 0.5 E, 31 mm at E, 29 mm at 2 E and 27 mm at
   5 E. A single block on its base does not depend on it (the moving base and the rock slope,
   the rule's validation, get no floor). Newton's kappa of 10 gives it a step ``sqrt(10 /
   3)`` times legacy DDA's (4.3e-4 s against 2.4e-4 at 2e10 N/m): over 3 s of shaking on
   five cuts of the rock mass (``benchmarks/cut_rate.py --auto --seconds 3``) 2 of 34,242
   steps were cut, against none of 62,503 at kappa 3, in 914 s of CPU against 1,155, and the
   face blocks moved 135 / 150 / 143 / 167 / 134 mm (median), against 136 / 157 / 123 / 131 /
   147 mm at kappa 3 and, at 2e10 N/m and dt 1.2e-4 s, 206 and 174 mm (cuts 2 and 3) and 136
   (cut 4): these wedges are near their limit, and neither step is the nearer throughout.
5. The shear penalty equals the normal one.
6. **A given penalty bounds an "auto" dt the same way**: a joint's normal penalty given as a
   number stays, and ``dt="auto"`` is shortened until the stiffest such penalty is at most
   ``kappa`` times the lightest free block's inertia, ``dt = sqrt(2 kappa m / p)``, as rules
   3 and 4 shorten it for a chosen one. Without it a stiff given penalty kept the shaking's
   or the fall's dt: a 5 cm pebble on joints of 1e11 N/m got 7.1e-3 s, 144 times its
   contact period, which :func:`dda.plausibility.check_time_step` then warned of, naming
   ``dt="auto"`` as the remedy; and the cut slope of ``examples/jointed_slope.py`` at its
   5e10 N/m got 3.0e-3 s (Newton) where the rule gives its 185 kg lightest block 2.7e-4 s
   (legacy DDA: 1.5e-4 s).
7. **An impact at the start's speeds sinks no deeper than 1% of the block's half-width**: a
   block of mass ``m`` thrown at ``v`` (its spin's speed at its farthest vertex included)
   sinks ``v sqrt(m / p)`` into what it hits, so the penalty is at least ``m v^2 /
   (TARGET_DEPTH h)^2`` over the free blocks, and an "auto" dt is shortened to keep it at
   ``kappa`` times the inertia (dynamic analysis; a static one starts every step at rest).
   Without it a 9 cm block thrown at 21 m/s got 8.6e5 N/m (the rest's rules: its weight and
   the inertia at the fall's dt), sank 1.1 cm, more than its half-width, in its first
   millisecond, and its run stopped on an untracked penetration (a hunt of the session of
   2026-12-06: 7 of its 10 legacy runs of such scenes; 0 of 8 under Newton).

8. **A bolt's vibration is resolved** (dynamic analysis): a bolt is a physical spring (its
   rock's steel, ``E A / L`` per metre of the section), not a contact's penalty, and how far
   it swings decides whether it breaks. ``dt`` is at most its shortest period
   (:func:`dda.bolts.shortest_period`: ``2 pi sqrt(m / k)`` with the block's rigid mass seen
   at the bolt's point) over ``BOLT_STEPS_PER_PERIOD`` (250). Newmark's gamma = 1 damps a
   vibration by ``exp(-pi omega dt / 4)`` in half a period, so a bolted block let go from
   rest pulls its bolt to about ``1 - pi^2 / (4 N)`` of the undamped ``2 W`` at ``N`` steps a
   period: 0.892 / 0.971 / 0.990 at 20 / 82 / 250 steps (the recursion of the one-mass
   system; ``tests/test_bolts.py`` runs it). Without the rule a 2 m wedge hung from a bolt of
   2.2e7 N/m (period 82 ms) got the fall's 0.032 s, 2.6 steps a period, and its bolt peaked at
   1.31 W: a bolt of strength 1.5 W survived that breaks at 1.94 W with dt 1e-3 s (an
   underground review of the session of 2026-12-07).

9. **A static analysis's step shows a mechanism** (``analysis="static"``): a static step
   starts at rest, so a block under an unbalanced acceleration ``a`` moves ``a dt^2 / 2`` a
   step, and a dynamic-sized dt hides a mechanism: a masonry arch 2% thinner than its limit,
   static at the fall's 1e-3 s, crept 0.19 mm in 4 s and 3,954 steps and looked as if it
   stood, where at 0.05 s it moved 25 mm in 80 steps (a masonry review of the session of
   2026-12-07). The step is that of a static trial of the factor of safety
   (:mod:`dda.studies.factor_of_safety`) with its defaults: ``STATIC_STEPS`` (40) steps
   move the smallest free block by ``STATIC_DISPLACEMENT_RATIO`` (1%) of its size under an
   unbalanced acceleration of ``STATIC_RESOLUTION`` (1e-3) g,
   ``dt = sqrt(4 d / (40 a))`` (an acceleration held for ``N`` static steps moves a block
   ``N a dt^2 / 2``; the factor of safety's second half counts), capped at 50 contact
   periods ``2 pi sqrt(m / p)`` of the lightest free block on the stiffest joint. Rules 1,
   6, 7 and 8 are for time: they do not apply, and the penalty (rules 2 to 5) is not held to
   the inertia of a step that has none.

A joint with a number keeps it; only "auto" values are chosen, all with the same rule (the
lightest free block and the most loaded contact of the scene).

The rule's own runs (``benchmarks/results/auto_settings.md``) err 0.16% / 0.22% / 0.12%
(Newton: moving base / rock slope 4 s / 16 s; 167 / 300 / 300 steps a period) and 0.090% /
0.53% / 0.61% (legacy DDA: 400 / 1,547 / 1,547). On the moving base Newton takes the
steps of the cheapest hand-picked cell within 1% of ``benchmarks/accuracy_cost.py``'s grid
(dt 3e-3 s, 2e7 N/m: 337 steps, 0.89%) and its CPU time (0.077 s against 0.076 s, the median
of seven runs each; 0.021 s against 0.023 s in one warm run of each on a 2-core AMD EPYC,
2026-12-07), for a sixth of the error (it took 300 steps a period with kappa 3: 1.8 times the
CPU). Legacy DDA takes 1.65 times its cheapest cell within 1% (dt 3e-3 s, 2e8 N/m: 0.28%)
and 0.69 times its cheapest as accurate as the rule (dt 1e-3 s, 2e10 N/m: 0.087%).

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dda._checks import finite_number
from dda.bolts import shortest_period
from dda.contact.friction import FrictionLaw
from dda.penalty_advice import TARGET_DEPTH
from dda.plausibility import DT_PERIODS

__all__ = ["AutoChoice", "BOLT_STEPS_PER_PERIOD", "KAPPA", "MASS_STIFFNESS", "PROBE_SECONDS",
           "STATIC_CAP_PERIODS", "STATIC_DISPLACEMENT_RATIO", "STATIC_RESOLUTION",
           "STATIC_STEPS", "choose", "static_step", "largest_onset_drop", "penalty_floor",
           "shaking_frequency", "static_step_cap", "steps_for_drop"]

#: the penalty as a multiple of Newmark's inertia 2 m / dt^2 of the lightest free block, for
#: a solver without its own ``auto_kappa`` (legacy DDA's; the fully implicit method takes 10)
KAPPA = 3.0
#: where blocks carry blocks, the penalty at least this multiple of their rock's Young's modulus
MASS_STIFFNESS = 2.0
#: how much of a shaking history (s) its frequency is measured over when the run's length
#: is not known
PROBE_SECONDS = 20.0
#: the most samples a shaking history's frequency is measured from (a record sampled finer
#: than its probe allows is read at PROBE_SECONDS / PROBE_SAMPLES)
PROBE_SAMPLES = 1 << 20
#: the share of the shaking's spectral energy below the frequency dt resolves
ENERGY_SHARE = 0.99
#: steps a period of the fastest bolt's vibration (rule 8): its peak force 1% low
BOLT_STEPS_PER_PERIOD = 250
#: a static analysis's step (rule 9): this many steps move the smallest free block by
#: STATIC_DISPLACEMENT_RATIO of its size under an unbalanced STATIC_RESOLUTION g, ...
STATIC_STEPS = 40
STATIC_DISPLACEMENT_RATIO = 0.01
STATIC_RESOLUTION = 1e-3
#: ... capped at this many contact periods of the lightest free block on the stiffest joint
#: (half of those at which a dynamic step is warned of; the factor of safety's static trials
#: take the same cap, static_step_cap)
STATIC_CAP_PERIODS = 0.5 * DT_PERIODS


@dataclass(frozen=True)
class AutoChoice:
    """What :func:`choose` chose: the step (s), the penalties (N/m) and why (``text``)."""

    dt: float
    normal_penalty: float
    shear_penalty: float
    text: str


def _samples(histories, duration: float | None):
    """Each history's acceleration sampled at 1 kHz (or its record's sampling interval, its
    length over its samples less one, where that is finer; ``PROBE_SAMPLES`` samples at
    most) from 0 to ``duration`` (default: the record's end, at most ``PROBE_SECONDS``):
    ``(step, a)`` pairs, ``a`` of shape (n, 2).

    Not the finest spacing: a jump written as two samples 1e-12 s apart, or two records
    merged at the union of their times that differ in the last bit (5.6e-17 s), asked for
    1e17 samples (a MemoryError of 1.88 EiB; an earthquake engineer's review, 2026-12-07);
    nor the median, which a square wave of such pairs makes the hair (73.8 GiB)."""
    span = min(duration, PROBE_SECONDS) if duration else PROBE_SECONDS
    out = []
    for h in histories:
        # (and never more than PROBE_SAMPLES samples, whatever a record's spacing says)
        step = max(min(1e-3, h.typical_spacing), span / PROBE_SAMPLES)
        t = np.arange(0.0, min(span, h.end_time), step)
        if len(t) >= 8:
            out.append((step, h.sample(t)))
    return out


def shaking_frequency(histories, duration: float | None = None) -> float | None:
    """The frequency (Hz) below which ``ENERGY_SHARE`` of the shaking's spectral energy lies,
    the highest over ``histories`` (:class:`dda.effects.AccelerationHistory`, both
    components); None when there is no shaking (or it is constant).

    Each history is sampled at 1 kHz (or at its record's sampling interval) from 0 to
    ``duration`` (default: the record's end, at most ``PROBE_SECONDS``).

    Examples
    --------
    >>> import numpy as np
    >>> from dda.effects import AccelerationHistory
    >>> h = AccelerationHistory(lambda t: (9.81 * np.sin(4 * np.pi * t), 0.0))
    >>> round(shaking_frequency([h], duration=5.0), 2)
    2.0
    """
    return _frequency(_samples(histories, duration))


def _frequency(samples) -> float | None:
    freq = None
    for step, a in samples:
        a = a - a.mean(axis=0)
        p = (np.abs(np.fft.rfft(a, axis=0)) ** 2).sum(axis=1)
        if p.sum() <= 0.0:
            continue
        f = np.fft.rfftfreq(len(a), step)
        c = np.cumsum(p) / p.sum()
        fq = float(f[min(int(np.searchsorted(c, ENERGY_SHARE)), len(f) - 1)])
        freq = fq if freq is None else max(freq, fq)
    return freq if freq else None


def _block_loads(model, a_max: float) -> tuple[np.ndarray, np.ndarray]:
    """(n_blocks,) the load per vertex contact under each free block (N per m): its weight, the
    free blocks above it (by the share of their width over it) and its point loads, times
    ``1 + a_max / g``, over two contacts; and whether free blocks lie above it."""
    g = abs(model.gravity or 0.0)
    n = model.n_blocks
    x = model.x_initial
    blk = model.topo.block
    x0 = np.full(n, np.inf)
    x1 = np.full(n, -np.inf)
    np.minimum.at(x0, blk, x[:, 0])
    np.maximum.at(x1, blk, x[:, 0])
    yc = model.centroid_initial[:, 1]
    weight = np.where(model.free, model.density * model.size**2 * g, 0.0)
    width = np.maximum(x1 - x0, 1e-300)
    load = weight.copy()
    carries = np.zeros(n, dtype=bool)
    free = np.flatnonzero(model.free)
    # the column above each free block, 256 rows at a time: at 10^4 blocks each temporary is
    # 20 MB (all rows at once would be 800 MB)
    for lo in range(0, len(free), 256):
        i = free[lo:lo + 256, None]
        j = free[None, :]
        over = np.clip(np.minimum(x1[i], x1[j]) - np.maximum(x0[i], x0[j]), 0.0, None)
        above = yc[j] > yc[i]
        share = (over / width[j]) * above
        load[free[lo:lo + 256]] += (share * weight[j]).sum(axis=1)
        carries[free[lo:lo + 256]] = (share > 0.0).any(axis=1)
    if len(model.load_block):
        np.add.at(load, model.load_block, np.hypot(*model.load_constant.T))
    factor = 1.0 + (a_max / g if g > 0.0 else 0.0)
    return 0.5 * load * factor, carries


def _load_floor(model, loads: np.ndarray, a_max: float) -> tuple[float, str]:
    """Rule 3: the penalty ``F / (TARGET_DEPTH h)`` that keeps the largest load per contact
    ``F`` (:func:`_block_loads`) within ``TARGET_DEPTH`` of its block's half-width ``h`` (N/m),
    and what it keeps."""
    h = model.thickness
    need = np.where(model.free, loads / (TARGET_DEPTH * h), 0.0)
    worst = int(np.argmax(need))
    return float(need[worst]), (
        f"keeps the load under {model.block_label(worst)} ({loads[worst]:.3g} N/m per "
        f"contact{', with the shaking' if a_max else ''}) within {100 * TARGET_DEPTH:g}% of "
        f"its half-width ({h[worst]:.3g} m)")


def _mass_floor(model, carries: np.ndarray) -> tuple[float, str]:
    """Rule 4: ``MASS_STIFFNESS`` times the smallest Young's modulus of the blocks that carry
    free blocks (``carries``, :func:`_block_loads`), or 0 where none does; and whose it is."""
    if not carries.any():
        return 0.0, ""
    young = np.where(carries, model.young, np.inf)
    soft = int(np.argmin(young))
    return MASS_STIFFNESS * float(young[soft]), (
        f"{MASS_STIFFNESS:g} x the Young's modulus {young[soft]:.3g} Pa of "
        f"{model.block_label(soft)}, which carries blocks")


def penalty_floor(model) -> tuple[float, str]:
    """The least normal penalty the rule takes for ``model`` at rest (N/m), and why: rule 3
    (the resting loads, no shaking) and rule 4 (a jointed mass not softer than its rock).

    A penalty softer than this sinks a resting load deeper than ``TARGET_DEPTH`` of a block's
    half-width, or softens the mass the blocks make; :mod:`dda.penalty_advice` does not
    advise one (it advises a shorter dt instead).
    """
    loads, carries = _block_loads(model, 0.0)
    need, why = _load_floor(model, loads, 0.0)
    floor, why_mass = _mass_floor(model, carries)
    if floor > need:
        return floor, f"{why_mass}; joints softer than the rock soften the whole mass"
    return need, f"the penalty that {why}"


def largest_onset_drop(model) -> tuple[float, FrictionLaw | None]:
    """The largest strength drop at the onset of slip among a scene's friction laws.

    Parameters
    ----------
    model : dda.model.Model

    Returns
    -------
    drop : float
        The largest :meth:`dda.contact.FrictionLaw.onset_drop` of ``model``'s laws, 0 to 1.
    law : FrictionLaw or None
        Its law (None when no law's strength drops).
    """
    drop, which = 0.0, None
    for law in model.joints.laws:
        value = finite_number("onset_drop()", law.onset_drop(), nonnegative=True,
                              where=repr(law))
        if value > 1.0:
            raise ValueError(f"{law!r}: onset_drop() is the share of its strength a contact "
                             f"loses at the onset of slip, 0 to 1, got {value}")
        if value > drop:
            drop, which = value, law
    return drop, which


def steps_for_drop(steps: int, per_drop: float, drop: float) -> int:
    """Rule 1's steps a period: ``steps + ceil(per_drop * drop)``.

    Parameters
    ----------
    steps : the solver's ``auto_steps_per_period``
    per_drop : the solver's ``auto_steps_per_drop``
    drop : the largest share of its strength a law of the scene loses at the onset of slip
        (:func:`largest_onset_drop`)

    Examples
    --------
    >>> steps_for_drop(400, 4100.0, 0.2797)  # legacy DDA on the rock slope's 40.5 / 31.6
    1547
    """
    return int(steps) + max(int(np.ceil(per_drop * drop)), 0)


def _steps_per_period(model, solver, steps: int) -> tuple[int, str]:
    """The steps a period of the shaking (rule 1), and why.

    Parameters
    ----------
    model : dda.model.Model
    solver : its ``auto_steps_per_drop`` (0 when it has none)
    steps : the solver's ``auto_steps_per_period``

    Returns
    -------
    steps : int
        ``N = steps + ceil(auto_steps_per_drop * drop)``, with ``drop`` from
        :func:`largest_onset_drop`: the error of a slip history goes as ``(a + b drop) / N``.
    why : str
        The reason, for ``sim.choices``.
    """
    per_drop = float(getattr(solver, "auto_steps_per_drop", 0.0))
    drop, law = largest_onset_drop(model)
    need = steps_for_drop(steps, per_drop, drop)
    if need == steps:
        return steps, "the solver's auto_steps_per_period"
    return need, (
        f"the solver's auto_steps_per_period {steps}, and as {solver.name} resolves the onset "
        f"of slip only to a step and {law!r} loses {100 * drop:.3g}% of its strength there, "
        f"its auto_steps_per_drop {per_drop:g} x {drop:.4g} = {per_drop * drop:.1f} more, "
        "rounded up")


def choose(model, solver, dt: float | None, shakes=(), duration: float | None = None,
           auto_penalty: bool = True, speeds: np.ndarray | None = None,
           dynamic: bool = True) -> AutoChoice:
    """Choose dt (when ``dt`` is None) and the penalty (module docstring) for ``model``.

    Parameters
    ----------
    model : dda.model.Model
    solver : the solver (its ``auto_steps_per_period``, ``auto_steps_per_drop`` and
        ``auto_kappa``)
    dt : the step asked for, or None to choose it
    shakes : the scene's shaking histories (:class:`dda.effects.AccelerationHistory`)
    duration : the run's length when known (the shaking is measured over it)
    auto_penalty : whether any joint's penalty is "auto" (else only dt is chosen)
    speeds : (n_blocks,) each block's speed at the start, its spin's at its farthest vertex
        included (m/s; rule 7; None or zeros: every block starts at rest)
    dynamic : whether the analysis is dynamic (rule 8, the bolts' vibration; a static step
        starts at rest and has none)
    """
    lines = []
    free = model.free
    if not free.any():
        raise ValueError("auto settings: the scene has no free block to choose them for")
    mass = np.where(free, model.density * model.size**2, np.inf)
    light = int(np.argmin(mass))
    m = float(mass[light])
    h = model.thickness
    g = abs(model.gravity or 0.0)
    samples = _samples(shakes, duration)
    a_max = max((float(np.hypot(a[:, 0], a[:, 1]).max()) for _, a in samples), default=0.0)
    name = model.block_label(light)
    steps = int(getattr(solver, "auto_steps_per_period", 300))
    kappa = float(getattr(solver, "auto_kappa", KAPPA))
    if dt is None and not dynamic:  # rule 9
        if g <= 0.0:
            raise ValueError("auto settings: a static analysis without gravity has no "
                             "acceleration to set its step by; give dt")
        d, dt = _static_move(model)
        lines.append(f"dt: a static step ({STATIC_STEPS} of them move the smallest free block "
                     f"{100 * STATIC_DISPLACEMENT_RATIO:g}% of its size, {d:.3g} m, under an "
                     f"unbalanced {STATIC_RESOLUTION:g} g): {dt:.3g} s")
        auto_dt = "static"
    elif dt is None:
        f = _frequency(samples)
        h_min = float(np.min(h[free]))
        drive = g + a_max
        dt_move = np.sqrt(2.0 * TARGET_DEPTH * h_min / drive) if drive > 0.0 else np.inf
        if f is not None:
            steps, why = _steps_per_period(model, solver, steps)
            dt_shake = 1.0 / (steps * f)
            lines.append(f"dt: {steps} steps ({why}) per period of the shaking's {f:.3g} Hz "
                         f"(below which {100 * ENERGY_SHARE:g}% of its spectral energy lies): "
                         f"{dt_shake:.3g} s")
        else:
            dt_shake = np.inf
        if dt_move < dt_shake:
            lines.append(f"dt: a block starting from rest moves at most {100 * TARGET_DEPTH:g}% "
                         f"of the thinnest free block's half-width ({h_min:.3g} m) in a step "
                         f"under {'gravity and the shaking' if a_max else 'gravity'}: "
                         f"{dt_move:.3g} s")
        dt = float(min(dt_shake, dt_move))
        dt_springs = dt  # (the joints' springs are chosen for this step, not the bolts')
        if dynamic and model.bolts is not None:  # rule 8
            period, bolt = shortest_period(model)
            if period / BOLT_STEPS_PER_PERIOD < dt:
                dt = period / BOLT_STEPS_PER_PERIOD
                lines.append(f"dt: {BOLT_STEPS_PER_PERIOD} steps a period of the fastest "
                             f"bolt's vibration ({bolt}, {period:.3g} s: a bolt let go "
                             f"from rest then peaks within 1% of its force): {dt:.3g} s")
        if not np.isfinite(dt):
            raise ValueError("auto settings: nothing in the scene sets a time scale (no "
                             "gravity, no shaking); give dt")
        # a penalty given as a number is held to the rule's own bound (rules 2 to 4): at most
        # kappa times the lightest free block's inertia, dt shortened until it is
        penalties = np.asarray(model.joints.normal_penalty, dtype=float)
        given = penalties[np.isfinite(penalties)]
        if given.size and float(given.max()) > kappa * 2.0 * m / dt**2:
            p_given = float(given.max())
            dt = dt_springs = float(np.sqrt(kappa * 2.0 * m / p_given))
            lines.append(f"dt: shortened to {dt:.3g} s to keep the joints' given normal "
                         f"penalty {p_given:.3g} N/m at {kappa:g} x Newmark's inertia 2 m / "
                         f"dt^2 of the lightest free block ({name}, {m:.3g} kg/m)")
        auto_dt = True
    else:
        auto_dt = False
    if auto_dt is not True:
        dt_springs = dt
    if not auto_penalty:
        if auto_dt == "static":
            dt = _static_cap(model, dt, np.asarray(model.joints.normal_penalty, dtype=float),
                             m, name, lines)
        return AutoChoice(dt, np.nan, np.nan, "\n".join(lines))
    # the penalty is kappa times the inertia at the step the joints need: a step shortened
    # to resolve a bolt's vibration (rule 8) would make it 23 times stiffer for 23 times the
    # steps (a bolted 0.2 m block: 2.1e11 N/m, 70 times its rock's E, under Newton)
    inertia = 2.0 * m / dt_springs**2
    pn = kappa * inertia
    reason = (f"normal penalty: {kappa:g} x Newmark's inertia 2 m / dt^2 = {inertia:.3g} N/m "
              f"of the lightest free block ({name}, {m:.3g} kg/m): {pn:.3g} N/m")
    loads, carries = _block_loads(model, a_max)
    need, why = _load_floor(model, loads, a_max)
    if need > pn:
        pn = need
        reason = (f"normal penalty: {pn:.3g} N/m {why}; {kappa:g} x the inertia 2 m / dt^2 of "
                  f"the lightest block would be {kappa * inertia:.3g} N/m")
    if speeds is not None and np.any(speeds[free] > 0.0):
        # rule 7: an impact at the start's speed v sinks a block of mass m by v sqrt(m / p)
        # (an undamped spring; the dashpot only makes it less)
        impact = np.where(free, model.density * model.size**2 * speeds**2
                          / (TARGET_DEPTH * h) ** 2, 0.0)
        fast = int(np.argmax(impact))
        if impact[fast] > pn:
            pn = float(impact[fast])
            reason = (f"normal penalty: {pn:.3g} N/m keeps an impact of "
                      f"{model.block_label(fast)} at its starting speed ({speeds[fast]:.3g} "
                      f"m/s, its spin included) within {100 * TARGET_DEPTH:g}% of its "
                      f"half-width ({h[fast]:.3g} m): m v^2 / depth^2; {kappa:g} x the "
                      f"inertia 2 m / dt^2 of the lightest block would be "
                      f"{kappa * inertia:.3g} N/m")
    floor, why = _mass_floor(model, carries)
    if floor > pn:
        pn = floor
        reason = (f"normal penalty: {why}: {pn:.3g} N/m (joints softer than the rock soften "
                  f"the whole mass; {kappa:g} x the inertia 2 m / dt^2 of the lightest block "
                  f"would be {kappa * inertia:.3g} N/m)")
    if auto_dt is True and pn > kappa * inertia and np.sqrt(kappa * 2.0 * m / pn) < dt:
        dt = float(np.sqrt(kappa * 2.0 * m / pn))
        reason += f"; dt shortened to {dt:.3g} s to keep it at {kappa:g} x the inertia"
    lines.append(reason)
    lines.append("shear penalty: the normal penalty")
    if auto_dt == "static":
        penalties = np.asarray(model.joints.normal_penalty, dtype=float)
        dt = _static_cap(model, dt, np.where(np.isfinite(penalties), penalties, pn), m, name,
                         lines)
    return AutoChoice(dt, pn, pn, "\n".join(lines))


def _static_move(model) -> tuple[float, float]:
    """Rule 9: the move ``d`` (``STATIC_DISPLACEMENT_RATIO`` of the smallest free block's
    size) and the static step ``sqrt(4 d / (STATIC_STEPS a))``, ``STATIC_STEPS`` of which
    move that block ``d`` under an unbalanced ``a = STATIC_RESOLUTION g`` (inf without
    gravity)."""
    d = STATIC_DISPLACEMENT_RATIO * float(np.min(model.size[model.free]))
    a = STATIC_RESOLUTION * abs(model.gravity or 0.0)
    return d, float(np.sqrt(4.0 * d / (STATIC_STEPS * a))) if a > 0.0 else float("inf")


def static_step(model) -> float:
    """Rule 9's static step of ``model`` with its joints' penalties (set), capped by
    :func:`static_step_cap`: the settled start's step (:mod:`dda.settling`). Without
    gravity, the cap alone; without that either, ``ValueError``."""
    dt = min(_static_move(model)[1],
             static_step_cap(model, np.asarray(model.joints.normal_penalty, dtype=float)))
    if not np.isfinite(dt):
        raise ValueError("a static step: the scene has no gravity and no joint penalty to "
                         "set it by")
    return dt


def static_step_cap(model, penalties: np.ndarray) -> float:
    """The longest static step: ``STATIC_CAP_PERIODS`` contact periods ``2 pi sqrt(m / p)``
    of the lightest free block on the stiffest of the joints' ``penalties`` (inf without a
    finite one). Rule 9's cap, and the factor of safety's static trials'."""
    finite = penalties[np.isfinite(penalties)]
    if not finite.size:
        return float("inf")
    m = float((model.density * model.size ** 2)[model.free].min())
    return float(STATIC_CAP_PERIODS * 2.0 * np.pi * np.sqrt(m / float(finite.max())))


def _static_cap(model, dt: float, penalties: np.ndarray, m: float, name: str,
                lines: list) -> float:
    """Rule 9's cap (:func:`static_step_cap`) on a static ``dt``; the reason added to
    ``lines`` (the lightest free block ``name`` of mass ``m``) when it binds."""
    cap = static_step_cap(model, penalties)
    if cap < dt:
        p = float(penalties[np.isfinite(penalties)].max())
        lines.append(f"dt: capped at {STATIC_CAP_PERIODS:g} contact periods 2 pi sqrt(m / p) "
                     f"of the lightest free block ({name}, {m:.3g} kg/m) on the stiffest "
                     f"joint ({p:.3g} N/m): {cap:.3g} s")
        return cap
    return dt
