"""Figure of a designed tube: the reach boxes over the arena, and each bound against time."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..runtime.plots import _draw_unsafe_sets, _rect  # noqa: E402
from ..spec.loader import Box, Spec  # noqa: E402
from .result import Design  # noqa: E402

#: Reach boxes drawn over the arena.
BOXES_DRAWN = 24


def plot_design(spec: Spec, design: Design, path: str | Path) -> Path:
    """Write a PNG of ``design``: tube boxes (the certificate's enclosure) and via boxes in
    the first two dimensions, and the certified enclosure of ``gamma_L``, ``gamma_U`` per
    dimension against time.

    Parameters
    ----------
    spec : Spec
    design : Design
    path : str or path
        Output file; its folder must exist.

    Returns
    -------
    pathlib.Path
    """
    tube, enc = design.tube, design.certificate.enclosure
    n = spec.dimension
    t_c = tube.prescribed_time
    fig = plt.figure(figsize=(11, 2.6 * max(n, 2)), layout="constrained")
    grid = fig.add_gridspec(n, 2, width_ratios=[1.1, 1.4])
    if n >= 2:
        ax = fig.add_subplot(grid[:, 0])
        dims = (0, 1)
        _rect(ax, spec.state_space, dims, fill=False, lw=1.5, ec="black")
        _draw_unsafe_sets(ax, spec, dims)
        _rect(ax, spec.target_set, dims, fc="tab:green", alpha=0.35, label="target")
        times = np.linspace(0.0, t_c, BOXES_DRAWN)
        which = np.searchsorted(enc.t_start, times, side="right") - 1
        for k in which:
            _rect(ax, Box(tuple(enc.lower_min[k]), tuple(enc.upper_max[k])), dims, fill=False,
                  ec="tab:orange", lw=0.6,
                  label="tube box (certified enclosure)" if k == which[0] else None)
        for k, seg in enumerate(tube.segments if design.method != "paper" else ()):
            _rect(ax, Box(seg.lower_to, seg.upper_to), dims, fill=False, ec="tab:purple",
                  lw=1.2, label="via boxes" if k == 0 else None)
        ax.set_xlim(spec.state_space.lower[0], spec.state_space.upper[0])
        ax.set_ylim(spec.state_space.lower[1], spec.state_space.upper[1])
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        ax.set_aspect("equal")
        ax.legend(loc="lower right", fontsize=7)
        ax.set_title(f"{spec.name}: {design.method} method, "
                     f"{design.design_time_s * 1e3:.1f} ms")
    end = 1.2 * t_c
    keep = enc.t_start < end
    t0 = enc.t_start[keep]
    t1 = np.minimum(enc.t_end[keep], end)
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        for lo, hi, colour, name in ((enc.lower_min, enc.lower_max, "tab:blue", r"$\gamma_L$"),
                                     (enc.upper_min, enc.upper_max, "tab:orange",
                                      r"$\gamma_U$")):
            for k in range(t0.size):
                ax.fill_between([t0[k], t1[k]], [lo[keep][k, i]] * 2, [hi[keep][k, i]] * 2,
                                color=colour, alpha=0.35, lw=0.8, edgecolor=colour,
                                label=f"{name} enclosure" if k == 0 else None)
        ax.axvline(t_c, color="tab:red", lw=0.8, ls=":", label="$t_c$")
        ax.set_ylabel(f"$x_{i + 1}$")
        if i == n - 1:
            ax.set_xlabel("t [s] (certified for every t >= 0; drawn up to 1.2 t_c)")
        if i == 0:
            ax.legend(loc="best", fontsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
