"""Pictures of a run: history plots of a Result (matplotlib) and frames and animations of a
VTU/PVD series (pyvista, off screen).

>>> import dda.plot  # needs matplotlib; the frame functions need pyvista
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

__all__ = ["history", "read_pvd", "render_frame", "animate"]


def history(result, blocks=None, path=None, title=None):
    """Plot a run's histories: block displacement, joint forces and contact states over time.

    Parameters
    ----------
    result : dda.Result
    blocks : list of Block (or names), optional
        The blocks to plot (default: every block that moved, up to 8).
    path : str or Path, optional
        Write the figure there (PNG, PDF, SVG by suffix) and close it.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three panels: |centroid displacement| of each block, the normal and shear force of
        the joints those blocks carry, and the number of open-to-closed contacts per step.
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    scene = result.scene
    if blocks is None:
        moved = [b for b in scene.blocks
                 if np.abs(result.displacement(b)).max(initial=0.0) > 0.0]
        blocks = moved[:8]
    blocks = [scene.block(b) for b in blocks]
    t = result.time
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for b in blocks:
        u = result.displacement(b)
        axes[0].plot(t, 1e3 * np.hypot(u[:, 0], u[:, 1]), label=b.name)
    axes[0].set_ylabel("displacement (mm)")
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
        axes[2].step(st.time, st.closed, where="post", label="closed")
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


def _blocks_mesh(pv, file, field):
    mesh = pv.read(str(file))
    if "kind" in mesh.cell_data:
        mesh = mesh.extract_cells(np.flatnonzero(np.asarray(mesh.cell_data["kind"]) == 0))
    values = np.asarray(mesh.cell_data[field])
    if values.ndim == 2:
        values = np.linalg.norm(values, axis=1)
    mesh.cell_data["shown"] = values
    return mesh


class _Frames:
    """A plotter with a fixed 2D camera and colour range over a series of frames."""

    def __init__(self, files, field, size):
        self.pv = _pyvista()
        self.field = field
        meshes = [_blocks_mesh(self.pv, f, field) for f in (files[0], files[-1])]
        lo = np.min([m.bounds[::2] for m in meshes], axis=0)
        hi = np.max([m.bounds[1::2] for m in meshes], axis=0)
        self.bounds = (lo, hi)
        top = max(float(np.nanmax(m.cell_data["shown"])) for m in meshes)
        self.clim = (0.0, top if top > 0 else 1.0)
        self.size = size

    def image(self, file, time):
        pv = self.pv
        mesh = _blocks_mesh(pv, file, self.field)
        p = pv.Plotter(off_screen=True, window_size=self.size)
        p.set_background("white")
        p.add_mesh(mesh, scalars="shown", clim=self.clim, cmap="viridis", show_edges=True,
                   edge_color="black", scalar_bar_args={"title": f"|{self.field}|",
                                                        "color": "black"})
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
                 size=(1024, 768)) -> Path:
    """Render one frame of a PVD series (default the last) to a PNG file, blocks coloured by
    the magnitude of a cell field (``displacement``, ``velocity``, ``stress``, ...)."""
    from PIL import Image

    entries = read_pvd(pvd)
    time, file = entries[frame]
    frames = _Frames([file, file], field, size)
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(frames.image(file, time)).save(png)
    return png


def animate(pvd, out, field: str = "displacement", fps: float = 10.0, size=(800, 600),
            max_frames: int | None = None) -> Path:
    """Animate a PVD series to a GIF (Pillow) or an MP4 (H.264 through imageio-ffmpeg).

    ``max_frames`` keeps that many frames evenly spread over the series. An MP4's frame
    size is rounded up to whole 16-pixel blocks, as the codec needs.
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
    frames = _Frames([entries[0][1], entries[-1][1]], field, size)
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
