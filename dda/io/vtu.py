"""A VTU/PVD series writer (meshio): one .vtu per recorded step and a .pvd that indexes them.

Field names carry their unit in brackets (``"displacement [m]"``; :data:`UNITS`). Each .vtu
holds
- the blocks as polygon cells, with cell data ``block_id`` (the block's index, int),
  ``shaken`` (1 on a shaken block, else 0), ``displacement [m]`` (centroid),
  ``velocity [m/s]`` (centroid), ``rotation [rad]`` and ``stress [Pa]`` ([sx, sy, txy]), and
  point data ``displacement [m]`` and ``velocity [m/s]`` at the vertices;
- the closed contacts as vertex cells at the contact points, with cell data
  ``normal_force [N/m]`` (compression positive), ``shear_force [N/m]``,
  ``normal_force_vector [N/m]`` and ``shear_force_vector [N/m]`` (3 components, the forces
  on the vertex's block, for ParaView's Glyph filter or pyvista's ``glyph``),
  ``contact_state`` (1 stick, 2 slip), ``vertex_block`` and ``edge_block`` (the indices of
  the contact's two blocks);
- the block names, in index order, as field data ``block_names``: their UTF-8 bytes, each
  name ended by a zero byte (meshio reads and writes no text arrays; :func:`block_names`
  turns the array back into names).
Block fields are NaN on contact cells and contact fields NaN on block cells (the integer
ones -1); ``kind`` is 0 on blocks and 1 on contacts, so a Threshold filter in ParaView
separates them. The fields that were written before they carried units are written under
their old names too (``displacement``, ``velocity``, ``rotation``, ``stress``,
``normal_force``, ``shear_force``), for the scripts that read them, unless
``VTUWriter(..., plain_names=False)``.
Files are written to a temporary name and renamed, so a reader never sees half a file. The
.pvd index gains each frame's entry as soon as its file is in place (its closing tags
rewritten in one write; the whole index rewritten, atomically, when it does not end as this
writer left it and when the run ends), so the folder of a killed run opens with every frame
but at most the last one. A writer's first file removes the files of its prefix's series
numbered from its own on, and half-written ones: a run into the folder of an earlier run
with the same prefix leaves one series there, not two mixed.
"""

from __future__ import annotations

import base64
import glob
import os
import re
import zlib
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from dda.result import Frame

__all__ = ["UNITS", "VTUWriter", "block_names", "field_name", "frame_to_mesh"]

#: the unit of each field of the files, written in its name: ``"displacement [m]"``
UNITS = {"displacement": "m", "velocity": "m/s", "rotation": "rad", "stress": "Pa",
         "normal_force": "N/m", "shear_force": "N/m", "normal_force_vector": "N/m",
         "shear_force_vector": "N/m"}

#: the fields also written under their names of before they carried units
PLAIN_NAMES = ("displacement", "velocity", "rotation", "stress", "normal_force", "shear_force")


def field_name(name: str) -> str:
    """The name a field has in the files: with its unit when it has one.

    Examples
    --------
    >>> field_name("displacement"), field_name("kind")
    ('displacement [m]', 'kind')
    """
    unit = UNITS.get(name)
    return name if unit is None else f"{name} [{unit}]"


def block_names(field_data) -> list[str]:
    """The block names of a file's field data (meshio's ``mesh.field_data`` or pyvista's
    ``mesh.field_data``), in block index order; empty when the file has none.

    Examples
    --------
    >>> block_names({"block_names": np.frombuffer(b"base\\0top\\0", dtype=np.uint8)})
    ['base', 'top']
    """
    if "block_names" not in field_data:
        return []
    raw = np.asarray(field_data["block_names"], dtype=np.uint8).tobytes()
    return raw.decode("utf-8").split("\0")[:-1]



def _pad3(a: np.ndarray) -> np.ndarray:
    return np.concatenate([a, np.zeros((len(a), 1))], axis=1)


