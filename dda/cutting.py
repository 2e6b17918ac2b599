"""Block cutting: a domain polygon cut into blocks by sets of parallel joints (with shapely).

A joint set in a 2D section is a family of parallel traces: their dip, their spacing measured
across the traces, and where the first one lies. Traces may be non-persistent: segments of a
given trace length with intact rock bridges between them. The domain's boundary and every
trace are noded together and polygonized; a trace that does not reach across a block ends in
it (a crack) and cuts nothing, as in the block cutting of DDA's DL program.

Examples
--------
>>> from dda.geometry import JointSet, cut_blocks
>>> square = [(0, 0), (3, 0), (3, 2), (0, 2)]
>>> blocks = cut_blocks(square, [JointSet(dip=0, spacing=1), JointSet(dip=90, spacing=1)])
>>> len(blocks), sorted(blocks[0])
(6, [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)])
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from dda._checks import finite_number

#: dropped slivers over this share of the domain's area are reported (a PlausibilityWarning)
SLIVER_AREA_WARNING = 0.01

__all__ = ["JointSet", "cut_blocks"]


@dataclass(frozen=True)
class JointSet:
    """A set of parallel joint traces in the section.

    Parameters
    ----------
    dip : float
        Angle of the traces below the horizontal, in degrees, going towards +x: 0 is
        horizontal bedding, 90 vertical, 30 descends towards +x, -30 (or 150) towards -x.
    spacing : float
        Distance between neighbouring traces, measured across them (m), positive.
    offset : float
        Where the traces lie: trace k passes at signed distance ``offset + k * spacing`` from
        the origin along the set's normal (m).
    persistence : float
        Fraction in (0, 1] of each trace that is jointed; below 1 each trace is segments of
        ``trace_length`` with intact rock bridges between them.
    trace_length : float, optional
        Length of one joint segment (m); required when ``persistence < 1``.
    """

    dip: float
    spacing: float
    offset: float = 0.0
    persistence: float = 1.0
    trace_length: float | None = None

    def __post_init__(self):
        where = "JointSet"
        finite_number("dip", self.dip, where=where)
        finite_number("spacing", self.spacing, positive=True, where=where)
        finite_number("offset", self.offset, where=where)
        p = finite_number("persistence", self.persistence, positive=True, where=where)
        if p > 1.0:
            raise ValueError(f"JointSet: persistence is a fraction in (0, 1], got {p}")
        if p < 1.0:
            if self.trace_length is None:
                raise ValueError("JointSet: a persistence below 1 needs a trace_length (m)")
            finite_number("trace_length", self.trace_length, positive=True, where=where)

    @property
    def direction(self) -> np.ndarray:
        a = math.radians(self.dip)
        return np.array([math.cos(a), -math.sin(a)])

    @property
    def normal(self) -> np.ndarray:
        a = math.radians(self.dip)
        return np.array([math.sin(a), math.cos(a)])

    def traces(self, bounds, rng) -> list[np.ndarray]:
        """The set's joint segments ((2, 2) arrays) over a box [xmin, ymin, xmax, ymax]."""
        xmin, ymin, xmax, ymax = bounds
        corners = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
        across = corners @ self.normal
        along = corners @ self.direction
        k = np.arange(math.ceil((across.min() - self.offset) / self.spacing),
                      math.floor((across.max() - self.offset) / self.spacing) + 1)
        lo, hi = along.min() - 1.0, along.max() + 1.0
        out = []
        for level in self.offset + k * self.spacing:
            base = level * self.normal
            if self.persistence >= 1.0:
                spans = [(lo, hi)]
            else:
                period = self.trace_length / self.persistence
                start = lo - rng.random() * period  # a random phase per trace
                starts = np.arange(start, hi, period)
                spans = [(s, s + self.trace_length) for s in starts]
            for s0, s1 in spans:
                out.append(np.array([base + s0 * self.direction, base + s1 * self.direction]))
        return out


