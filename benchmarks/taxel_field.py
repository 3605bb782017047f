"""Pictures of the pads' taxel field: the tissue fingers holding the default
cylinder, then the cylinder made heavier until it slips (accuracy.shear_under_load), read on a
fine grid at three moments - the hold, 95 % of the way to the slip load, and the first sample
after the slip.

    PYTHONPATH=. python benchmarks/taxel_field.py [--rows 12] [--cols 8] [--plot docs/results/taxel_field.png]

Each column is a moment, the rows are the left pad's pressure [kPa] and its downward shear
[mm] (the right pad is its mirror). Prints each moment's load and the field's totals. The default
pad has 3 x 4 free particles on its inner face (13 x 15 mm cells): a finer grid shows how each
cell's load is spread, not finer physics.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from softgrasp_env.accuracy import shear_under_load
from softgrasp_env.config import FRICTION_LAWS, TissueConfig
from softgrasp_env.scene import GraspScene, SceneConfig

ROOT = Path(__file__).resolve().parents[1]


def moments(load: np.ndarray, slip_load: float) -> list[tuple[str, int]]:
    """(label, sample index) of the hold, 95 % of the way to slip, and the first sample past it."""
    near = int(np.searchsorted(load, load[0] + 0.95 * (slip_load - load[0])))
    return [("holding", 0), ("95 % of the slip load", min(near, len(load) - 2)), ("slipping", len(load) - 1)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=12)
    parser.add_argument("--cols", type=int, default=8)
    parser.add_argument("--plot", type=Path, default=ROOT / "docs" / "results" / "taxel_field.png")
    parser.add_argument("--friction-law", choices=FRICTION_LAWS, default="patch",
                        help="the tissue's friction law (TissueConfig.friction_law)")
    ns = parser.parse_args(argv)
    scene = GraspScene(SceneConfig(tissue=TissueConfig(friction_law=ns.friction_law)))
    try:
        rec = shear_under_load(scene, rows=ns.rows, cols=ns.cols)
        grid = scene.fingers.taxel_grid(ns.rows, ns.cols)
    finally:
        scene.close()
    picks = moments(rec.load, rec.slip_load)
    for label, k in picks:
        f = rec.fields[k]
        print(f"{label:<24} load {rec.load[k]:.3f} N: pressure x area {f[..., 0].sum(axis=(1, 2)) * grid.area} N, "
              f"shear under the loaded taxels {rec.shear[k] * 1e3:.3f} mm, slide {rec.slide[k] * 1e3:.3f} mm")  # fmt: skip
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return 0
    fig, axes = plt.subplots(2, len(picks), figsize=(3.2 * len(picks), 6.4), constrained_layout=True)
    extent = (-grid.half_width * 100, grid.half_width * 100, -grid.half_height * 100, grid.half_height * 100)
    pmax = max(float(rec.fields[k][0, ..., 0].max()) for _, k in picks) / 1e3
    smax = max(float(-rec.fields[k][0, ..., 4].min()) for _, k in picks) * 1e3
    for col, (label, k) in enumerate(picks):
        f = rec.fields[k][0]
        im0 = axes[0, col].imshow(f[..., 0] / 1e3, extent=extent, vmin=0.0, vmax=pmax, cmap="viridis")
        im1 = axes[1, col].imshow(-f[..., 4] * 1e3, extent=extent, vmin=0.0, vmax=smax, cmap="magma")
        axes[0, col].set_title(f"{label}\nload {rec.load[k]:.2f} N", fontsize=9)
        for row in (0, 1):
            axes[row, col].set_xlabel("along the face, y [cm]", fontsize=8)
        axes[0, col].set_ylabel("up, z [cm]", fontsize=8)
        axes[1, col].set_ylabel("up, z [cm]", fontsize=8)
    fig.colorbar(im0, ax=axes[0, :], label="pressure [kPa]")
    fig.colorbar(im1, ax=axes[1, :], label="downward shear [mm]")
    law = {"patch": "", "contact": ", Coulomb per contact"}[ns.friction_law]
    fig.suptitle(f"The left pad's taxels: the default cylinder made heavier until it slips{law}", fontsize=10)
    ns.plot.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(ns.plot, dpi=100)
    print(f"wrote {ns.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
