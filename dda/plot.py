"""Pictures of a run: history plots of a Result (matplotlib) and frames and animations of a
VTU/PVD series (pyvista, off screen).

>>> import dda.plot  # needs matplotlib; the frame functions need pyvista
"""

from __future__ import annotations

import os
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

__all__ = ["history", "read_pvd", "render_frame", "animate", "animate_to"]


def _reference_block(result, relative_to):
    """The block displacements are measured from: ``"auto"`` takes the first shaken block
    (a shaking table: what matters is how far the blocks move on it), else none."""
    scene = result.scene
    if relative_to == "auto":
        shaken = [s.block for s in scene.shakes]
        return scene.blocks[shaken[0]] if shaken else None
    return None if relative_to is None else scene.block(relative_to)


def history(result, blocks=None, path=None, title=None, relative_to="auto"):
    """Plot a run's histories: block displacement, joint forces and contact states over time.

    Parameters
    ----------
    result : dda.Result
    blocks : list of Block (or names), optional
        The blocks to plot (default: every block that moved, up to 8).
    path : str or Path, optional
        Write the figure there (PNG, PDF, SVG by suffix) and close it.
    title : str, optional
    relative_to : Block, name, index, None or "auto"
        Plot displacements relative to this block's. The default, ``"auto"``, takes the first
        shaken block when the scene has one (so a stack on a shaking table shows how far it
        slides on the table, not the table's own travel), else plots them from the start.

    Returns
    -------
    matplotlib.figure.Figure
        Three panels: |centroid displacement| of each block, the normal and shear force of
        the joints those blocks carry, and the number of contacts open (tracked), sticking
        and slipping at each step.
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    scene = result.scene
    ref = _reference_block(result, relative_to)
    origin = result.displacement(ref) if ref is not None else 0.0

    def moved(b):
        return result.displacement(b) - origin

    if blocks is None:
        blocks = [b for b in scene.blocks
                  if b != ref and np.abs(moved(b)).max(initial=0.0) > 0.0][:8]
    blocks = [scene.block(b) for b in blocks]
    t = result.time
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for b in blocks:
        u = moved(b)
        axes[0].plot(t, 1e3 * np.hypot(u[:, 0], u[:, 1]), label=b.name)
    axes[0].set_ylabel("displacement (mm)" if ref is None else
                       f"displacement relative\nto {ref.name} (mm)")
    if blocks:
        axes[0].legend(fontsize="small", ncol=2)
    plotted = 0
    shown = {b.index for b in blocks}
    for a, c in result.joint_pairs():
        if plotted >= 6 or not ({a.index, c.index} & shown):
            continue
        f = result.joint_force(a, c)
        name = f"{a.name}/{c.name}"
        line = axes[1].plot(t, 1e-3 * f[:, 0], label=f"{name} normal")[0]
        axes[1].plot(t, 1e-3 * f[:, 1], "--", color=line.get_color(), label=f"{name} shear")
        plotted += 1
    axes[1].set_ylabel("joint force (kN/m)")
    if plotted:
        axes[1].legend(fontsize="small", ncol=2)
    st = result.stats
    if len(st):
        axes[2].step(st.time, st.closed - st.sliding, where="post", label="stick")
        axes[2].step(st.time, st.sliding, where="post", label="slip")
        axes[2].step(st.time, st.contacts - st.closed, where="post", label="open (tracked)")
        axes[2].legend(fontsize="small")
    axes[2].set_ylabel("contacts")
    axes[2].yaxis.get_major_locator().set_params(integer=True)  # counts: whole ticks
    axes[2].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=100)
        plt.close(fig)
    return fig


def read_pvd(path) -> list[tuple[float, Path]]:
    """The (time, VTU file) entries of a PVD collection, in time order.

    (pyvista's ``PVDReader`` reads the same XML the same way, in Python; this one needs no
    pyvista, so the series of a run can be listed, checked and resumed without it.)
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"no PVD file {path}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"{path} is not a PVD file ({exc})") from None
    entries = [(float(d.get("timestep", "0")), path.parent / d.get("file"))
               for d in root.iter("DataSet") if d.get("file")]
    if not entries:
        what = " (a .vtu is one frame: give the series' .pvd)" if path.suffix == ".vtu" else ""
        raise ValueError(f"{path} lists no data sets{what}")
    missing = [f for _, f in entries if not f.is_file()]
    if missing:
        raise ValueError(f"{path} lists {len(missing)} of its {len(entries)} files that are "
                         f"not there, the first {missing[0]} (a series moved without its "
                         "files, or deleted)")
    return sorted(entries, key=lambda e: e[0])


