"""Scene builders of the paper cases (METHOD.md section 9), shared by examples and tests."""

from __future__ import annotations

import numpy as np

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.materials import LinearElastic

__all__ = ["shear_box", "shear_stress", "SHEAR_BOX_LENGTH", "moving_base", "relative_slip",
           "stepped_table", "rock_slope", "slide_down_dip", "SLOPE_DIP", "SLOPE_STOP",
           "ramped_sine", "stacked_cubes", "CUBE", "shaken_incline", "gap_until_stopper",
           "rocking_block", "rocking_amplitudes", "sine_displacement"]

G = 9.81

#: contact length of the shear-box cases (the upper block's width), m
SHEAR_BOX_LENGTH = 0.1


def shear_box(shear: float, friction=None, normal_stress: float = 1e6, young: float = 1e9,
              poisson: float = 0.2, penalty: float = 10e9, consolidation: float = 0.0,
              loading_stiffness: float = 1e8, driven: str = "joint"):
    """Two elastic blocks sheared along their joint under a constant normal stress.

    The direct-shear case of H 3(1) and the simple-shear case of S 3(1): a lower block
    150 x 100 mm (fixed) and an upper block 100 x 100 mm centred on it (the 25/100/25 mm
    layout of S figure 7). The normal stress acts on the upper block's top face (two point
    loads at its corners). The upper block's two lower corners are driven to the right by
    ``shear`` metres over one second, each through a spring of ``loading_stiffness`` N/m in
    x (y free). The springs stand for the loading system's compliance, so the shear stress
    rises over several steps as in the papers' figures; acting at the level of the joint they
    put no moment on the block, so both joint contacts carry the same normal and shear force
    and yield together (pushed at its top, a block this tall would tip over its front corner
    at P/N = w / 2h = 0.5 < tan 30 deg). With ``driven="corners"`` all four corners are
    driven, each through its own spring: the two at the top put a moment on the block, and
    its joint's two contacts carry unequal normal forces (what tells the two onset rules of
    :class:`dda.contact.StaticDynamicTransition` apart). The shear starts after
    ``consolidation`` seconds under the normal stress alone. Run it as a static
    analysis with ``dt = 1 / n`` and ``consolidation = dt`` for n shear steps after one
    consolidation step, for ``1 + dt`` seconds.

    Returns
    -------
    scene, lower, upper
    """
    rock = LinearElastic(young=young, poisson=poisson, density=2500.0)
    scene = dda.Scene()
    lower = scene.add_block([(0, 0), (0.15, 0), (0.15, 0.1), (0, 0.1)], rock, fixed=True,
                            name="lower")
    top_left, top_right = (0.025, 0.2), (0.125, 0.2)
    upper = scene.add_block([(0.025, 0.1), (0.125, 0.1), top_right, top_left], rock,
                            name="upper")
    force = normal_stress * SHEAR_BOX_LENGTH / 2
    for corner in (top_left, top_right):
        scene.add_point_load(upper, point=corner, force=(0.0, -force))
    points = {"joint": [(0.025, 0.1), (0.125, 0.1)],
              "corners": [(0.025, 0.1), (0.125, 0.1), top_right, top_left]}
    if driven not in points:
        raise ValueError(f"shear_box: driven must be 'joint' or 'corners', got {driven!r}")
    scene.prescribe_motion(upper, displacement=lambda t: (shear * max(t - consolidation, 0.0),
                                                          None),
                           penalty=loading_stiffness, points=points[driven])
    if friction is None:
        friction = CoulombSingle(phi=30.0)
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=friction))
    return scene, lower, upper


def shear_stress(result, lower, upper) -> np.ndarray:
    """Shear stress on the joint (Pa), positive when it resists the upper block moving right:
    the pair's shear force over the contact length."""
    return -result.joint_force(lower, upper)[:, 1] / SHEAR_BOX_LENGTH


def moving_base(penalty: float = 2e9, phi: float = 36.4, amplitude: float = G,
                freq: float = 2.0, shear_ratio: float = 1.0):
    """A block on a base that shakes horizontally: H 3(2) and A 4(1).

    Two elastic blocks (E 14.9 GPa, nu 0.2, unit weight 21.56 kN/m^3): a base 1 m x 0.2 m and
    a 0.2 m square block centred on it, joint friction ``phi`` degrees. The base follows the
    table acceleration ``amplitude sin(2 pi freq t)`` (m/s^2) from rest; the default is the
    1 g, 2 Hz shaking of METHOD.md section 10. ``penalty`` is the normal penalty (N/m), the
    shear penalty is ``shear_ratio`` times it.

    Returns
    -------
    scene, base, block
    """
    rock = LinearElastic(young=14.9e9, poisson=0.2, density=21.56e3 / G)
    scene = dda.Scene(gravity=G)
    base = scene.add_block([(0, 0), (1, 0), (1, 0.2), (0, 0.2)], rock, fixed=True, name="base")
    block = scene.add_block([(0.4, 0.2), (0.6, 0.2), (0.6, 0.4), (0.4, 0.4)], rock,
                            name="block")
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=shear_ratio * penalty,
                                  friction=CoulombSingle(phi=phi)))
    omega = 2 * np.pi * freq
    scene.shake(base, acceleration=lambda t: (amplitude * np.sin(omega * t), 0.0))
    return scene, base, block


