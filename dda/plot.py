"""Pictures of a run: history plots of a Result (matplotlib) and frames and animations of a
VTU/PVD series (pyvista, off screen).

>>> import dda.plot  # needs matplotlib; the frame functions need pyvista
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

__all__ = ["history", "read_pvd", "render_frame", "animate"]


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
    """The (time, VTU file) entries of a PVD collection, in time order."""
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
        raise ValueError(f"{path} lists no data sets")
    return sorted(entries, key=lambda e: e[0])


def _pyvista():
    try:
        import pyvista as pv
    except ImportError:
        raise ImportError("rendering needs pyvista: pip install 'dda[vis]'") from None
    pv.OFF_SCREEN = True
    return pv


_RELATIVE_FIELDS = ("displacement", "velocity", "rotation")


def _blocks_mesh(pv, file, field, relative_to=None):
    mesh = pv.read(str(file))
    if "kind" in mesh.cell_data:
        mesh = mesh.extract_cells(np.flatnonzero(np.asarray(mesh.cell_data["kind"]) == 0))
    if field not in mesh.cell_data:
        names = sorted(k for k in mesh.cell_data if k not in ("kind", "vtkOriginalCellIds"))
        raise ValueError(f"{file} has no block field {field!r} (there are: {', '.join(names)})")
    values = np.asarray(mesh.cell_data[field], dtype=float)
    if relative_to is not None:
        if field not in _RELATIVE_FIELDS:
            raise ValueError(f"relative_to goes with {', '.join(_RELATIVE_FIELDS)}, not "
                             f"{field!r}")
        ids = np.asarray(mesh.cell_data["block_id"])
        hit = np.flatnonzero(ids == relative_to)
        if len(hit) == 0:
            raise ValueError(f"{file} has no block with block_id {relative_to}")
        values = values - values[hit[0]]
    if values.ndim == 2:
        values = np.linalg.norm(values, axis=1)
    mesh.cell_data["shown"] = values
    return mesh


class _Frames:
    """A plotter with a fixed 2D camera and colour range over a series of frames."""

    def __init__(self, files, field, size, relative_to=None):
        self.pv = _pyvista()
        self.field = field
        self.relative_to = relative_to
        meshes = [_blocks_mesh(self.pv, f, field, relative_to) for f in (files[0], files[-1])]
        lo = np.min([m.bounds[::2] for m in meshes], axis=0)
        hi = np.max([m.bounds[1::2] for m in meshes], axis=0)
        self.bounds = (lo, hi)
        top = max(float(np.nanmax(m.cell_data["shown"])) for m in meshes)
        self.clim = (0.0, top if top > 0 else 1.0)
        self.size = size
        self.title = f"|{field}|" + ("" if relative_to is None else
                                      f" relative to block {relative_to}")

    def image(self, file, time):
        pv = self.pv
        mesh = _blocks_mesh(pv, file, self.field, self.relative_to)
        p = pv.Plotter(off_screen=True, window_size=self.size)
        p.set_background("white")
        p.add_mesh(mesh, scalars="shown", clim=self.clim, cmap="viridis",
                   scalar_bar_args={"title": self.title, "color": "black"})
        # the polygons' own edges (show_edges would draw the triangles they render as)
        p.add_mesh(mesh.extract_all_edges(), color="black", line_width=1)
        p.add_text(f"t = {time:.4g} s", color="black", font_size=10)
        lo, hi = self.bounds
        centre = 0.5 * (lo + hi)
        p.camera_position = [(centre[0], centre[1], 1.0), (centre[0], centre[1], 0.0),
                             (0.0, 1.0, 0.0)]
        p.enable_parallel_projection()
        p.camera.parallel_scale = 0.55 * max(hi[1] - lo[1], (hi[0] - lo[0]) * self.size[1]
                                             / self.size[0])
        img = p.screenshot(return_img=True)
        p.close()
        return img


def render_frame(pvd, png, frame: int = -1, field: str = "displacement",
                 size=(1024, 768), relative_to: int | None = None) -> Path:
    """Render one frame of a PVD series (default the last) to a PNG file, blocks coloured by
    the magnitude of a cell field (``displacement``, ``velocity``, ``stress``, ...).

    ``relative_to`` (a block index, the ``block_id`` of the VTU cells) colours
    displacement, velocity or rotation relative to that block's: on a shaking table, how
    far each block has moved on the table.
    """
    from PIL import Image

    entries = read_pvd(pvd)
    time, file = entries[frame]
    frames = _Frames([file, file], field, size, relative_to)
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(frames.image(file, time)).save(png)
    return png


def animate(pvd, out, field: str = "displacement", fps: float = 10.0, size=(800, 600),
            max_frames: int | None = None, relative_to: int | None = None) -> Path:
    """Animate a PVD series to a GIF (Pillow) or an MP4 (H.264 through imageio-ffmpeg).

    ``max_frames`` keeps that many frames evenly spread over the series. An MP4's frame
    size is rounded up to whole 16-pixel blocks, as the codec needs. ``field`` and
    ``relative_to`` as in :func:`render_frame`.
    """
    out = Path(out)
    kind = out.suffix.lower()
    if kind not in (".gif", ".mp4"):
        raise ValueError(f"animate: write a .gif or an .mp4, not {out.suffix or out.name!r}")
    if kind == ".mp4":
        try:
            import imageio.v3 as iio
            import imageio_ffmpeg  # noqa: F401  (the ffmpeg binary the writer runs)
        except ImportError:
            raise ImportError("MP4 needs imageio and imageio-ffmpeg: pip install 'dda[vis]' "
                              "(or write a .gif)") from None
        size = tuple(16 * -(-int(s) // 16) for s in size)
    entries = read_pvd(pvd)
    if max_frames is not None and len(entries) > max_frames:
        pick = np.unique(np.linspace(0, len(entries) - 1, max_frames).round().astype(int))
        entries = [entries[i] for i in pick]
    frames = _Frames([entries[0][1], entries[-1][1]], field, size, relative_to)
    images = [frames.image(f, t) for t, f in entries]
    out.parent.mkdir(parents=True, exist_ok=True)
    if kind == ".gif":
        from PIL import Image

        pics = [Image.fromarray(i).convert("P", palette=Image.ADAPTIVE) for i in images]
        pics[0].save(out, save_all=True, append_images=pics[1:], loop=0,
                     duration=int(round(1000.0 / fps)))
    else:
        iio.imwrite(out, np.stack(images), plugin="FFMPEG", fps=fps)
    return out
