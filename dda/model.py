"""Model: a scene compiled into arrays, built once and never changed by a run.

The blocks' geometry and materials, which blocks carry unknowns, the joint and friction-law
tables with the pair index, the loads and constraint springs as arrays, and the block forces
of a step (METHOD.md sections 1 and 2). :func:`dda.step.step` reads it; so do the energy, the
CLI, the pictures and anyone who wants to look inside a run (``Simulation.model``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from dda import geometry
from dda.bolts import BoltTable
from dda.contact.contacts import ContactSet, pair_key
from dda.contact.dashpot import damping_ratio
from dda.contact.detection import Memo, VertexTopology
from dda.contact.friction import FrictionLaw
from dda.kernels.joints import deepest_spring, joint_rows
from dda.scene import Scene
from dda.water import water_loads

__all__ = ["JointTable", "Model"]


@dataclass(frozen=True)
class JointTable:
    """The scene's joints as arrays: one row per distinct joint, a default and per-pair rows.

    Attributes
    ----------
    default : row of the default joint, -1 when the scene has none
    pair_keys, pair_joint : sorted :func:`dda.contact.contacts.pair_key` of the pairs that
        have their own joint, and that joint's row
    normal_penalty, shear_penalty : (n_joints,) p_n and p_s
    law : (n_joints,) row of each joint's friction law in ``laws``
    laws : the distinct friction laws
    history_fields : every law's history fields and their initial values
    damping_ratio : (n_joints,) zeta of each joint's impact dashpot
        (:mod:`dda.contact.dashpot`), or None when no joint has one
    shear_damping_ratio : (n_joints,) zeta of each joint's shear dashpot (its
        ``damping_ratio`` where ``JointMaterial.shear_dashpot``, else 0), or None when no
        joint has one
    """

    default: int
    pair_keys: np.ndarray
    pair_joint: np.ndarray
    normal_penalty: np.ndarray
    shear_penalty: np.ndarray
    law: np.ndarray
    laws: tuple[FrictionLaw, ...]
    history_fields: dict
    damping_ratio: np.ndarray | None = None  # None also in checkpoints of earlier versions
    shear_damping_ratio: np.ndarray | None = None  # the same

    @classmethod
    def from_scene(cls, scene: Scene, n_blocks: int) -> JointTable:
        joints, index_of = [], {}

        def row(j):
            if id(j) not in index_of:
                index_of[id(j)] = len(joints)
                joints.append(j)
            return index_of[id(j)]

        default = row(scene.default_joint) if scene.default_joint is not None else -1
        pairs = scene.pair_joints
        keys = np.array([pair_key(a, b, n_blocks) for (a, b) in pairs], dtype=np.int64)
        ids = np.array([row(j) for j in pairs.values()], dtype=np.int64)
        order = np.argsort(keys)
        laws, law_of = [], {}
        for j in joints:
            if id(j.friction) not in law_of:
                law_of[id(j.friction)] = len(laws)
                laws.append(j.friction)
        fields = {}
        for law in laws:
            fields.update(law.history_fields())
        zeta = np.array([damping_ratio(j.restitution) for j in joints], dtype=float)
        # the shear dashpot works on the law's elastic shear displacement, ``g_se``: a law
        # that keeps none gets no shear dashpot
        zeta_s = np.where([getattr(j, "shear_dashpot", False)
                           and "g_se" in j.friction.history_fields() for j in joints], zeta, 0.0)
        # "auto" penalties are NaN until the simulation chooses them (:meth:`with_penalties`)
        return cls(default, keys[order], ids[order],
                   np.array([_penalty(j.normal_penalty) for j in joints], dtype=float),
                   np.array([_penalty(j.shear_penalty) for j in joints], dtype=float),
                   np.array([law_of[id(j.friction)] for j in joints], dtype=np.int64),
                   tuple(laws), fields, zeta if np.any(zeta > 0.0) else None,
                   zeta_s if np.any(zeta_s > 0.0) else None)

    @property
    def auto(self) -> bool:
        """Whether some penalty is still "auto" (NaN)."""
        return bool(np.isnan(self.normal_penalty).any() or np.isnan(self.shear_penalty).any())

    def with_penalties(self, normal: float, shear: float) -> JointTable:
        """The table with its "auto" normal and shear penalties set (a shear penalty left
        "auto" beside a given normal one takes that normal one)."""
        pn = np.where(np.isnan(self.normal_penalty), normal, self.normal_penalty)
        ps = np.where(np.isnan(self.shear_penalty),
                      np.where(np.isnan(self.normal_penalty), shear, pn), self.shear_penalty)
        return replace(self, normal_penalty=pn, shear_penalty=ps)

    def index(self, keys: np.ndarray) -> np.ndarray:
        """Row of the joint of each block pair (given by its pair key); -1 where none."""
        out = np.full(len(keys), self.default, dtype=np.int64)
        if len(self.pair_keys):
            pos = np.clip(np.searchsorted(self.pair_keys, keys), 0, len(self.pair_keys) - 1)
            hit = self.pair_keys[pos] == keys
            out[hit] = self.pair_joint[pos[hit]]
        return out


class Model:
    """A scene compiled into arrays (see the module docstring). Build it with ``Model(scene)``.

    Attributes
    ----------
    scene : the Scene it was built from
    n_blocks : number of blocks
    offsets : (n_blocks + 1,) CSR offsets of the blocks' vertices
    topo : :class:`dda.contact.detection.VertexTopology` of the vertices
    x_initial, centroid_initial : vertices and block centroids at the start
    size : (n_blocks,) square root of each block's area at the start (a length scale)
    thickness : (n_blocks,) ``2 area / perimeter`` at the start: half a square's side
    min_size, min_thickness : the smallest of each
    density, elasticity : (n_blocks,) and (n_blocks, 3, 3) material data
    free : (n_blocks,) True for the blocks that carry unknowns (not fixed, shaken or moved)
    rigid : (n_blocks,) bool of the blocks without strain unknowns, or None when none is
    damping : per block (mass, stiffness) Rayleigh coefficients, or None
    joints : :class:`JointTable`
    shakes, full_motions, partial_motions : the scene's shaking and prescribed motions
    load_initial, load_block, load_constant, load_varying : point loads as arrays
    spring_initial, spring_block, spring_motion, spring_mask, spring_penalty : the penalty
        springs of partial constraints, one per material point
    bolts : :class:`dda.bolts.BoltTable` of the scene's bolts, or None without any

    Examples
    --------
    >>> import dda
    >>> from dda.materials import LinearElastic
    >>> scene = dda.Scene(gravity=9.81)
    >>> _ = scene.add_block([(0, 0), (1, 0), (1, 1), (0, 1)],
    ...                     LinearElastic(young=1e9, poisson=0.2, density=1000.0))
    >>> model = Model(scene)
    >>> model.n_blocks, model.free.tolist(), model.size.tolist()
    (1, [True], [1.0])
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        blocks = scene.block_inputs
        nb = len(blocks)
        self.n_blocks = nb
        x0, offsets = scene.vertex_arrays()
        #: where the model's coordinates start, in the scene's: a scene at a site's
        #: coordinates (y = 4e6 m) is computed about its own centre
        #: (:func:`dda.geometry.site_origin`; the frames and results are in the scene's)
        self.origin = geometry.site_origin(x0)
        if self.origin.any():
            x0 = x0 - self.origin
        self.offsets = offsets
        self.topo = VertexTopology.from_offsets(offsets)
        self.x_initial = x0.copy()
        ints = geometry.polygon_integrals(x0, offsets)
        self.centroid_initial = ints.centroid.copy()
        self.size = np.sqrt(ints.area)
        edges = x0[self.topo.nxt] - x0
        perimeter = np.add.reduceat(np.hypot(edges[:, 0], edges[:, 1]), offsets[:-1])
        self.thickness = 2.0 * ints.area / perimeter
        self.min_size = float(np.min(self.size))
        self.min_thickness = float(np.min(self.thickness))
        self.density = np.array([b.material.density for b in blocks])
        # the blocks' stresses at t = 0 (Scene.add_block's stress; a checkpoint's scene from
        # before it has none); set below to 0 on the blocks whose motion is known
        self.stress_initial = np.array([getattr(b, "stress", np.zeros(3)) for b in blocks],
                                       dtype=float).reshape(-1, 3)
        self.elasticity = np.stack([b.material.elasticity() for b in blocks])
        young = np.array([b.material.young for b in blocks])
        self.young = young
        self.gravity = scene.gravity

        # blocks whose motion is known carry no unknowns; rigid ones carry no strain unknowns
        self.free = np.array([not b.fixed for b in blocks])
        rigid = np.array([b.rigid for b in blocks], dtype=bool)
        self.rigid = rigid if rigid.any() else None
        self.shakes = scene.shakes
        self.full_motions = tuple(m for m in scene.motions if not m.springs)
        self.partial_motions = tuple(m for m in scene.motions if m.springs)
        for s in self.shakes:
            self.free[s.block] = False
        for m in self.full_motions:
            self.free[m.block] = False
        # a block without unknowns has nothing for a stress to act on: it would only show in
        # the output and in the strain energy
        self.stress_initial[~self.free] = 0.0
        self.constraint_penalty = 100.0 * young.max()
        self.damping = scene.damping_coefficients()
        self.water = scene.water
        if self.water is not None and self.origin.any():
            self.water = replace(self.water, x=self.water.x - self.origin[0],
                                 y=self.water.y - self.origin[1])
        # the edges (by first vertex) the water can load: the free blocks'
        self.water_edges = np.flatnonzero(self.free[self.topo.block])
        self.joints = JointTable.from_scene(scene, nb)
        self._compile_loads(scene.point_loads)
        self._compile_springs(x0)
        # the bolts (dda.bolts), None in a scene without any
        self.bolts = BoltTable.from_scene(scene, self.free, self.origin)
        # what a step derives from the contacts' block pairs alone, kept while they stay
        self.memo = Memo(size=2)

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.__dict__.setdefault("origin", np.zeros(2))  # a model pickled before it was
        self.__dict__.setdefault("bolts", None)  # a model pickled before bolts were
        # a model pickled before these were kept (a checkpoint of an earlier version)
        if "memo" not in state:
            self.min_size = float(np.min(self.size))
            self.min_thickness = float(np.min(self.thickness))
            self.memo = Memo(size=2)

    def _compile_loads(self, loads):
        self.load_initial = np.array([ld.point for ld in loads]).reshape(-1, 2) - self.origin
        self.load_block = np.array([ld.block for ld in loads], dtype=np.int64)
        self.load_constant = np.array([ld.force(0.0) if ld.force.constant else (0.0, 0.0)
                                       for ld in loads]).reshape(-1, 2)
        self.load_varying = tuple((i, ld.force) for i, ld in enumerate(loads)
                                  if not ld.force.constant)

    def _compile_springs(self, x0):
        # one penalty spring per point (default: every vertex) of each partially constrained
        # block; the points are material points that move with the block
        partial = self.partial_motions
        points = [m.points - self.origin if m.points is not None
                  else x0[self.offsets[m.block]:self.offsets[m.block + 1]] for m in partial]
        counts = np.array([len(p) for p in points], dtype=np.int64)
        self.spring_initial = np.concatenate(points) if points else np.zeros((0, 2))
        self.spring_block = np.repeat(np.array([m.block for m in partial], dtype=np.int64),
                                      counts)
        self.spring_motion = np.repeat(np.arange(len(partial)), counts)
        self.spring_mask = np.array([m.displacement.mask for m in partial],
                                    dtype=float).reshape(-1, 2)[self.spring_motion]
        self.spring_penalty = np.array([m.penalty or self.constraint_penalty
                                        for m in partial]).reshape(-1)[self.spring_motion]

    # ------------------------------------------------------------------ lookups
    @property
    def plain_blocks(self) -> bool:
        """Whether the blocks' system is stiffness, mass, gravity and stress alone: no
        damping, point loads or constraint springs (a step then takes the compiled block
        kernels of :mod:`dda.kernels.blocks`)."""
        return (self.damping is None and not len(self.load_block) and not len(self.spring_block)
                and self.__dict__.get("water") is None)

    @property
    def moves_known(self) -> bool:
        """Whether some block's motion is given in time (shaken, or moved in full): without
        any, the known blocks stand still and a step's known increments are zero."""
        return bool(self.shakes or self.full_motions)

    def block_label(self, i: int) -> str:
        """How messages name block ``i`` (its name, or its index)."""
        return str(self.scene.blocks[int(i)])

    def joint_index(self, bj: np.ndarray, bk: np.ndarray) -> np.ndarray:
        """Row of :attr:`joints` of the joint between blocks bj and bk (-1 where none)."""
        j = self.joints
        return joint_rows(np.asarray(bj, dtype=np.int64), np.asarray(bk, dtype=np.int64),
                          self.n_blocks, j.pair_keys, j.pair_joint, j.default)

    def deepest_spring(self, contacts: ContactSet) -> float:
        """The deepest spring penetration ``-t_n / p_n`` of the closed contacts of
        ``contacts`` (m), 0 when none sinks (:meth:`spring_depths`' largest, compiled)."""
        j = self.joints
        c = contacts
        return float(deepest_spring(np.asarray(c.state, dtype=np.int8),
                                    np.ascontiguousarray(c.t_n, dtype=np.float64),
                                    np.asarray(c.bj, dtype=np.int64),
                                    np.asarray(c.bk, dtype=np.int64), self.n_blocks,
                                    j.pair_keys, j.pair_joint, j.default, j.normal_penalty))

    def spring_depths(self, contacts: ContactSet):
        """The closed contacts of ``contacts`` (indices), how deep their springs sink
        (``-t_n / p_n``, m) and their normal penalties."""
        closed = (contacts.state != 0).nonzero()[0]
        pn = self.joints.normal_penalty[self.joint_index(contacts.bj[closed],
                                                         contacts.bk[closed])]
        return closed, -contacts.t_n[closed] / pn, pn

    def initial_contacts(self) -> ContactSet:
        """An empty contact set with every law's history fields."""
        return ContactSet.empty(self.joints.history_fields)

    def initial_velocity(self) -> np.ndarray:
        """(n_blocks, 6) velocities at the start (zero for blocks whose motion is known)."""
        vel = np.zeros((self.n_blocks, 6))
        for i, b in enumerate(self.scene.block_inputs):
            vel[i, :2] = b.velocity
            vel[i, 2] = b.angular_velocity
        vel[~self.free] = 0.0
        return vel

    def initial_speeds(self) -> np.ndarray:
        """(n_blocks,) each free block's speed at the start plus its spin's speed at its
        farthest vertex from its centroid (m/s; zero for blocks whose motion is known)."""
        vel = self.initial_velocity()
        reach = np.hypot(*(self.x_initial - self.centroid_initial[self.topo.block]).T)
        farthest = np.zeros(self.n_blocks)
        np.maximum.at(farthest, self.topo.block, reach)
        return np.hypot(vel[:, 0], vel[:, 1]) + np.abs(vel[:, 2]) * farthest

    # ------------------------------------------------------------------ per step
    def known_motion(self, t1: float, known_u: np.ndarray, shaking: tuple):
        """Known translation at ``t1`` and velocity of every block whose motion is given.

        Returns ``(u, v, shaking)``: (n_blocks, 2) each, and the shaking integrators' states
        at ``t1`` (``shaking`` holds them at the step's start; nothing here changes).
        """
        u = known_u.copy()
        v = np.zeros((self.n_blocks, 2))
        after = []
        for s, start in zip(self.shakes, shaking, strict=True):
            u[s.block], v[s.block], end = s.history.advance(start, t1)
            after.append(end)
        for m in self.full_motions:
            u[m.block] = m.displacement(t1)
        return u, v, tuple(after)

    def block_forces(self, t1, ints, stress, load_points, spring_points, x=None):
        """Block stiffness, mass, damping and external forces (METHOD.md sections 1 and 2).

        ``ints`` are the polygon integrals of the blocks at the step's start, ``stress`` the
        blocks' committed stresses, the points the current places of the loads' and springs'
        material points, ``x`` the vertices at the step's start (for the water pressure).
        Returns (nb, 6, 6) k, m and c (None without damping) and (nb, 6) f.
        """
        k = geometry.stiffness_matrices(ints.area, self.elasticity)
        m = geometry.mass_matrices(ints, self.density)
        c = None
        if self.damping is not None:  # C = alpha M + beta K_e, before any penalty spring
            alpha, beta = self.damping
            c = alpha[:, None, None] * m + beta[:, None, None] * k
        f = np.zeros((self.n_blocks, 6))
        if self.gravity:
            f[:, 1] -= self.gravity * self.density * ints.area
        f[:, 3:] -= ints.area[:, None] * stress
        centroid = ints.centroid
        if self.__dict__.get("water") is not None:
            # the pressure and its stiffness: the load f_w - K_w d, the step's end to first
            # order (the start's alone fed a bobbing block's motion; dda.water)
            fw, kw = water_loads(self.water, self.x_initial if x is None else x,
                                 self.topo.nxt, self.topo.block, centroid, self.water_edges)
            f += fw
            k = k + kw
        if len(self.load_block):
            forces = self.load_constant.copy()
            for i, history in self.load_varying:  # one user callable per time-varying load
                forces[i] = history(t1)
            t = geometry.t_matrix(load_points, centroid[self.load_block])
            np.add.at(f, self.load_block, np.einsum("lij,li->lj", t, forces))
        if len(self.spring_block):
            # penalty springs p T^T T on the constrained directions of each point (METHOD s. 1)
            u = np.array([mo.displacement(t1) for mo in self.partial_motions])
            u = u[self.spring_motion]
            t = geometry.t_matrix(spring_points, centroid[self.spring_block])
            t = t * self.spring_mask[:, :, None]
            target = (self.spring_initial + u - spring_points) * self.spring_mask
            p = self.spring_penalty
            np.add.at(k, self.spring_block, p[:, None, None] * np.einsum("vij,vik->vjk", t, t))
            np.add.at(f, self.spring_block, p[:, None] * np.einsum("vij,vi->vj", t, target))
        return k, m, c, f


def _penalty(value) -> float:
    return np.nan if isinstance(value, str) else float(value)