def _pyvista():
    try:
        import pyvista as pv
    except ImportError:
        raise ImportError("rendering needs pyvista: pip install 'dda[vis]'") from None
    pv.OFF_SCREEN = True
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        # headless: VTK's X window tries the display first and logs a warning in colour on
        # every render ("bad X server connection") before it renders off screen anyway
        from vtkmodules.vtkCommonCore import vtkLogger  # noqa: PLC0415

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    return pv


_RELATIVE_FIELDS = ("displacement", "velocity", "rotation")
_NOT_SHOWN = ("kind", "vtkOriginalCellIds", "block_id", "shaken", "vertex_block", "edge_block")
#: the units a colour bar may show a quantity in, for each unit of the files
_DISPLAY_UNITS = {"m": (("µm", 1e-6), ("mm", 1e-3), ("m", 1.0)),
                  "m/s": (("µm/s", 1e-6), ("mm/s", 1e-3), ("m/s", 1.0)),
                  "rad": (("µrad", 1e-6), ("mrad", 1e-3), ("rad", 1.0)),
                  "Pa": (("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("GPa", 1e9)),
                  "N/m": (("N/m", 1.0), ("kN/m", 1e3), ("MN/m", 1e6))}


def _split_unit(name: str) -> tuple[str, str | None]:
    """``"displacement [m]"`` -> ``("displacement", "m")``; a name without a unit -> (name,
    None)."""
    if name.endswith("]") and " [" in name:
        base, unit = name[:-1].rsplit(" [", 1)
        return base, unit
    return name, None


def _field_key(names, field: str, file) -> str:
    """The cell array that ``field`` names: itself, or the one that carries its unit
    (``"displacement"`` -> ``"displacement [m]"``, written by the files since they carry
    units; files of before have the plain name only)."""
    names = list(names)
    with_unit = [k for k in names if _split_unit(k)[0] == field and _split_unit(k)[1]]
    if field in names and (_split_unit(field)[1] or not with_unit):
        return field
    if with_unit:
        return with_unit[0]
    shown = sorted({_split_unit(k)[0] for k in names if k not in _NOT_SHOWN})
    raise ValueError(f"{file} has no block field {field!r} (there are: {', '.join(shown)})")


def _block_fields(mesh) -> list[str]:
    """The cell arrays of a file's block cells that hold a value on them: the contacts'
    arrays, written NaN on the block cells, are not block fields (``dda render --field``
    listed them among the block fields)."""
    out = []
    for k in mesh.cell_data.keys():
        values = np.asarray(mesh.cell_data[k])
        if values.dtype.kind not in "fc" or np.isfinite(values).any():
            out.append(k)
    return out


def _display_unit(unit: str | None, top: float) -> tuple[str | None, float]:
    """The unit to show values up to ``top`` (in ``unit``) in, and its size in ``unit``: the
    largest whose size ``top`` reaches (mm under a metre, MPa from 1e6 Pa, ...)."""
    choices = _DISPLAY_UNITS.get(unit)
    if not choices:
        return unit, 1.0
    fit = [c for c in choices if top >= c[1]]
    return fit[-1] if fit else choices[0]


def _blocks_of(pv, file):
    """The block cells of a VTU file and the block names the file carries (by block_id)."""
    from dda.io.vtu import block_names

    mesh = pv.read(str(file))
    names = block_names(mesh.field_data)
    if "kind" in mesh.cell_data:
        mesh = mesh.extract_cells(np.flatnonzero(np.asarray(mesh.cell_data["kind"]) == 0))
    return mesh, names


def _listing(ids, names) -> str:
    """``base (0), top (1), ...`` (the first 20 blocks)."""
    ids = sorted(int(i) for i in ids)
    label = [f"{names[i]} ({i})" if i < len(names) else str(i) for i in ids[:20]]
    more = f", ... ({len(ids) - 20} more)" if len(ids) > 20 else ""
    return ", ".join(label) + more


def _file_reference(mesh, names, relative_to, file="the file") -> int | None:
    """The ``block_id`` that ``relative_to`` names in a file's block cells, or None.

    Parameters
    ----------
    mesh : pyvista mesh of the block cells (cell data ``block_id``, optionally ``shaken``)
    names : list of str
        The file's block names by block_id (:func:`dda.io.vtu.block_names`; may be empty).
    relative_to : None, int, or str
        None: no reference block. An int: a block_id. A string: the block of that name when
        a block has it; else ``"auto"`` (the shaken block when the file marks one, else
        none), ``"none"`` (no reference block), or an integer (a block_id, so a block
        named ``"3"`` is found by its name and ``"3"`` is block_id 3 only when no block
        has that name).
    file : str or Path
        The file's name, for the messages.

    Raises
    ------
    ValueError
        For a name or block_id the file does not have; the message lists its blocks.
    """
    if relative_to is None:
        return None
    ids = np.asarray(mesh.cell_data["block_id"]).astype(np.int64)
    if isinstance(relative_to, str):
        key = relative_to.strip()
        if key in names:
            return names.index(key)
        if key.lower() == "none":
            return None
        if key.lower() == "auto":
            shaken = np.asarray(mesh.cell_data["shaken"]) if "shaken" in mesh.cell_data else ()
            marked = ids[np.asarray(shaken) == 1] if len(shaken) else ids[:0]
            return int(marked.min()) if len(marked) else None
        try:
            relative_to = int(key)
        except ValueError:
            where = (f"the blocks are: {_listing(ids, names)}" if names else
                     "it carries no block names: give a block_id, one of "
                     f"{_listing(ids, names)}")
            raise ValueError(f"no block named {key!r} in {file}; {where}") from None
    if isinstance(relative_to, (bool, np.bool_)) or not isinstance(
            relative_to, (int, np.integer)):
        raise ValueError(f"relative_to: a block name, a block_id, 'auto' or None, not "
                         f"{relative_to!r}")
    if not np.any(ids == relative_to):
        raise ValueError(f"{file} has no block with block_id {relative_to} (the blocks are: "
                         f"{_listing(ids, names)})")
    return int(relative_to)


def _principal(v, sign):
    """A principal stress of [sx, sy, txy] rows: the mean plus (sign 1) or minus the radius
    of Mohr's circle."""
    return 0.5 * (v[:, 0] + v[:, 1]) + sign * _mohr_radius(v)


def _mohr_radius(v):
    """The largest in-plane shear stress of [sx, sy, txy] rows, sqrt(((sx - sy) / 2)^2 +
    txy^2)."""
    return np.hypot(0.5 * (v[:, 0] - v[:, 1]), v[:, 2])


#: the parts of a field a picture may show (``"stress:s1"``, ``"displacement:x"``); without
#: one, a vector's magnitude. Stresses tension positive, as the files hold them.
_PARTS = {
    "stress": {"sx": lambda v: v[:, 0], "sy": lambda v: v[:, 1], "txy": lambda v: v[:, 2],
               "mean": lambda v: 0.5 * (v[:, 0] + v[:, 1]),
               "s1": lambda v: _principal(v, 1.0), "s2": lambda v: _principal(v, -1.0),
               "tmax": _mohr_radius},
    "displacement": {"x": lambda v: v[:, 0], "y": lambda v: v[:, 1]},
    "velocity": {"x": lambda v: v[:, 0], "y": lambda v: v[:, 1]},
}


def _field_part(field: str) -> tuple[str, str | None]:
    """``"stress:s1"`` -> ``("stress", "s1")``; a field without a part -> (field, None)."""
    if ":" in field:
        name, part = field.rsplit(":", 1)
        return name.strip(), part.strip()
    return field, None


def _colour_mesh(pv, file, field, relative_to=None):
    """The block cells of ``file`` with cell data ``shown``, the magnitude of ``field`` (in
    the file's unit), or the part it names after a colon (:data:`_PARTS`: ``"stress:s1"``,
    ``"displacement:x"``), relative to the block ``relative_to`` names
    (:func:`_file_reference`), and what was shown: ``{"field": the array's name, "vector":
    whether a magnitude is shown, "part": the part or None, "reference": block_id or None,
    "reference_name": its name or None}``."""
    mesh, names = _blocks_of(pv, file)
    field, part = _field_part(field)
    key = _field_key(_block_fields(mesh), field, file)
    base = _split_unit(key)[0]
    if base not in _RELATIVE_FIELDS and relative_to is not None and not (
            isinstance(relative_to, str) and relative_to.strip().lower() in ("auto", "none")):
        raise ValueError(f"relative_to goes with {', '.join(_RELATIVE_FIELDS)}, not "
                         f"{field!r}")
    ref = _file_reference(mesh, names, relative_to, file) if base in _RELATIVE_FIELDS else None
    values = np.asarray(mesh.cell_data[key], dtype=float)
    vector = values.ndim == 2
    if ref is not None:
        ids = np.asarray(mesh.cell_data["block_id"])
        values = values - values[np.flatnonzero(ids == ref)[0]]
    if part is not None:
        parts = _PARTS.get(base, {})
        if part not in parts:
            have = (f"its parts: {', '.join(parts)}" if parts else "it has no parts")
            raise ValueError(f"{base!r} has no part {part!r} ({have})")
        mesh.cell_data["shown"] = parts[part](values)
        vector = False
    else:
        mesh.cell_data["shown"] = np.linalg.norm(values, axis=1) if vector else values
    name = names[ref] if ref is not None and ref < len(names) else None
    return mesh, {"field": key, "vector": vector, "part": part, "reference": ref,
                  "reference_name": name}


def _blocks_mesh(pv, file, field, relative_to=None):
    """The block cells of ``file`` with cell data ``shown`` (:func:`_colour_mesh`)."""
    return _colour_mesh(pv, file, field, relative_to)[0]


def _nice_length(span: float) -> float:
    """The largest 1, 2 or 5 times a power of ten that is at most ``span`` (a scale bar's
    length).

    Examples
    --------
    >>> _nice_length(0.37), _nice_length(3.0), _nice_length(0.0012)
    (0.2, 2.0, 0.001)
    """
    power = 10.0 ** np.floor(np.log10(span))
    return float(max(k * power for k in (1, 2, 5) if k * power <= span * (1 + 1e-12)))


def _length_label(length: float) -> str:
    return f"{length * 1e3:g} mm" if length < 0.1 else f"{length:g} m"


class _Frames:
    """Pictures of a series' frames that a report can use: the blocks (pyvista, off screen)
    coloured by one field on a fixed colour range, on axes in metres with a scale bar, a
    colour bar that names the quantity and its unit, and the time (matplotlib lays them out).

    The camera and the colour range cover every one of ``files``: a block that flies out
    and comes back in the middle of a series stays in the picture.
    """

    DPI = 100
    #: margins around the picture of the blocks, pixels: left, bottom, right, top
    MARGINS = (78, 52, 128, 34)

    def __init__(self, files, field, size, relative_to="auto"):
        self.pv = _pyvista()
        self.field = field
        self.relative_to = relative_to
        lo, hi, low, top = np.full(3, np.inf), np.full(3, -np.inf), np.inf, -np.inf
        for f in dict.fromkeys(files):  # each file once, read one at a time
            m, info = _colour_mesh(self.pv, f, field, relative_to)
            lo = np.minimum(lo, m.bounds[::2])
            hi = np.maximum(hi, m.bounds[1::2])
            low = min(low, float(np.nanmin(m.cell_data["shown"])))
            top = max(top, float(np.nanmax(m.cell_data["shown"])))
        base, unit = _split_unit(info["field"])
        # a signed quantity (a rotation, a stress component) on a diverging map centred on
        # 0: a range from 0 up drew every clockwise rotation as the fixed base's 0
        self.signed = low < 0.0
        peak = max(-low, top) if self.signed else top
        self.unit, self.scale = _display_unit(unit, peak)
        span = peak / self.scale if peak > 0 else 1.0
        self.clim = (-span, span) if self.signed else (0.0, span)
        self.cmap = "coolwarm" if self.signed else "viridis"
        self.size = tuple(int(s) for s in size)
        quantity = f"|{base}|" if info["vector"] else base
        if info.get("part"):
            quantity += f" {info['part']}"
        if info["reference"] is not None:
            name = info["reference_name"] or f"block {info['reference']}"
            quantity += f" relative to {name}"
        self.title = quantity + (f" [{self.unit}]" if self.unit else "")
        self._view(lo, hi)
        self._figure = None

    def _view(self, lo, hi):
        """The world window the blocks are drawn in: the frames' bounds with a margin, on
        the aspect of the picture's pixels."""
        left, bottom, right, top = self.MARGINS
        w, h = self.size
        self.pixels = (max(w - left - right, 16), max(h - bottom - top, 16))
        pw, ph = self.pixels
        span = np.maximum(hi[:2] - lo[:2], 1e-9) * 1.08
        width = max(span[0], span[1] * pw / ph)
        height = width * ph / pw
        centre = 0.5 * (lo[:2] + hi[:2])
        self.extent = (centre[0] - width / 2, centre[0] + width / 2,
                       centre[1] - height / 2, centre[1] + height / 2)

    def mesh(self, file):
        """The block cells of one file, ``shown`` in the colour bar's unit."""
        mesh = _blocks_mesh(self.pv, file, self.field, self.relative_to)
        mesh.cell_data["shown"] = mesh.cell_data["shown"] / self.scale
        return mesh

    def scene(self, file) -> np.ndarray:
        """The blocks alone, (height, width, 3) pixels covering :attr:`extent`."""
        pv = self.pv
        mesh = self.mesh(file)
        x0, x1, y0, y1 = self.extent
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        # drawn about the picture's centre: VTK renders in single precision, and at a site's
        # coordinates (y = 4e6 m) the outlines sat 5 cm off their faces
        mesh.points = mesh.points - np.array([cx, cy, 0.0])
        p = pv.Plotter(off_screen=True, window_size=self.pixels)
        p.set_background("white")
        # unlit, so that a block's colour is the colour bar's at its value (lit, the blocks
        # came out about 20% darker than the bar said)
        p.add_mesh(mesh, scalars="shown", clim=self.clim, cmap=self.cmap, show_scalar_bar=False,
                   lighting=False)
        # the polygons' own edges (show_edges would draw the triangles they render as),
        # lifted towards the camera: in the faces' plane they fought them for the depth test
        # and parts of outlines came out grey or missing
        edges = mesh.extract_all_edges()
        edges.points = edges.points + np.array([0.0, 0.0, 0.01])
        p.add_mesh(edges, color="black", line_width=1, lighting=False)
        p.camera_position = [(0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
        p.enable_parallel_projection()
        p.camera.parallel_scale = 0.5 * (y1 - y0)
        img = p.screenshot(return_img=True)
        p.close()
        return np.asarray(img)[..., :3]

    def image(self, file, time) -> np.ndarray:
        """One picture, (height, width, 3) pixels of ``size``."""
        scene = self.scene(file)
        if self._figure is None:
            self._figure = self._layout(scene)
        fig, picture, clock = self._figure
        picture.set_data(scene)
        clock.set_text(f"t = {time:.4g} s")
        fig.canvas.draw()
        return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()

    def _layout(self, scene):
        """The figure around the first picture of the blocks: axes, colour bar, scale bar
        (in the corner the blocks leave most free) and time."""
        from matplotlib import colors
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.cm import ScalarMappable
        from matplotlib.figure import Figure
        from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

        w, h = self.size
        left, bottom, right, top = self.MARGINS
        fig = Figure(figsize=(w / self.DPI, h / self.DPI), dpi=self.DPI)
        FigureCanvasAgg(fig)
        pw, ph = self.pixels
        ax = fig.add_axes((left / w, bottom / h, pw / w, ph / h))
        picture = ax.imshow(scene, extent=self.extent, origin="upper", aspect="auto",
                            interpolation="nearest")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.tick_params(labelsize=9)
        cax = fig.add_axes(((left + pw + 16) / w, bottom / h, 16 / w, ph / h))
        bar = fig.colorbar(ScalarMappable(colors.Normalize(*self.clim), self.cmap), cax=cax)
        bar.set_label(self.title, fontsize=10)
        bar.ax.tick_params(labelsize=9)
        x0, x1, y0, y1 = self.extent
        length = _nice_length(0.2 * (x1 - x0))
        ax.add_artist(AnchoredSizeBar(
            ax.transData, length, _length_label(length), loc=_free_corner(scene), pad=0.5,
            sep=4, borderpad=0.6, frameon=True, size_vertical=0.008 * (y1 - y0),
            color="black", fontproperties={"size": 10}))
        clock = ax.set_title("", fontsize=11, loc="left")
        return fig, picture, clock


def _free_corner(scene: np.ndarray) -> str:
    """The corner of a picture (matplotlib's location name) whose quarter holds the fewest
    non-white pixels."""
    h, w = scene.shape[:2]
    filled = (scene < 245).any(axis=2)
    quarters = {"upper left": filled[: h // 4, : w // 3], "upper right": filled[: h // 4,
                                                                                 -w // 3:],
                "lower left": filled[-h // 4:, : w // 3],
                "lower right": filled[-h // 4:, -w // 3:]}
    return min(quarters, key=lambda k: quarters[k].mean())


def render_frame(pvd, png, frame: int = -1, field: str = "displacement",
                 size=(1024, 768), relative_to="auto") -> Path:
    """Render one frame of a PVD series (default the last) to a PNG file of ``size`` pixels.

    The blocks are coloured by the magnitude of a cell field, on axes in metres, with a
    scale bar, a colour bar that names the quantity and its unit, and the time.

    Parameters
    ----------
    pvd : str or Path
        The series' .pvd file.
    png : str or Path
        The picture to write.
    frame : int
        Which frame (an index into the series; default the last).
    field : str
        ``"displacement"``, ``"velocity"``, ``"rotation"``, ``"stress"``, ...: a cell field
        of the blocks, by its name with or without its unit (``"displacement [m]"``); a
        vector's magnitude, or after a colon one part: ``"displacement:x"``, ``:y``; for
        stress (tension positive) ``"stress:sx"``, ``sy``, ``txy``, ``mean`` ((sx + sy) /
        2), ``s1`` and ``s2`` (the principal stresses, largest first) or ``tmax`` (the
        largest in-plane shear).
    size : (int, int)
        Width and height of the picture, pixels.
    relative_to : "auto", str, int or None
        Colour displacement, velocity or rotation relative to this block's (on a shaking
        table, how far each block has moved on the table): a block's name or its
        ``block_id`` (the block's index). The default, ``"auto"``, takes the shaken block
        when the files mark one (cell data ``shaken``); None (or ``"none"``) colours the
        fields as they are. A string is a block's name when a block has it, else an
        integer string is a block_id (see :func:`_file_reference`).

    Returns
    -------
    Path
        The PNG written.
    """
    from PIL import Image

    png = Path(png)
    if png.suffix.lower() not in Image.registered_extensions():
        raise ValueError(f"render_frame: {png} needs a picture's extension (.png, .jpg, ...)")
    entries = read_pvd(pvd)
    if not -len(entries) <= frame < len(entries):
        raise ValueError(f"frame {frame} is not in {pvd}: it has {len(entries)} frames "
                         f"(0 to {len(entries) - 1}, or -1 for the last)")
    time, file = entries[frame]
    frames = _Frames([file, file], field, size, relative_to)
    png.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(frames.image(file, time)).save(png)
    return png


def animate(pvd, out, field: str = "displacement", fps: float = 10.0, size=(800, 600),
            max_frames: int | None = None, relative_to="auto") -> Path:
    """Animate a PVD series to a GIF (Pillow) or an MP4 (H.264 through imageio-ffmpeg).

    ``max_frames`` keeps that many frames evenly spread over the series (the first and the
    last among them). An MP4's frame size is rounded up to whole 16-pixel blocks, as the
    codec needs. ``field`` and ``relative_to`` as in :func:`render_frame`; each frame is drawn
    as it draws one, on one camera and colour range that cover all the frames drawn. The
    frames go to the file as they are drawn (an MP4), or as 8-bit palette pictures (a GIF,
    a third of a full-colour frame's memory).
    """
    return animate_to([out], pvd, field=field, fps=fps, size=size, max_frames=max_frames,
                      relative_to=relative_to)[0]


def animate_to(outs, pvd, field: str = "displacement", fps: float = 10.0, size=(800, 600),
               max_frames: int | None = None, relative_to="auto") -> list[Path]:
    """:func:`animate` to several files (a GIF and an MP4) from one drawing of each frame."""
    outs = [Path(o) for o in outs]
    for out in outs:
        if out.suffix.lower() not in (".gif", ".mp4"):
            raise ValueError(f"animate: write a .gif or an .mp4, not "
                             f"{out.suffix or out.name!r}")
    if isinstance(fps, bool) or not (isinstance(fps, (int, float)) and 0.0 < fps <= 1000.0):
        raise ValueError(f"animate: fps must be a number of frames per second in (0, 1000], "
                         f"got {fps!r}")
    if max_frames is not None and (isinstance(max_frames, bool) or not isinstance(
            max_frames, (int, np.integer)) or max_frames < 1):
        raise ValueError(f"animate: max_frames must be a whole number >= 1, got "
                         f"{max_frames!r}")
    mp4 = any(o.suffix.lower() == ".mp4" for o in outs)
    if mp4:
        try:
            import imageio.v2 as iio
            import imageio_ffmpeg  # noqa: F401  (the ffmpeg binary the writer runs)
        except ImportError:
            raise ImportError("MP4 needs imageio and imageio-ffmpeg: pip install 'dda[vis]' "
                              "(or write a .gif)") from None
        size = tuple(16 * -(-int(s) // 16) for s in size)
    entries = read_pvd(pvd)
    if max_frames is not None and len(entries) > max_frames:
        pick = np.unique(np.linspace(0, len(entries) - 1, max_frames).round().astype(int))
        entries = [entries[i] for i in pick]
    frames = _Frames([f for _, f in entries], field, size, relative_to)
    for out in outs:
        out.parent.mkdir(parents=True, exist_ok=True)
    # each file is written under a temporary name and renamed once whole: an animation cut
    # short (Ctrl-C, an error) left a valid but short MP4 in the place of the last good one
    parts = {}
    for out in outs:  # (a name of its own: a user's "x.part.mp4" is left alone)
        handle, name = tempfile.mkstemp(suffix=out.suffix, prefix=f".{out.stem}.",
                                        dir=out.parent)
        os.close(handle)
        parts[out] = Path(name)
    movies = [iio.get_writer(parts[out], format="FFMPEG", fps=fps, macro_block_size=16)
              for out in outs if out.suffix.lower() == ".mp4"]
    gif_frames = []
    done = False
    try:
        for t, f in entries:
            image = frames.image(f, t)
            for movie in movies:
                movie.append_data(image)
            if len(movies) < len(outs):
                from PIL import Image

                gif_frames.append(Image.fromarray(image).convert("P", palette=Image.ADAPTIVE))
        for movie in movies:
            movie.close()
        for out in outs:
            if out.suffix.lower() == ".gif":
                gif_frames[0].save(parts[out], format="GIF", save_all=True,
                                   append_images=gif_frames[1:], loop=0,
                                   duration=int(round(1000.0 / fps)))
        for out in outs:
            os.replace(parts[out], out)
        done = True
    finally:
        if not done:
            for movie in movies:
                try:
                    movie.close()
                except Exception:  # noqa: BLE001 - closed already, or broken: it goes anyway
                    pass
            for part in parts.values():
                part.unlink(missing_ok=True)
    return outs