def relative_slip(result, base, block, direction=(1.0, 0.0)) -> np.ndarray:
    """Displacement of ``block`` relative to ``base`` along ``direction`` (m), per record."""
    rel = result.displacement(block) - result.displacement(base)
    return rel @ np.asarray(direction, dtype=float)


#: dip of the rock-slope joint (degrees) and the slide at which its stopper holds (m)
SLOPE_DIP = 15.0
SLOPE_STOP = 0.105


def stepped_table(peak_gal: float = 670.0, freq: float = 2.0, levels: int = 8,
                  hold: float = 2.0):
    """Horizontal table acceleration ``t -> (a_x, 0)`` (m/s^2): a sinusoid of ``freq`` Hz whose
    amplitude rises in ``levels`` equal steps, one every ``hold`` seconds, to ``peak_gal``.

    The wave is a cosine, and the amplitude changes at whole periods. The table starts from
    rest, so it has zero mean velocity and shakes about a fixed place; a sine would drift at
    A / omega. ``hold`` must be a whole number of periods; the acceleration jumps at
    ``k * hold``.
    """
    periods = hold * freq
    if abs(periods - round(periods)) > 1e-9 or periods < 1:
        raise ValueError(f"stepped_table: hold ({hold} s) must be a whole number of periods "
                         f"of {freq} Hz")

    def accel(t):
        level = min(int(t / hold + 1e-12) + 1, levels) / levels
        return (0.01 * peak_gal * level * np.cos(2 * np.pi * freq * t), 0.0)

    accel.breakpoints = [k * hold for k in range(1, levels)]
    return accel


def rock_slope(friction, table=None, normal_penalty: float = 10e9,
               shear_penalty: float = 10e6, height: float = 0.13):
    """The two-block rock slope of the shaking-table test of S 3(2) (Adachi et al. 2017).

    A lower block with a face dipping 15 degrees, bolted to the table, and an upper block
    (240 mm along x, 130 mm high) on the face. Ryukyu limestone: E 7.0 GPa, nu 0.33,
    22.0 kN/m^3. The papers' kn 10 GN/m and ks 10 MN/m are the defaults. A lip at the toe of
    the lower block (a non-convex block) stops the slide after ``SLOPE_STOP`` = 10.5 cm, as the
    stopper of the test did. ``table`` is the table acceleration (default
    :func:`stepped_table`); ``height`` the upper block's height (m).

    Returns
    -------
    scene, lower, upper
    """
    rock = LinearElastic(young=7.0e9, poisson=0.33, density=22.0e3 / G)
    scene = dda.Scene(gravity=G)
    dip = np.radians(SLOPE_DIP)
    width, toe = 0.38, 0.05
    rise = width * np.tan(dip)

    def face(x):
        return toe + rise - x * np.tan(dip)

    x1, x2 = 0.06, 0.30
    x_stop = x2 + SLOPE_STOP * np.cos(dip)
    lip = face(x_stop) + 0.04
    lower = scene.add_block(
        [(0, 0), (x_stop + 0.03, 0), (x_stop + 0.03, lip), (x_stop, lip),
         (x_stop, face(x_stop)), (0, toe + rise)],
        rock, fixed=True, name="lower",
    )
    upper = scene.add_block([(x1, face(x1)), (x2, face(x2)), (x2, face(x1) + height),
                             (x1, face(x1) + height)], rock, name="upper")
    scene.set_joint(JointMaterial(normal_penalty=normal_penalty, shear_penalty=shear_penalty,
                                  friction=friction))
    scene.shake(lower, acceleration=table if table is not None else stepped_table())
    return scene, lower, upper