class VTUWriter:
    """Write a run as ``PREFIX_00000.vtu, ...`` and ``PREFIX.pvd``.

    Parameters
    ----------
    prefix : str or Path
        Path prefix of the files, for example ``"out/case"``; folders are created.
    every : int
        Write every this many recorded steps.
    interval : float, optional
        Write a frame once the simulated time has moved on by at least this much (s) since
        the last frame written, whatever the steps in between: evenly spaced frames where
        dt changes (cut steps, ``dt="auto"``). With it, ``every`` must be 1. The first frame
        and the run's last are written either way.
    plain_names : bool
        Also write the fields that carry a unit in their name (``"displacement [m]"``) under
        their old plain names (``"displacement"``), for scripts written before.

    Examples
    --------
    >>> import tempfile, os
    >>> w = VTUWriter(os.path.join(tempfile.mkdtemp(), "case"))
    >>> w.pvd_path.name
    'case.pvd'
    """

    #: (class defaults: the writers of checkpoints saved before they were options)
    plain_names = True
    interval = None

    def __init__(self, prefix, every: int = 1, plain_names: bool = True,
                 interval: float | None = None):
        self.prefix = Path(prefix)
        if (isinstance(every, bool) or not isinstance(every, (int, np.integer))
                or int(every) < 1):
            raise ValueError(f"VTUWriter: every must be a whole number of recorded steps, at "
                             f"least 1, got {every!r}")
        self.every = int(every)
        if interval is not None:
            interval = float(interval)
            if not (np.isfinite(interval) and interval > 0.0):
                raise ValueError(f"VTUWriter: interval must be a positive time in s, got "
                                 f"{interval!r}")
            if self.every != 1:
                raise ValueError("VTUWriter: give every or interval, not both")
        self.interval = interval
        self.plain_names = bool(plain_names)
        self.prefix.parent.mkdir(parents=True, exist_ok=True)
        self._entries: list[tuple[float, str]] = []
        self._n = 0  # entries that count: _entries[:_n]
        self._seen = 0
        #: time of the last frame given to :meth:`write` (written or skipped by ``every``)
        self.last_time: float | None = None

    @property
    def pvd_path(self) -> Path:
        return self.prefix.with_name(self.prefix.name + ".pvd")

    @property
    def files(self) -> list[Path]:
        """The .vtu files written so far."""
        return [self.prefix.parent / name for _, name in self._entries[:self._n]]

    def write(self, frame: Frame, last: bool = False) -> None:
        """Write one frame (called by the simulation at every recorded step); every
        ``every``-th is written (or, with ``interval``, the first frame at least that long
        after the last written), and the ``last`` of a run whatever the count, so a series
        always ends at the run's end.

        The file is written under a temporary name and renamed, and the writer's count is
        updated only after that, in one statement: a run interrupted anywhere in here leaves
        either no new file and the old count, or the new file and the new count
        (``last_time`` tells a resumed run which frame the writer has).
        """
        n = self._n
        # a run's stop writes its last frame, which skip() counted when it came: not a new
        # frame (counted again, or taken as the next one due, every frame after a resume
        # came one step late)
        again = (last and frame.time == self.last_time
                 and not (n and self._entries[n - 1][0] == frame.time))
        due = not again and self.due(frame.time)
        if due or last:
            # (an interval runs from the frames it was due at, not from a run's ends)
            self._write_file(frame, self._seen + (not again),
                             frame.time if due else self.__dict__.get("anchor_time"))
            return
        self.skip(frame.time)

    def write_extra(self, frame: Frame) -> None:
        """Write a frame beside the series' thinning (a run's end or stop between recorded
        steps, the start of a run that goes on from one): the frames after it are those of
        a run never stopped."""
        anchor = self.__dict__.get("anchor_time")
        if anchor is None and self._n:  # (a writer from an earlier version's checkpoint)
            anchor = self._entries[self._n - 1][0]
        self._write_file(frame, self._seen, anchor)

    def _write_file(self, frame: Frame, seen: int, anchor: float | None) -> None:
        """The frame's file and its entry; then the counts, ``last_time`` and the interval's
        anchor in one statement (:meth:`write`'s docstring)."""
        n = self._n
        if "_cleared" not in self.__dict__:
            self._clear_stale(n)
        name = f"{self.prefix.name}_{n:05d}.vtu"
        path = self.prefix.parent / name
        # (not ending in .vtu: a file cut short by a kill must not join a *.vtu series)
        tmp = path.with_name(path.name + ".part")
        write_vtu(tmp, frame, plain_names=self.plain_names)
        os.replace(tmp, path)
        del self._entries[n:]  # an entry left by an interrupted write
        self._entries.append((frame.time, name))
        self._n, self._seen, self.last_time, self.anchor_time = n + 1, seen, frame.time, anchor
        self._index_last()

    def _clear_stale(self, n: int) -> None:
        """Remove this prefix's series files numbered ``n`` and up, and half-written ones:
        an earlier run's (or an interrupted run's beyond its checkpoint), which a
        ``PREFIX_*.vtu`` glob or ParaView's grouped file series would mix into this one (a
        0.1 s run into the folder of a 0.4 s one left 150 of its frames there). Once per
        writer and process, at its first file."""
        self._cleared = True
        pattern = re.compile(re.escape(self.prefix.name) + r"_(\d{5,})\.vtu(\.part|\.tmp\.vtu)?")
        for path in self.prefix.parent.glob(f"{glob.escape(self.prefix.name)}_*"):
            match = pattern.fullmatch(path.name)
            if match and (match.group(2) or int(match.group(1)) >= n):
                path.unlink(missing_ok=True)

    def due(self, time: float) -> bool:
        """Whether :meth:`write` would write a file for a frame at ``time`` (s) given now
        (the run's ``last`` frame always is). A recorder asks before it builds the frame: a
        thinned series costs no frame for the steps it skips."""
        if self.interval is not None:
            return time >= self.due_after()
        return self.frames_to_due() == 0

    def due_after(self) -> float:
        """With ``interval``: the time from which a frame is :meth:`due` (-inf before the
        first is written)."""
        n = self._n
        anchor = self.__dict__.get("anchor_time")  # (none in an earlier version's checkpoint)
        if anchor is None:
            anchor = -np.inf if n == 0 else self._entries[n - 1][0]
        # (a relative slack: frame times are sums of steps, 0.05 may come as 0.0499999...)
        return anchor + self.interval * (1 - 1e-9)

    def frames_to_due(self) -> int:
        """With ``every``: the frames given to :meth:`write` or :meth:`skip` before the next
        one that is :meth:`due` (0: the next is)."""
        return (-self._seen) % self.every

    def skip(self, time: float) -> None:
        """Count a frame at ``time`` that is not :meth:`due`, as :meth:`write` would."""
        self._seen, self.last_time = self._seen + 1, time

    def close(self) -> None:
        """Write the .pvd index of every file written."""
        self._write_pvd()

    def __getstate__(self):
        state = self.__dict__.copy()
        state.pop("_pvd_end", None)  # where this process left the index: not for a resume
        state.pop("_cleared", None)  # a resumed run clears what lies beyond its checkpoint
        return state

    def _index_last(self):
        """Add the last entry to the .pvd index in place: its line and the closing tags
        written over the old closing tags, in one write (a whole rewrite, atomic, when the
        index is not the one this writer left)."""
        end = self.__dict__.get("_pvd_end")  # (entries, offset of the closing tags)
        path = self.pvd_path
        if end is None or end[0] != self._n - 1 or not path.is_file() or (
                path.stat().st_size != end[1] + len(_CLOSING)):
            self._write_pvd()
            return
        line = _dataset(*self._entries[self._n - 1]).encode()
        with open(path, "r+b") as f:
            f.seek(end[1])
            f.write(line + _CLOSING)
        self._pvd_end = (self._n, end[1] + len(line))

    def _write_pvd(self):
        head = ('<?xml version="1.0"?>\n'
                '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                "  <Collection>\n")
        body = "".join(_dataset(t, name) for t, name in self._entries[:self._n])
        data = (head + body).encode()
        tmp = self.pvd_path.with_name(self.pvd_path.name + ".tmp")
        tmp.write_bytes(data + _CLOSING)
        os.replace(tmp, self.pvd_path)
        self._pvd_end = (self._n, len(data))


_CLOSING = b"  </Collection>\n</VTKFile>\n"


def _dataset(t: float, name: str) -> str:
    """One entry of the .pvd index."""
    return f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>\n'


def write_vtu(path, frame: Frame, plain_names: bool = True) -> None:
    """Write one frame as a .vtu file: :func:`frame_to_mesh` by meshio, then the block names
    as field data (which meshio's writer leaves out)."""
    meshio.write(path, frame_to_mesh(frame, plain_names), file_format="vtu")
    if frame.block_names:
        names = b"".join(n.encode("utf-8") + b"\0" for n in frame.block_names)
        _add_field_data(path, {"block_names": np.frombuffer(names, dtype=np.uint8)})


def _add_field_data(path, arrays: dict) -> None:
    """Put ``<FieldData>`` with these 1D byte arrays into a .vtu file meshio wrote (zlib
    compressed, as meshio writes the rest)."""
    path = Path(path)
    text = path.read_bytes()
    tag = b"<UnstructuredGrid>"
    at = text.index(tag) + len(tag)
    rows = "".join(
        f'\n<DataArray type="UInt8" Name={quoteattr(name)} '
        f'NumberOfTuples="{len(a)}" format="binary">\n{_zlib_base64(a.tobytes())}\n'
        "</DataArray>" for name, a in arrays.items())
    path.write_bytes(text[:at] + f"\n<FieldData>{rows}\n</FieldData>".encode() + text[at:])


def _zlib_base64(data: bytes) -> str:
    """VTK's zlib-compressed binary layout in one block: a UInt32 header (1 block, its size
    twice, its compressed size; in the machine's byte order, the file's) and the compressed
    bytes, each in base64."""
    packed = zlib.compress(data)
    header = np.array([1, len(data), len(data), len(packed)], dtype=np.uint32)
    return (base64.b64encode(header.tobytes()) + base64.b64encode(packed)).decode()


def frame_to_mesh(frame: Frame, plain_names: bool = True) -> meshio.Mesh:
    """The meshio mesh of one frame (block cells grouped by vertex count, then contacts).

    Parameters
    ----------
    frame : dda.result.Frame
    plain_names : bool
        Also put the fields that have a unit under their plain names (``"displacement"`` as
        well as ``"displacement [m]"``).
    """
    counts = np.diff(frame.offsets)
    sizes = np.unique(counts)
    groups = [np.flatnonzero(counts == k) for k in sizes]
    n_vertices, n_contacts = len(frame.vertices), len(frame.contact_point)
    points = _pad3(np.concatenate([frame.vertices, frame.contact_point]))
    point_data = {
        "displacement": _pad3(np.concatenate([frame.vertex_displacement,
                                              np.zeros((n_contacts, 2))])),
        "velocity": _pad3(np.concatenate([frame.vertex_velocity, np.zeros((n_contacts, 2))])),
    }
    cells = [("polygon", frame.offsets[g][:, None] + np.arange(k))
             for k, g in zip(sizes, groups, strict=True)]
    if n_contacts:
        cells.append(("vertex", (n_vertices + np.arange(n_contacts))[:, None]))
    order = np.concatenate(groups) if groups else np.zeros(0, dtype=np.int64)
    rows = {k: np.concatenate([b, c]) for (k, b), c in zip(
        _block_rows(frame, order).items(), _contact_rows(frame).values(), strict=True)}
    # one array per cell block
    cuts = np.cumsum([len(g) for g in groups] + ([n_contacts] if n_contacts else []))[:-1]
    cell_data = {field_name(k): np.split(v, cuts) for k, v in rows.items()}
    point_data = {field_name(k): v for k, v in point_data.items()}
    if plain_names:
        cell_data.update({k: list(cell_data[field_name(k)]) for k in PLAIN_NAMES})
        point_data.update({k: point_data[field_name(k)] for k in PLAIN_NAMES
                           if field_name(k) in point_data})
    return _with_bolts(meshio.Mesh(points, cells, point_data=point_data,
                                   cell_data=cell_data), frame)


def _block_rows(frame: Frame, order: np.ndarray) -> dict:
    """The cell data of the block cells (blocks in the order ``order``), by plain name."""
    nb = len(order)
    nan, none = np.full(nb, np.nan), np.full(nb, -1, dtype=np.int64)
    return {
        "kind": np.zeros(nb),
        "block_id": order.astype(np.int64),
        "shaken": np.isin(order, frame.shaken).astype(np.uint8),
        "displacement": _pad3(frame.displacement[order]),
        "velocity": _pad3(frame.velocity[order, :2]),
        "rotation": frame.rotation[order].astype(float),
        "stress": frame.stress[order].astype(float),
        "normal_force": nan, "shear_force": nan,
        "normal_force_vector": np.full((nb, 3), np.nan),
        "shear_force_vector": np.full((nb, 3), np.nan),
        "contact_state": nan, "vertex_block": none, "edge_block": none,
    }


def _contact_rows(frame: Frame) -> dict:
    """The cell data of the contact cells, by plain name (the keys of :func:`_block_rows`).

    The vectors are the forces on the contact's vertex's block: the normal force along the
    edge's normal (out of the edge's block), the shear force along the edge's tangent
    ``tau``, the normal turned clockwise by 90 degrees: ``-shear_force * tau``.
    """
    nc = len(frame.contact_point)
    nan = np.full(nc, np.nan)
    n = np.asarray(frame.contact_normal, dtype=float).reshape(nc, 2)
    tau = np.stack([n[:, 1], -n[:, 0]], axis=1)
    fn = np.asarray(frame.normal_force, dtype=float)
    fs = np.asarray(frame.shear_force, dtype=float)
    blocks = np.asarray(frame.contact_blocks, dtype=np.int64).reshape(nc, 2)
    return {
        "kind": np.ones(nc),
        "block_id": np.full(nc, -1, dtype=np.int64),
        "shaken": np.zeros(nc, dtype=np.uint8),
        "displacement": np.full((nc, 3), np.nan),
        "velocity": np.full((nc, 3), np.nan),
        "rotation": nan,
        "stress": np.full((nc, 3), np.nan),
        "normal_force": fn, "shear_force": fs,
        "normal_force_vector": _pad3(fn[:, None] * n),
        "shear_force_vector": _pad3(-fs[:, None] * tau),
        "contact_state": frame.contact_state.astype(float),
        "vertex_block": blocks[:, 0], "edge_block": blocks[:, 1],
    }


def _with_bolts(mesh: meshio.Mesh, frame: Frame) -> meshio.Mesh:
    """``mesh`` with the frame's bolts (:mod:`dda.bolts`) as line cells after its other
    cells, from end a to end b; ``mesh`` itself in a scene without bolts.

    The bolt cells have ``kind`` 2 and cell data ``bolt_force [N/m]`` (the axial force,
    tension positive; 0 once broken), ``bolt_state`` (0 intact, 1 broken) and ``bolt_id``
    (the bolt's index, ``Scene.add_bolt``'s return); those are NaN (float) or -1 (integers)
    on the other cells, and the other cells' fields NaN or -1 on the bolts. The bolts' ends
    are points of their own, with zero point data.
    """
    ends = frame.bolt_points
    if ends is None or not len(ends):
        return mesh
    nb = len(ends)
    first = len(mesh.points)
    points = np.concatenate([mesh.points, _pad3(np.asarray(ends, dtype=float).reshape(-1, 2))])
    point_data = {k: np.concatenate([v, np.zeros((2 * nb, *np.shape(v)[1:]), np.asarray(v).dtype)])
                  for k, v in mesh.point_data.items()}
    cells = [(c.type, c.data) for c in mesh.cells]
    sizes = [len(c.data) for c in mesh.cells]
    cells.append(("line", first + np.arange(2 * nb).reshape(nb, 2)))

    def filled(like, n):
        like = np.asarray(like)
        fill = np.nan if like.dtype.kind == "f" else (-1 if like.dtype.kind == "i" else 0)
        return np.full((n, *like.shape[1:]), fill, dtype=like.dtype)

    cell_data = {k: [*v, filled(v[0], nb)] for k, v in mesh.cell_data.items()}
    if "kind" in cell_data:
        cell_data["kind"][-1] = np.full(nb, 2, dtype=cell_data["kind"][-1].dtype)
    broken = np.asarray(frame.bolt_broken, dtype=bool)
    for name, values in (("bolt_force [N/m]", np.asarray(frame.bolt_force, dtype=float)),
                         ("bolt_state", broken.astype(np.int64)),
                         ("bolt_id", np.arange(nb, dtype=np.int64))):
        cell_data[name] = [filled(values, n) for n in sizes] + [values]
    return meshio.Mesh(points, cells, point_data=point_data, cell_data=cell_data)
