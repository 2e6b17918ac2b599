"""The picture of a strength reduction (:meth:`StrengthReduction.picture`; matplotlib).

Left: the scene, its failing blocks (at the smallest failed factor) in red, the other free
blocks light, the fixed and driven ones dark, the water table (if any) in blue and the bolts
(if any) in their starting positions as orange lines. Right: every trial's movement (the largest
criterion ratio: 1 or more is failed) against F (movement on a log scale), stable trials as
circles, failed ones as crosses (each at the step that stopped it: a trial ends once its
failure is certain, so a weaker joint may show less movement), the final bracket shaded and F
marked.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["picture"]

#: the smallest movement ratio drawn (a log axis has no zero)
FLOOR = 1e-6


def picture(fos, path=None):
    """Draw ``fos`` (a :class:`dda.studies.factor_of_safety.StrengthReduction`); write it
    to ``path`` (PNG, PDF, SVG by suffix) and close it when given. Returns the figure."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    scene = fos.scene
    verts, offsets = scene.vertex_arrays()
    polygons = [verts[offsets[i]:offsets[i + 1]] for i in range(len(offsets) - 1)]
    colour = np.where(fos.plan.watched, "0.88", "0.55").astype(object)
    for b in fos.failing_blocks:
        colour[b.index] = "tab:red"
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5),
                                   gridspec_kw={"width_ratios": [1.3, 1.0]})
    ax0.add_collection(PolyCollection(polygons, facecolors=list(colour), edgecolors="k",
                                      linewidths=0.5))
    _draw_effects(ax0, scene, verts)
    ax0.autoscale_view()
    ax0.set_aspect("equal")
    ax0.set_xlabel("x (m)")
    ax0.set_ylabel("y (m)")
    lo, hi = fos.bracket
    ax0.set_title(f"F = {fos.factor:.4g}; in red the blocks failing at F = {hi:.4g}"
                  if math.isfinite(hi) else f"stable up to F = {lo:.4g}", fontsize="medium")

    f = np.array([r["factor"] for r in fos.trials])
    m = np.maximum(np.array([r["movement"] for r in fos.trials]), FLOOR)
    ok = np.array([bool(r["stable"]) for r in fos.trials])
    if 0.0 < lo and math.isfinite(hi):
        ax1.axvspan(lo, hi, color="0.9", label="final bracket")
    if math.isfinite(fos.factor):
        ax1.axvline(fos.factor, color="k", lw=0.8, label=f"F = {fos.factor:.4g}")
    ax1.axhline(1.0, color="tab:red", lw=0.8, ls="--", label="threshold")
    ax1.plot(f[ok], m[ok], "o", mfc="none", color="tab:blue", label="stable")
    ax1.plot(f[~ok], m[~ok], "x", color="tab:red", label="failed")
    ax1.set_yscale("log")
    ax1.set_xlabel("F (joint strength divided by F)")
    # a failed trial stops once its failure is certain: its movement is the one at that step
    ax1.set_ylabel("movement / threshold (failed: when stopped)")
    ax1.set_title(f"{len(fos.trials)} trials, {fos.plan.analysis}", fontsize="medium")
    ax1.legend(fontsize="small")
    if ax0.get_legend_handles_labels()[0]:
        ax0.legend(fontsize="small", loc="best")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path)
        plt.close(fig)
    return fig


def _draw_effects(ax, scene, verts) -> None:
    """The scene's water table across its blocks' width and its bolts at the start: a strength
    reduction weakens the joints, not these, so a reader should see what holds the slope."""
    water = scene.water
    if water is not None:
        x0, x1 = float(verts[:, 0].min()), float(verts[:, 0].max())
        inside = water.x[(water.x > x0) & (water.x < x1)]
        x = np.concatenate([[x0], inside, [x1]])
        ax.plot(x, water.head(x), color="tab:blue", lw=1.5, label="water table")
    for k, bolt in enumerate(scene.bolts):
        ax.plot([bolt.point_a[0], bolt.point_b[0]], [bolt.point_a[1], bolt.point_b[1]],
                color="tab:orange", lw=1.5, label="bolts" if k == 0 else None)
