"""A VTU/PVD series writer (meshio): one .vtu per recorded step and a .pvd that indexes them.

Each .vtu holds
- the blocks as polygon cells, with cell data ``block_id``, ``displacement`` (centroid, m),
  ``velocity`` (centroid, m/s), ``rotation`` (rad) and ``stress`` ([sx, sy, txy], Pa), and point
  data ``displacement`` and ``velocity`` at the vertices;
- the closed contacts as vertex cells at the contact points, with cell data ``normal_force``
  (compression positive, N/m), ``shear_force`` (N/m) and ``contact_state`` (1 stick, 2 slip).
Block fields are NaN on contact cells and contact fields NaN on block cells; ``kind`` is 0 on
blocks and 1 on contacts, so a Threshold filter in ParaView separates them.
Files are written to a temporary name and renamed, so a reader never sees half a file. The
.pvd index gains each frame's entry as soon as its file is in place (its closing tags
rewritten in one write; the whole index rewritten, atomically, when it does not end as this
writer left it and when the run ends), so the folder of a killed run opens with every frame
but at most the last one.
"""

from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from dda.result import Frame

__all__ = ["VTUWriter"]


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

    Examples
    --------
    >>> import tempfile, os
    >>> w = VTUWriter(os.path.join(tempfile.mkdtemp(), "case"))
    >>> w.pvd_path.name
    'case.pvd'
    """

    def __init__(self, prefix, every: int = 1):
        self.prefix = Path(prefix)
        if int(every) < 1:
            raise ValueError("VTUWriter: every must be at least 1")
        self.every = int(every)
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

    def write(self, frame: Frame) -> None:
        """Write one frame (called by the simulation at every recorded step).

        The file is written under a temporary name and renamed, and the writer's count is
        updated only after that, in one statement: a run interrupted anywhere in here leaves
        either no new file and the old count, or the new file and the new count
        (``last_time`` tells a resumed run which frame the writer has).
        """
        n = self._n
        if self._seen % self.every == 0:
            name = f"{self.prefix.name}_{n:05d}.vtu"
            path = self.prefix.parent / name
            tmp = path.with_name(path.name + ".tmp.vtu")
            meshio.write(tmp, frame_to_mesh(frame), file_format="vtu")
            os.replace(tmp, path)
            del self._entries[n:]  # an entry left by an interrupted write
            self._entries.append((frame.time, name))
            n += 1
            self._n, self._seen, self.last_time = n, self._seen + 1, frame.time
            self._index_last()
            return
        self._n, self._seen, self.last_time = n, self._seen + 1, frame.time

    def close(self) -> None:
        """Write the .pvd index of every file written."""
        self._write_pvd()

    def __getstate__(self):
        state = self.__dict__.copy()
        state.pop("_pvd_end", None)  # where this process left the index: not for a resume
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


def frame_to_mesh(frame: Frame) -> meshio.Mesh:
    """The meshio mesh of one frame (block cells grouped by vertex count, then contacts)."""
    offsets = frame.offsets
    counts = np.diff(offsets)
    n_vertices = len(frame.vertices)
    n_contacts = len(frame.contact_point)
    points = _pad3(np.concatenate([frame.vertices, frame.contact_point]))
    point_data = {
        "displacement": _pad3(np.concatenate([frame.vertex_displacement,
                                              np.zeros((n_contacts, 2))])),
        "velocity": _pad3(np.concatenate([frame.vertex_velocity, np.zeros((n_contacts, 2))])),
    }
    cells = []
    data = {k: [] for k in ("kind", "block_id", "displacement", "velocity", "rotation", "stress",
                            "normal_force", "shear_force", "contact_state")}
    for nv in np.unique(counts):
        blocks = np.flatnonzero(counts == nv)
        conn = offsets[blocks][:, None] + np.arange(nv)
        cells.append(("polygon", conn))
        nb = len(blocks)
        nan = np.full(nb, np.nan)
        data["kind"].append(np.zeros(nb))
        data["block_id"].append(blocks.astype(float))
        data["displacement"].append(_pad3(frame.displacement[blocks]))
        data["velocity"].append(_pad3(frame.velocity[blocks, :2]))
        data["rotation"].append(frame.rotation[blocks])
        data["stress"].append(frame.stress[blocks])
        data["normal_force"].append(nan)
        data["shear_force"].append(nan)
        data["contact_state"].append(nan)
    if n_contacts:
        cells.append(("vertex", (n_vertices + np.arange(n_contacts))[:, None]))
        nan = np.full(n_contacts, np.nan)
        data["kind"].append(np.ones(n_contacts))
        data["block_id"].append(np.full(n_contacts, -1.0))
        data["displacement"].append(np.full((n_contacts, 3), np.nan))
        data["velocity"].append(np.full((n_contacts, 3), np.nan))
        data["rotation"].append(nan)
        data["stress"].append(np.full((n_contacts, 3), np.nan))
        data["normal_force"].append(frame.normal_force.astype(float))
        data["shear_force"].append(frame.shear_force.astype(float))
        data["contact_state"].append(frame.contact_state.astype(float))
    return _with_bolts(meshio.Mesh(points, cells, point_data=point_data, cell_data=data), frame)


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
