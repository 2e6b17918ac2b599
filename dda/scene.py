"""Scene: the blocks, their materials, the joints and the effects, each input checked."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from dda import geometry
from dda._checks import finite_number, finite_vector
from dda.bolts import bolt_label, outside_distance
from dda.contact.detection import TOUCH_TOLERANCE, overlap_depths
from dda.contact.joint import JointMaterial
from dda.effects import AccelerationHistory, DisplacementHistory, LoadHistory
from dda.errors import OverlapError
from dda.materials import LinearElastic
from dda.plausibility import PlausibilityWarning, check_gravity, check_unit_weight
from dda.water import WaterTable

__all__ = ["Block", "Scene", "MAX_BLOCKS", "MAX_VERTICES", "OVERLAP_TOLERANCE"]

#: the most blocks a scene takes, and vertices a block (Scene's defaults): far beyond any
#: real scene (the 10,000-block benchmarks, polygons of tens of corners), they stop a mistyped
#: input (a cut at centimetre spacing of a kilometre, a polygon of a million points) at once
#: instead of running out of memory or time
MAX_BLOCKS = 1_000_000
MAX_VERTICES = 100_000
#: blocks overlapping at the start by less than this fraction of the smaller one's size count
#: as touching: coordinates typed with 6 decimals put neighbours about 1e-7 m into each other,
#: and their contacts take that up in the first step
OVERLAP_TOLERANCE = TOUCH_TOLERANCE


@dataclass(frozen=True)
class Block:
    """A light handle on one block of a scene: its index and its name."""

    index: int
    name: str

    def __str__(self):
        return f"block {self.name!r}"


def _stress_vector(value, where: str) -> np.ndarray:
    """``(sxx, syy, sxy)`` as a checked float array (Pa)."""
    try:
        sigma = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        sigma = None
    if sigma is None or sigma.shape != (3,):
        raise ValueError(f"{where}: stress must be (sxx, syy, sxy) in Pa, got {value!r}")
    for name, v in zip(("sxx", "syy", "sxy"), value, strict=True):
        finite_number(f"stress {name}", v, where=where)
    return sigma


@dataclass
class _BlockInput:
    vertices: np.ndarray
    material: LinearElastic
    fixed: bool
    velocity: np.ndarray
    angular_velocity: float
    rigid: bool = False
    stress: np.ndarray = field(default_factory=lambda: np.zeros(3))


@dataclass
class _PointLoad:
    block: int
    point: np.ndarray
    force: LoadHistory


@dataclass
class _Motion:
    block: int
    displacement: DisplacementHistory
    penalty: float | None
    points: np.ndarray | None = None

    @property
    def springs(self) -> bool:
        """Held by penalty springs (some points or one direction) rather than moved exactly."""
        return self.points is not None or not self.displacement.mask.all()


@dataclass
class _Shake:
    block: int
    history: AccelerationHistory


@dataclass
class _Bolt:
    block_a: int
    point_a: np.ndarray
    block_b: int
    point_b: np.ndarray
    stiffness: float
    pretension: float
    strength: float | None


@dataclass
class _Damping:
    blocks: tuple[int, ...] | None  # None: every block
    mass: float
    stiffness: float


@dataclass
class _Joints:
    default: JointMaterial | None = None
    pairs: dict[tuple[int, int], JointMaterial] = field(default_factory=dict)


class Scene:
    """Blocks, materials, joints and effects of one DDA model.

    Parameters
    ----------
    gravity : float or None
        Acceleration of gravity in m/s^2, acting in -y. None or 0 means no gravity effect.

    Examples
    --------
    >>> from dda import Scene
    >>> from dda.materials import LinearElastic
    >>> rock = LinearElastic(young=1e9, poisson=0.2, density=2000.0)
    >>> scene = Scene(gravity=9.81)
    >>> base = scene.add_block([(0, 0), (1, 0), (1, 0.2), (0, 0.2)], rock, fixed=True)
    >>> base
    Block(index=0, name='block0')
    """

    def __init__(self, gravity: float | None = None, max_blocks: int = MAX_BLOCKS,
                 max_vertices: int = MAX_VERTICES):
        g = 0.0 if gravity is None else finite_number("gravity", gravity, where="Scene")
        check_gravity(g)
        self.gravity = g
        for name, value in (("max_blocks", max_blocks), ("max_vertices", max_vertices)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 3:
                raise ValueError(f"Scene: {name} must be a whole number of at least 3, got "
                                 f"{value!r}")
        self.max_blocks = int(max_blocks)
        self.max_vertices = int(max_vertices)
        self._blocks: list[_BlockInput] = []
        self._handles: list[Block] = []
        self._loads: list[_PointLoad] = []
        self._motions: list[_Motion] = []
        self._shakes: list[_Shake] = []
        self._joints = _Joints()
        self._damping: list[_Damping] = []
        self._bolts: list[_Bolt] = []

    # ------------------------------------------------------------------ blocks
    @property
    def blocks(self) -> list[Block]:
        """Handles of every block in the order they were added."""
        return list(self._handles)

    def block(self, key) -> Block:
        """The handle of a block given by handle, name or index."""
        if isinstance(key, Block):
            if key.index >= len(self._handles) or self._handles[key.index] != key:
                raise ValueError(f"{key} does not belong to this scene")
            return key
        if isinstance(key, (int, np.integer)):
            if not 0 <= key < len(self._handles):
                raise ValueError(f"no block with index {key} (the scene has {len(self._handles)})")
            return self._handles[int(key)]
        try:
            index = self._name_index().get(key)
        except TypeError:  # unhashable: no name
            index = None
        if index is None:
            raise ValueError(f"no block named {key!r}")
        return self._handles[index]

    def _name_index(self) -> dict:
        """``{name: index}`` of the blocks (kept as they are added; built again for a scene
        pickled before it was kept). A search of the list made adding n blocks O(n^2):
        20,000 took 9.6 s."""
        index = self.__dict__.get("_names")
        if index is None or len(index) != len(self._handles):
            index = {h.name: h.index for h in self._handles}
            self._names = index
        return index

    def add_block(
        self,
        vertices,
        material: LinearElastic,
        fixed: bool = False,
        name: str | None = None,
        velocity=(0.0, 0.0),
        angular_velocity: float = 0.0,
        rigid: bool = False,
        stress=None,
    ) -> Block:
        """Add a polygonal block.

        Parameters
        ----------
        vertices : (n, 2) array-like
            Corners of a simple polygon (convex or not), counter-clockwise, n >= 3, in metres.
        material : LinearElastic
        fixed : bool
            A fixed block carries no unknowns: it stays put unless it is shaken or its motion
            is prescribed in both directions.
        name : str, optional
            Defaults to ``"block<index>"``; names must be unique.
        velocity : (vx, vy)
            Initial velocity of the block's centroid (m/s).
        angular_velocity : float
            Initial angular velocity about the centroid (rad/s, counter-clockwise positive).
        rigid : bool
            A rigid block moves with 3 unknowns (translation and rotation) instead of 6: it
            does not strain and carries no stress. Worth it for blocks much stiffer than
            their joints, where the strain is tiny and costs unknowns.
        stress : (sxx, syy, sxy), optional
            Initial stress (Pa, tension positive: an in-situ compression is negative), the
            block's stress at t = 0 (METHOD.md section 1: the load ``-A [sxx, syy, sxy]`` on
            its strain unknowns at every step, as any stress it carries). Its contacts start
            unloaded, so a stressed block pushes its neighbours until they carry it
            (:meth:`set_initial_stress` for a whole rock mass). A block whose motion is known
            (fixed, shaken, moved) has no unknowns for it to act on: its stress is dropped.
        """
        index = len(self._blocks)
        if index >= self.max_blocks:
            raise ValueError(f"add_block: the scene has {index} blocks, its limit "
                             f"(Scene(max_blocks=...), default {MAX_BLOCKS:,})")
        name = f"block{index}" if name is None else str(name)
        names = self._name_index()
        if name in names:
            raise ValueError(f"a block named {name!r} exists already; block names must be unique")
        if any(ord(c) < 32 or ord(c) == 127 for c in name):
            raise ValueError(f"block name {name!r}: no control characters (a zero byte ends "
                             "a name in the VTU files' block_names)")
        where = f"block {name!r}"
        try:
            v = np.array(vertices, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{where}: vertices must be an (n, 2) array of numbers") from None
        if v.ndim == 2 and len(v) > self.max_vertices:
            raise ValueError(f"{where}: {len(v):,} vertices, more than the limit of "
                             f"{self.max_vertices:,} a block (Scene(max_vertices=...))")
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise ValueError(
                f"{where}: vertices must be an (n, 2) array with n >= 3, got {v.shape}"
            )
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{where}: vertices contain NaN or inf")
        if np.array_equal(v[0], v[-1]):
            v = v[:-1]  # a closed ring given with its first point repeated
        edges = np.roll(v, -1, axis=0) - v
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        size = np.ptp(v, axis=0).max()
        if np.any(lengths <= 1e-12 * size) or len(v) < 3:
            i = int(np.argmin(lengths))
            raise ValueError(f"{where}: vertices {i} and {(i + 1) % len(v)} coincide")
        crossings = geometry.self_intersections(v)
        if crossings:
            i, j = crossings[0]
            raise ValueError(
                f"{where}: the polygon is self-intersecting (edge {i}-{(i + 1) % len(v)} meets "
                f"edge {j}-{(j + 1) % len(v)})"
            )
        area = geometry.signed_areas(v, np.array([0, len(v)]))[0]
        if abs(area) <= 1e-14 * size * size:
            raise ValueError(f"{where}: the polygon has zero area")
        if area < 0:
            raise ValueError(
                f"{where}: the vertices are clockwise; give them counter-clockwise (reverse them)"
            )
        if not isinstance(material, LinearElastic):
            raise TypeError(f"{where}: material must be a LinearElastic, got {material!r}")
        vel = finite_vector("velocity", velocity, where=where)
        omega = finite_number("angular_velocity", angular_velocity, where=where)
        if not isinstance(rigid, (bool, np.bool_)):
            raise TypeError(f"{where}: rigid must be True or False, got {rigid!r}")
        sigma = (np.zeros(3) if stress is None
                 else _stress_vector(stress, where))
        if rigid and np.any(sigma != 0.0):
            raise ValueError(f"{where}: a rigid block carries no stress (it has no strain "
                             "unknowns); give the stress to a block that is not rigid")
        if fixed and (np.any(vel != 0.0) or omega != 0.0):
            warnings.warn(f"{where}: the block is fixed, so its initial velocity is ignored "
                          "(a moving support: Scene.prescribe_motion or Scene.shake)",
                          PlausibilityWarning, stacklevel=2)
        self._blocks.append(_BlockInput(v, material, bool(fixed), vel, omega, bool(rigid),
                                        sigma))
        handle = Block(index, name)
        self._handles.append(handle)
        names[name] = index
        return handle

    # ------------------------------------------------------------------ joints
    def set_joint(self, joint: JointMaterial, between=None):
        """Set the default joint, or the joint between one pair of blocks.

        Parameters
        ----------
        joint : JointMaterial
        between : (block, block), optional
            Two blocks (handles, names or indices); without it the joint is the scene default.
        """
        if not isinstance(joint, JointMaterial):
            raise TypeError(f"set_joint: joint must be a JointMaterial, got {joint!r}")
        if between is None:
            self._joints.default = joint
            return
        try:
            a, b = between
        except (TypeError, ValueError):
            raise ValueError("set_joint: between must be a pair of blocks") from None
        a, b = self.block(a), self.block(b)
        if a == b:
            raise ValueError(f"set_joint: between names {a} twice")
        self._joints.pairs[(min(a.index, b.index), max(a.index, b.index))] = joint

    # ------------------------------------------------------------------ effects
    def _movable(self, block, what: str, partial: bool = False) -> Block:
        # a fixed block has a known motion (zero unless shaken or fully prescribed), so it may
        # be shaken, but a partial constraint would leave a direction free
        h = self.block(block)
        if partial and self._blocks[h.index].fixed:
            raise ValueError(f"{what}: {h} is fixed; it cannot have a direction left free")
        if any(s.block == h.index for s in self._shakes) or any(
            m.block == h.index for m in self._motions
        ):
            raise ValueError(f"{what}: {h} has a prescribed motion already")
        return h

    def shake(self, block, acceleration, times=None) -> None:
        """Make a block follow an acceleration history from rest (a shaking table).

        The block translates rigidly (no rotation, no strain) and carries no unknowns.

        Parameters
        ----------
        block : Block, name or index
        acceleration : callable or array-like
            A callable ``t -> (ax, ay)`` in m/s^2, or sampled values ((n,) for x only, or
            (n, 2)) at ``times``, or a pair ``(times, values)``. Records are piecewise linear.
        times : array-like, optional
            Sample times of a recorded accelerogram (s), increasing, starting at 0, or after
            it by at most the first sample spacing (the acceleration then ramps from zero at
            t = 0 to the first sample).
        """
        h = self._movable(block, "shake")
        hist = AccelerationHistory(acceleration, times, name=f"shake of {h}")
        self._shakes.append(_Shake(h.index, hist))

    def prescribe_motion(self, block, displacement, penalty: float | None = None,
                         points=None) -> None:
        """Prescribe the displacement of every vertex of a block (or of some of its points).

        Parameters
        ----------
        block : Block, name or index
        displacement : callable
            ``t -> (ux, uy)`` in metres from the start, zero at t = 0; None in a direction
            leaves that direction free. With both given the block translates as prescribed and
            carries no unknowns; with one None, penalty springs hold the other direction.
        penalty : float, optional
            Spring stiffness (N/m) of a spring constraint; default 100 x the largest Young's
            modulus x 1 m.
        points : (n, 2) array-like, optional
            Material points of the block that follow the displacement (a loading platen on
            one face, say), each through a penalty spring; the block keeps its unknowns and
            deforms. Default: every vertex.
        """
        h = self.block(block)
        hist = DisplacementHistory(displacement, name=f"prescribe_motion of {h}")
        pts = None
        if points is not None:
            try:
                pts = np.array(points, dtype=float).reshape(-1, 2)
            except (TypeError, ValueError):
                raise ValueError(
                    f"prescribe_motion of {h}: points must be an (n, 2) array of numbers"
                ) from None
            if len(pts) == 0 or not np.all(np.isfinite(pts)):
                raise ValueError(
                    f"prescribe_motion of {h}: points must be finite and at least one")
        self._movable(h, "prescribe_motion", partial=pts is not None or not hist.mask.all())
        if penalty is not None:
            penalty = finite_number("penalty", penalty, positive=True, where="prescribe_motion")
        self._motions.append(_Motion(h.index, hist, penalty, pts))

    def add_point_load(self, block, point, force) -> None:
        """Apply a point force (N per m of thickness) at a material point of a block.

        Parameters
        ----------
        block : Block, name or index
        point : (x, y)
            Where the force acts at the start, inside the block or on its boundary; the
            point then moves with the block.
        force : (fx, fy) or callable ``t -> (fx, fy)``

        Raises
        ------
        ValueError
            When the point lies outside the block.

        A load on a fixed block moves nothing (the block is held however hard it is pushed)
        and warns (:class:`dda.PlausibilityWarning`).
        """
        h = self.block(block)
        where = f"point load on {h}"
        p = self._point_on(h, "point", point, where)
        if self._blocks[h.index].fixed:
            warnings.warn(f"{where}: the block is fixed, so the load moves nothing",
                          PlausibilityWarning, stacklevel=2)
        self._loads.append(_PointLoad(h.index, p, LoadHistory(force, name=f"point load on {h}")))

    def add_bolt(self, block_a, point_a, block_b, point_b, stiffness: float,
                 pretension: float = 0.0, strength: float | None = None) -> int:
        """Bolt two blocks together: an axial spring between a material point of each.

        The bolt's force, tension positive, is ``N = pretension + stiffness (L - L0)`` with
        ``L`` the distance between its two points and ``L0`` that at the start: the
        pretension acts from the start. It enters every step's system like the contacts
        (:mod:`dda.bolts` has the terms). A bolt whose force would exceed ``strength`` breaks
        in that step (the step is solved again without it) and stays broken.

        Parameters
        ----------
        block_a, block_b : Block, name or index
            Two different blocks; one of them may be fixed (an anchor in stable rock), not
            both.
        point_a, point_b : (x, y)
            The bolt's ends at the start, inside (or on the boundary of) block_a and
            block_b; they then move with their blocks. They must not coincide.
        stiffness : float
            Axial stiffness ``k`` (N/m per m of thickness), positive: ``E A / L`` of the
            tendon for a bolt of cross-section ``A`` per m.
        pretension : float
            Tension at the start (N per m), zero or positive.
        strength : float, optional
            Tensile force (N per m) above which the bolt breaks; None: it never breaks.
            Positive, and not below the pretension.

        Returns
        -------
        int
            The bolt's index ``i`` (``result.bolt_force(i)``).

        Examples
        --------
        >>> import dda
        >>> from dda.materials import LinearElastic
        >>> rock = LinearElastic(young=1e9, poisson=0.2, density=2000.0)
        >>> scene = dda.Scene(gravity=9.81)
        >>> base = scene.add_block([(0, 0), (2, 0), (2, 1), (0, 1)], rock, fixed=True)
        >>> top = scene.add_block([(0.5, 1), (1.5, 1), (1.5, 2), (0.5, 2)], rock)
        >>> scene.add_bolt(top, (1.0, 1.8), base, (1.0, 0.2), stiffness=1e7, pretension=5e3)
        0
        >>> scene.add_bolt(top, (1.0, 2.5), base, (1.0, 0.2), stiffness=1e7)  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        ValueError: bolt 1 (...): point_a (1, 2.5) is outside block 'block1', 0.5 m from it
        """
        a, b = self.block(block_a), self.block(block_b)
        i = len(self._bolts)
        where = bolt_label(i, a, b)
        if a == b:
            raise ValueError(f"{where}: block_a and block_b are the same block; a bolt joins "
                             "two blocks")
        ends = [self._point_on(h, name, point, where)
                for name, h, point in (("point_a", a, point_a), ("point_b", b, point_b))]
        if np.hypot(*(ends[1] - ends[0])) == 0.0:
            raise ValueError(f"{where}: point_a and point_b coincide; a bolt needs a length")
        if self._blocks[a.index].fixed and self._blocks[b.index].fixed:
            raise ValueError(f"{where}: both blocks are fixed; a bolt needs a block that can "
                             "move")
        k = finite_number("stiffness", stiffness, positive=True, where=where)
        p0 = finite_number("pretension", pretension, nonnegative=True, where=where)
        if strength is not None:
            strength = finite_number("strength", strength, positive=True, where=where)
            if strength < p0:
                raise ValueError(f"{where}: the pretension {p0:g} N/m exceeds the strength "
                                 f"{strength:g} N/m")
        self._bolts.append(_Bolt(a.index, ends[0], b.index, ends[1], k, p0, strength))
        return i

    def _point_on(self, h, name: str, point, where: str) -> np.ndarray:
        """``point`` as an array, checked finite and inside block ``h`` or on its boundary
        (within 1e-9 of its size); a ValueError names ``where`` and ``name`` otherwise."""
        p = finite_vector(name, point, where=where)
        verts = self._blocks[h.index].vertices
        out = outside_distance(verts, p)
        if out > 1e-9 * float(np.ptp(verts, axis=0).max()):
            raise ValueError(f"{where}: {name} ({p[0]:g}, {p[1]:g}) is outside {h}, "
                             f"{out:.3g} m from it")
        return p

    def set_damping(self, mass: float = 0.0, stiffness: float = 0.0, blocks=None) -> None:
        """Viscous (Rayleigh) damping of blocks, ``C = mass * M + stiffness * K_e``.

        The equation of motion becomes ``M a + C v + K u = F`` (METHOD.md section 2, A1-A3);
        with Newmark's beta 0.5, gamma 1 a step adds ``(2 / dt) C`` to the block's matrix and
        ``C v_n`` to its forces. A scene without damping has neither term.

        Parameters
        ----------
        mass : float
            Mass-proportional coefficient (1/s). It damps every velocity of the block, rigid
            motion included, measured from rest (not from a shaking table): a free block
            moving at ``v`` slows as ``exp(-mass * t)``.
        stiffness : float
            Stiffness-proportional coefficient (s). ``K_e`` acts on the strain unknowns only,
            so this damps the block's own vibration and leaves rigid motion alone; a strain
            mode of frequency ``omega`` gets the damping ratio ``stiffness * omega / 2``.
        blocks : list of blocks (handles, names or indices), optional
            The blocks damped; default every block. A later call overrides an earlier one
            for the blocks it names; zero for both coefficients removes the damping.

        Examples
        --------
        >>> from dda import Scene
        >>> scene = Scene()
        >>> scene.set_damping(mass=0.5)
        >>> scene
        Scene(0 blocks, damping)
        """
        a = finite_number("mass", mass, nonnegative=True, where="set_damping")
        b = finite_number("stiffness", stiffness, nonnegative=True, where="set_damping")
        chosen = None
        if blocks is not None:
            if isinstance(blocks, (str, Block, int, np.integer)):
                blocks = [blocks]
            try:
                chosen = tuple(self.block(k).index for k in blocks)
            except TypeError:
                raise TypeError("set_damping: blocks must be a list of blocks, names or "
                                f"indices, got {blocks!r}") from None
        self._damping.append(_Damping(chosen, a, b))

    def set_initial_stress(self, stress, blocks=None) -> None:
        """Give blocks an initial stress (an in-situ stress field).

        Parameters
        ----------
        stress : (sxx, syy, sxy) or callable
            Pa, tension positive (an in-situ compression is negative); a callable
            ``(x, y) -> (sxx, syy, sxy)`` is taken at each block's centroid, e.g. a vertical
            stress growing with depth, ``lambda x, y: (-k0 * rho * g * (h - y), -rho * g *
            (h - y), 0.0)``.
        blocks : list of Block, names or indices, optional
            Default: every block that is neither rigid nor fixed (a rigid one carries no
            stress; a block whose motion is known, fixed, shaken or moved, has no unknowns
            for it to act on, and the simulation drops its stress). A later call replaces
            an earlier one's (and ``add_block``'s) stress on the blocks it covers.

        The contacts start unloaded: the stressed blocks push each other until their joints
        carry the stress (a static analysis, ``analysis="static"``, finds that state, and
        so does a dynamic run's settled start, ``Simulation(start="settled")``; from rest a
        dynamic run starts with the push: README, "A dynamic run's start").
        """
        if blocks is None:
            chosen = [i for i, b in enumerate(self._blocks) if not (b.rigid or b.fixed)]
        else:
            chosen = [self.block(b).index for b in blocks]
        if not chosen:
            return
        ints = geometry.polygon_integrals(*self.vertex_arrays())
        for i in chosen:
            b, where = self._blocks[i], f"block {self._handles[i].name!r}"
            value = (stress(*(float(c) for c in ints.centroid[i])) if callable(stress)
                     else stress)
            sigma = _stress_vector(value, where)
            if b.rigid and np.any(sigma != 0.0):
                raise ValueError(f"{where}: a rigid block carries no stress (it has no strain "
                                 "unknowns)")
            b.stress = sigma

    def set_water_table(self, table, unit_weight: float = 9810.0) -> None:
        """Water in the joints below a water table (:mod:`dda.water`).

        Every block edge below the table takes the hydrostatic pressure
        ``unit_weight * (h(x) - y)`` as a surface traction, integrated exactly along the edge
        with the geometry of each step's start; joints carry it on both faces, so their
        contact forces are effective forces (uplift, a water-filled tension crack's push).

        Parameters
        ----------
        table : float or sequence of (x, y) or None
            A level (the table's height, m), or a polyline of strictly increasing x that
            spans every block's x at the start (constant beyond its ends while blocks move);
            None removes the water table.
        unit_weight : float
            Of the water, N/m^3 (9810 for fresh water).
        """
        if table is None:
            self._water = None
            return
        gamma = finite_number("unit_weight", unit_weight, positive=True,
                              where="Scene.set_water_table")
        check_unit_weight(gamma)
        if np.ndim(table) == 0:
            self._water = WaterTable.level(finite_number("table", table,
                                                         where="Scene.set_water_table"), gamma)
            return
        points = np.asarray(table, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2:
            raise ValueError("Scene.set_water_table: table must be a level or a polyline of "
                             f"at least 2 (x, y) points, got an array of shape {points.shape}")
        if not np.all(np.isfinite(points)):
            raise ValueError("Scene.set_water_table: the table's points contain NaN or inf")
        if np.any(np.diff(points[:, 0]) <= 0):
            raise ValueError("Scene.set_water_table: the table's x must increase strictly "
                             "(one height above each x)")
        self._water = WaterTable(points[:, 0].copy(), points[:, 1].copy(), gamma)

    @property
    def water(self) -> WaterTable | None:
        """The water table (:meth:`set_water_table`), or None: a dry scene."""
        return self.__dict__.get("_water")

    def damping_coefficients(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Per block (mass, stiffness) damping coefficients, or None without damping."""
        n = len(self._blocks)
        alpha, beta = np.zeros(n), np.zeros(n)
        for d in self._damping:
            idx = slice(None) if d.blocks is None else list(d.blocks)
            alpha[idx], beta[idx] = d.mass, d.stiffness
        if not (alpha.any() or beta.any()):
            return None
        return alpha, beta

    # ------------------------------------------------------------------ read access
    # what the scene holds, read by dda.model.Model and the tools (tuples: read only)
    @property
    def block_inputs(self) -> tuple:
        """Per block: vertices, material, fixed, velocity, angular_velocity, rigid."""
        return tuple(self._blocks)

    @property
    def shakes(self) -> tuple:
        """The shaken blocks: ``(block index, AccelerationHistory)`` records."""
        return tuple(self._shakes)

    @property
    def motions(self) -> tuple:
        """The prescribed motions: block index, displacement history, penalty, points."""
        return tuple(self._motions)

    @property
    def point_loads(self) -> tuple:
        """The point loads: block index, point, force history."""
        return tuple(self._loads)

    @property
    def bolts(self) -> tuple:
        """The bolts (:meth:`add_bolt`): blocks, points at the start, stiffness, pretension,
        strength (None: unbreakable), in the order they were added."""
        return tuple(self._bolts)

    @property
    def damping_settings(self) -> tuple:
        """The :meth:`set_damping` calls in order: blocks (None: all), mass, stiffness."""
        return tuple(self._damping)

    @property
    def default_joint(self) -> JointMaterial | None:
        """The joint of every pair that has none of its own."""
        return self._joints.default

    @property
    def pair_joints(self) -> dict:
        """``{(a, b): JointMaterial}`` with a < b block indices: the pairs' own joints."""
        return dict(self._joints.pairs)

    # ------------------------------------------------------------------ checks
    def joint_for(self, a: int, b: int) -> JointMaterial:
        """The joint between blocks a and b (the pair's, or the default)."""
        key = (min(a, b), max(a, b))
        joint = self._joints.pairs.get(key, self._joints.default)
        if joint is None:
            raise ValueError(
                f"no joint between {self._handles[a]} and {self._handles[b]}: call "
                "scene.set_joint(JointMaterial(...)) for a default"
            )
        return joint

    def validate(self) -> None:
        """Check the scene as a whole: blocks present, no overlap at the start, joints set."""
        if not self._blocks:
            raise ValueError("the scene has no blocks")
        if len(self._blocks) > 1 and self._joints.default is None:
            # every pair that can touch needs a joint; without a default, all pairs must be set
            n = len(self._blocks)
            if len(self._joints.pairs) < n * (n - 1) // 2:
                raise ValueError(
                    f"the scene has no default joint, and joints for "
                    f"{len(self._joints.pairs)} of its {n * (n - 1) // 2} block pairs: any two "
                    "blocks may come into contact during a run; call "
                    "scene.set_joint(JointMaterial(...)) without between= for the others")
        verts, offsets = self.vertex_arrays()
        water = self.water
        if water is not None and not water.is_level:
            low, high = verts[:, 0].min(), verts[:, 0].max()
            if water.x[0] > low or water.x[-1] < high:
                raise ValueError(
                    f"the water table spans x = {water.x[0]:g} to {water.x[-1]:g} m, not the "
                    f"scene's width, {low:g} to {high:g} m: extend it to cover every block")
        bad = overlap_depths(verts, offsets, OVERLAP_TOLERANCE)
        if bad:
            a, b, depth = max(bad, key=lambda abd: abd[2])
            sizes = [np.ptp(self._blocks[i].vertices, axis=0).max() for i in (a, b)]
            more = f" (and {len(bad) - 1} more pairs)" if len(bad) > 1 else ""
            raise OverlapError(
                f"{self._handles[a]} and {self._handles[b]} overlap at the start by "
                f"{depth:.3g} m, {100 * depth / min(sizes):.3g}% of the smaller block's size"
                f"{more}; blocks may touch but not overlap (an overlap under "
                f"{100 * OVERLAP_TOLERANCE:g}% of the smaller block's size counts as touching)",
                blocks=(self._handles[a], self._handles[b]), depth=depth)

    def vertex_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """All vertices stacked (n_vertices, 2) and the CSR offsets of the blocks."""
        counts = [len(b.vertices) for b in self._blocks]
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        verts = np.concatenate([b.vertices for b in self._blocks]) if self._blocks else np.zeros(
            (0, 2)
        )
        return verts, offsets

    def __repr__(self):
        effects = []
        if self.gravity:
            effects.append(f"gravity={self.gravity}")
        if self._shakes:
            effects.append(f"{len(self._shakes)} shaken")
        if self._motions:
            effects.append(f"{len(self._motions)} prescribed")
        if self._loads:
            effects.append(f"{len(self._loads)} point loads")
        if any(d.mass or d.stiffness for d in self._damping):
            effects.append("damping")
        if self._bolts:
            effects.append(f"{len(self._bolts)} bolts")
        return f"Scene({len(self._blocks)} blocks{', ' if effects else ''}{', '.join(effects)})"