def gap_until_stopper(slide: np.ndarray, rigid: np.ndarray,
                      near: float = 0.95) -> tuple[float, int]:
    """The largest gap between a slide history and the rigid block's, over the rigid block's
    slide when either first reaches ``near`` of the stopper distance ``SLOPE_STOP`` (the
    whole history when neither does), and that record's index."""
    at = np.flatnonzero((slide >= near * SLOPE_STOP) | (rigid >= near * SLOPE_STOP))
    end = int(at[0]) if len(at) else len(slide) - 1
    gap = np.abs(slide[: end + 1] - rigid[: end + 1]).max() / max(float(rigid[end]), 1e-4)
    return float(gap), end


def slide_down_dip(result, lower, upper) -> np.ndarray:
    """Slide of the upper block down the rock-slope joint, relative to the lower block (m)."""
    dip = np.radians(SLOPE_DIP)
    return relative_slip(result, lower, upper, (np.cos(dip), -np.sin(dip)))


#: edge of the stacked concrete cubes of A 3 (m)
CUBE = 0.15


def ramped_sine(freq: float, amplitude_gal: float, ramp: float = 0.5,
                stop: float | None = None):
    """Table acceleration ``t -> (a_x, 0)``: a sine of ``freq`` Hz and ``amplitude_gal``, its
    amplitude raised over the first ``ramp`` seconds by a half-cosine (no jump at the start)
    and, when ``stop`` is given, lowered the same way over the last ``ramp`` seconds before
    ``stop``; the table is still after ``stop``.
    """
    amp = 0.01 * amplitude_gal
    omega = 2 * np.pi * freq

    def accel(t):
        env = 0.5 * (1 - np.cos(np.pi * t / ramp)) if t < ramp else 1.0
        if stop is not None:
            if t >= stop:
                return (0.0, 0.0)
            if t > stop - ramp:
                env *= 0.5 * (1 - np.cos(np.pi * (stop - t) / ramp))
        return (amp * env * np.sin(omega * t), 0.0)

    return accel


def sine_displacement(freq: float, amplitude_gal: float):
    """Table displacement ``t -> (u_x, 0)`` whose acceleration is a sine of ``freq`` Hz and
    ``amplitude_gal`` from t = 0, as a displacement history drives a table in legacy DDA
    (A, section 2):

        u_x = -(a / omega^2) sin(omega t),   so   d2u_x/dt2 = a sin(omega t)

    It starts at 0 with the velocity ``-a / omega``: the table jumps to it at the first step
    (the acceleration history of :func:`ramped_sine` starts from rest instead).
    """
    amp = 0.01 * amplitude_gal
    omega = 2 * np.pi * freq

    def displacement(t):
        return (-amp / omega**2 * np.sin(omega * t), 0.0)

    return displacement


def _joint(normal, shear, friction, restitution):
    """A joint with the impact dashpot of ``restitution``, or the default one (None)."""
    extra = {} if restitution is None else {"restitution": restitution}
    return JointMaterial(normal_penalty=normal, shear_penalty=shear, friction=friction, **extra)


def stacked_cubes(table=None, penalty: float = 2e7, shear_ratio: float = 1.0,
                  phi: float = 36.4, restitution: float | None = None, displacement=None):
    """Three 15 cm concrete cubes (7.4 kg each) stacked on a shaking table: A 3 and A 4(2).

    Unit weight 21.56 kN/m^3 (7.4 kg / 0.15^3 m^3), E 14.9 GPa, nu 0.2, joint friction
    ``phi`` degrees (A's single-block value), normal penalty ``penalty`` (A: 2e4 kN/m) and
    shear penalty ``shear_ratio`` times it, the impact dashpot of ``restitution`` (None: the
    joint's default, :class:`dda.contact.JointMaterial`). The table is a fixed 1.2 m x 0.1 m
    block following ``table`` (an acceleration history from rest, see :func:`ramped_sine`)
    or ``displacement`` (``t -> (u_x, u_y)``, see :func:`sine_displacement`), one of the two.

    Returns
    -------
    scene, table_block, cubes (bottom to top)
    """
    rock = LinearElastic(young=14.9e9, poisson=0.2, density=21.56e3 / G)
    scene = dda.Scene(gravity=G)
    base = scene.add_block([(-0.6, -0.1), (0.6, -0.1), (0.6, 0.0), (-0.6, 0.0)], rock,
                           fixed=True, name="table")
    h = CUBE / 2
    cubes = [scene.add_block([(-h, k * CUBE), (h, k * CUBE), (h, (k + 1) * CUBE),
                              (-h, (k + 1) * CUBE)], rock, name=f"cube{k + 1}")
             for k in range(3)]
    scene.set_joint(_joint(penalty, shear_ratio * penalty, CoulombSingle(phi=phi), restitution))
    if (table is None) == (displacement is None):
        raise ValueError("stacked_cubes: give the table an acceleration history (table) or a "
                         "displacement history (displacement), one of the two")
    if table is not None:
        scene.shake(base, acceleration=table)
    else:
        scene.prescribe_motion(base, displacement)
    return scene, base, cubes