def estimated_blocks(domain_bounds, domain_area: float, joint_sets) -> float:
    """About how many blocks the sets cut a domain into, before any is cut: with ``n_i``
    traces of set i across the domain's box (its extent across the traces over the
    spacing) and their persistence ``p_i``, ``f (1 + sum n_i p_i + sum_{i<j} n_i p_i n_j
    p_j)``, ``f`` the share of the box the domain fills (two persistent sets: ``n_1 n_2``
    cells, as a grid has)."""
    xmin, ymin, xmax, ymax = domain_bounds
    corners = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    counts = []
    for js in joint_sets:
        across = corners @ js.normal
        counts.append((across.max() - across.min()) / js.spacing * js.persistence)
    box = max((xmax - xmin) * (ymax - ymin), 1e-300)
    pairs = sum(counts[i] * counts[j] for i in range(len(counts))
                for j in range(i + 1, len(counts)))
    return min(1.0, domain_area / box) * (1.0 + sum(counts) + pairs)


def cut_blocks(domain, joint_sets, min_size: float | None = None, seed: int = 0,
               max_blocks: int | None = None, openings=()) -> list:
    """Cut a domain polygon into blocks along joint sets.

    Parameters
    ----------
    domain : (n, 2) array-like
        A simple polygon (any orientation), in metres.
    joint_sets : list of JointSet (or one)
    openings : list of (m, 2) array-likes, optional
        Excavations (a tunnel's or a cavern's outline, a circle as a polygon of many
        corners): simple polygons taken out of the domain before it is cut, so that the
        blocks around an opening end on its outline and the slivers it leaves are dropped
        with the others. An opening may reach across the domain's boundary (a cutting, a
        portal). Every block must still be simple: an opening that no joint trace reaches
        lies inside one block, which would enclose it, and is refused.
    min_size : float, optional
        Blocks thinner than this (2 area / perimeter, half the side of a square) are dropped
        as slivers; by default a tenth of the smallest spacing. Slivers over 1% of the
        domain's area in all (:data:`SLIVER_AREA_WARNING`) are reported by a
        :class:`~dda.PlausibilityWarning`.
    seed : int
        Seed of the random phases of non-persistent traces.
    max_blocks : int, optional
        Refuse at once, before cutting, when :func:`estimated_blocks` says the cut would
        make more blocks than this (default :data:`dda.scene.MAX_BLOCKS`): a mistyped
        spacing must not run for hours.

    Returns
    -------
    list of lists of (x, y)
        Counter-clockwise corners of each block, without collinear corners (a corner where a
        neighbour's joint ends stays when it bends the outline), ready for
        :meth:`dda.Scene.add_block`; sorted bottom to top, then left to right.
    """
    try:
        import shapely
    except ImportError:
        raise ImportError("cut_blocks needs shapely: pip install 'dda[cut]'") from None
    from shapely.geometry import LineString, Polygon
    from shapely.geometry.polygon import orient
    from shapely.ops import polygonize

    if isinstance(domain, Polygon) and len(domain.interiors):
        # a shapely polygon with holes: its holes are the openings
        openings = [np.asarray(ring.coords) for ring in domain.interiors] + list(openings)
        domain = np.asarray(domain.exterior.coords)
    elif isinstance(domain, Polygon):
        domain = np.asarray(domain.exterior.coords)
    try:
        dom = Polygon(np.asarray(domain, dtype=float))
    except (ValueError, TypeError) as exc:
        raise ValueError(f"cut_blocks: domain must be (n, 2) corners, n >= 3 ({exc}); an "
                         "opening in it goes to openings=") from None
    if not np.all(np.isfinite(np.asarray(dom.exterior.coords))):
        raise ValueError("cut_blocks: the domain's corners must be finite")
    if not dom.is_valid or dom.area <= 0.0:
        raise ValueError("cut_blocks: the domain must be a simple polygon with an area")
    holes = []
    for i, opening in enumerate(openings):
        try:
            hole = Polygon(np.asarray(opening, dtype=float))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"cut_blocks: openings[{i}] must be (n, 2) corners, n >= 3 "
                             f"({exc})") from None
        if (not np.all(np.isfinite(np.asarray(hole.exterior.coords))) or not hole.is_valid
                or hole.area <= 0.0):
            raise ValueError(f"cut_blocks: openings[{i}] must be a simple polygon with an "
                             "area and finite corners")
        if not hole.intersects(dom):
            raise ValueError(f"cut_blocks: openings[{i}] lies outside the domain")
        holes.append(hole)
    if holes:
        dom = dom.difference(shapely.union_all(holes))
        if dom.is_empty or dom.area <= 0.0:
            raise ValueError("cut_blocks: the openings take the whole domain")
    sets = [joint_sets] if isinstance(joint_sets, JointSet) else list(joint_sets)
    for i, js in enumerate(sets):
        if not isinstance(js, JointSet):
            raise TypeError(f"cut_blocks: joint_sets[{i}] must be a JointSet, got {js!r}")
    if min_size is None:
        min_size = 0.1 * min((js.spacing for js in sets), default=0.0)
    min_size = finite_number("min_size", min_size, nonnegative=True, where="cut_blocks")
    if max_blocks is None:
        from dda.scene import MAX_BLOCKS

        max_blocks = MAX_BLOCKS
    estimate = estimated_blocks(dom.bounds, dom.area, sets)
    if estimate > max_blocks:
        raise ValueError(
            f"cut_blocks: these joint sets would cut the domain into about {estimate:,.0f} "
            f"blocks, more than the limit of {max_blocks:,} (max_blocks; a scene's "
            "max_blocks); check the spacings (m) against the domain's size")

    rng = np.random.default_rng(seed)
    lines = [dom.boundary]
    for js in sets:
        for seg in js.traces(dom.bounds, rng):
            piece = LineString(seg).intersection(dom)
            if not piece.is_empty:
                lines.append(piece)
    # node the traces on a decimal grid far below any block: traces computed with sin and
    # cos (a vertical set's direction is (6e-17, -1)) would leave corners 1e-17 m apart, and
    # snapping after noding (set_precision of the union) left a trace 4e-16 m inside the
    # boundary overlapping it unnoded, and polygonize dropped the faces beside it (a 1 m
    # square cut by a vertical set 1 m apart gave no block at all)
    extent = max(dom.bounds[2] - dom.bounds[0], dom.bounds[3] - dom.bounds[1])
    grid = 10.0 ** (math.floor(math.log10(extent)) - 9)
    faces = polygonize(shapely.union_all(lines, grid_size=grid))
    blocks = []
    dropped, dropped_area = 0, 0.0
    for face in shapely.get_parts(faces) if hasattr(faces, "geoms") else faces:
        if face.area <= 0.0 or not dom.contains(face.representative_point()):
            continue
        if len(face.interiors):
            inside = [i for i, hole in enumerate(holes)
                      if any(Polygon(ring).contains(hole.representative_point())
                             for ring in face.interiors)]
            if inside:
                raise ValueError(
                    f"cut_blocks: openings[{inside[0]}] lies inside one block (no joint "
                    "trace reaches it), which would enclose it; a DDA block is a simple "
                    "polygon: a denser or more persistent set, or a trace through the "
                    "opening, cuts it")
            raise ValueError(
                "cut_blocks: a block would enclose another (a closed loop of traces that "
                "meets no other joint); change the trace length or the seed")
        face = orient(face.simplify(0.0), sign=1.0)
        if 2.0 * face.area / face.length < min_size:
            dropped, dropped_area = dropped + 1, dropped_area + face.area
            continue
        blocks.append([(float(x), float(y)) for x, y in face.exterior.coords[:-1]])
    blocks.sort(key=lambda b: (round(min(p[1] for p in b), 9), round(min(p[0] for p in b), 9)))
    if dropped_area > SLIVER_AREA_WARNING * dom.area:
        from dda.plausibility import PlausibilityWarning

        warnings.warn(f"cut_blocks: {dropped} slivers thinner than min_size = {min_size:g} m "
                      f"were dropped, {100 * dropped_area / dom.area:.2g}% of the domain's "
                      f"area ({len(blocks)} blocks kept): a smaller min_size keeps them",
                      PlausibilityWarning, stacklevel=2)
    return blocks