def shaken_incline(friction, table, dip: float = 20.0, penalty: float = 1e9,
                   width: float = 0.2, height: float = 0.1):
    """A block on a plane dipping ``dip`` degrees, on a shaking table: the rigid-block case of
    :func:`dda.studies.references.sliding_block` with an elastic block of its own size.

    A fixed lower block (1.2 m long) whose top face dips towards +x, and a ``width`` x
    ``height`` block (E 7 GPa, nu 0.25, 2500 kg/m^3) resting on the face 0.2 m from its top
    edge. ``table`` is the lower block's acceleration ``t -> (a_x, a_y)``; the joint has
    ``penalty`` N/m normal and shear.

    Returns
    -------
    scene, lower, block, down_dip
        ``down_dip``: the unit vector down the face, for :func:`relative_slip`.
    """
    rock = LinearElastic(young=7e9, poisson=0.25, density=2500.0)
    scene = dda.Scene(gravity=G)
    b = np.radians(dip)
    length, toe = 1.2, 0.1
    top = toe + length * np.tan(b)
    lower = scene.add_block([(0.0, 0.0), (length, 0.0), (length, toe), (0.0, top)], rock,
                            fixed=True, name="lower")
    along, normal = np.array([np.cos(b), -np.sin(b)]), np.array([np.sin(b), np.cos(b)])
    p1 = np.array([0.2, top - 0.2 * np.tan(b)])
    corners = [p1, p1 + width * along, p1 + width * along + height * normal,
               p1 + height * normal]
    block = scene.add_block([tuple(map(float, c)) for c in corners], rock, name="block")
    scene.set_joint(JointMaterial(normal_penalty=penalty, shear_penalty=penalty,
                                  friction=friction))
    scene.shake(lower, acceleration=table)
    return scene, lower, block, (float(along[0]), float(along[1]))


def rocking_block(tilt: float, penalty: float = 2e8, restitution: float | None = None,
                  width: float = 0.15, height: float = 0.45, phi: float = 36.4,
                  table=None):
    """A ``width`` x ``height`` block of the stacked cubes' concrete (:func:`stacked_cubes`)
    released from rest on its right corner at ``tilt`` radians on a fixed base: Housner's
    rocking block (:func:`dda.studies.references.housner_rocking`). The joint has ``penalty``
    N/m normal and shear, friction ``phi`` degrees and the impact dashpot of ``restitution``
    (None: the joint's default, :class:`dda.contact.JointMaterial`). ``result.rotation`` of
    the block is then ``tilt`` when it stands upright. With ``table`` (an acceleration
    history, see :func:`ramped_sine`) the base shakes: at ``tilt`` 0, the block of
    :func:`dda.studies.references.housner_shaken`.

    Returns
    -------
    scene, block
    """
    rock = LinearElastic(young=14.9e9, poisson=0.2, density=21.56e3 / G)
    scene = dda.Scene(gravity=G)
    scene.add_block([(-0.6, -0.1), (0.6, -0.1), (0.6, 0.0), (-0.6, 0.0)], rock, fixed=True,
                    name="base")
    c, s = np.cos(tilt), np.sin(tilt)
    corners = np.array([(-width, 0.0), (0.0, 0.0), (0.0, height), (-width, height)])
    corners = corners @ np.array([[c, -s], [s, c]]) + [0.5 * width, 1e-7]
    block = scene.add_block([tuple(map(float, p)) for p in corners], rock, name="block")
    scene.set_joint(_joint(penalty, penalty, CoulombSingle(phi=phi), restitution))
    if table is not None:
        scene.shake(0, acceleration=table)
    return scene, block


def rocking_amplitudes(time, rotation, tilt: float, after: float = 0.02) -> np.ndarray:
    """The rocking amplitudes of a :func:`rocking_block` run released at ``tilt``: the
    largest tilt from upright (``rotation - tilt``) of each swing after the first (a swing
    ends where the tilt changes sign: an impact) that starts after ``after`` seconds."""
    theta = np.asarray(rotation) - tilt
    time = np.asarray(time)
    side = np.sign(theta)
    starts = np.flatnonzero(side[1:] != side[:-1]) + 1
    swings = np.split(np.arange(len(theta)), starts)
    return np.array([float(np.max(np.abs(theta[s]))) for s in swings[1:]
                     if len(s) and time[s[0]] > after and side[s[0]] != 0])
