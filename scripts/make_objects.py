"""Make the shipped convex meshes of ``object="pebble-N"`` (softgrasp_env/scene/meshes/).

Each pebble is the convex hull of seeded random points: a base polygon on the ground (z = 0, so it
stands on a flat face), a smaller top polygon, turned and shifted, and points bulging out between
them. A pebble is kept only if it stands (its centroid over its base with 5 mm to spare) and fits
the default gripper (at most 45 mm from its centroid's vertical in any horizontal direction).

Needs scipy (a development tool, not a dependency of the package):
``python scripts/make_objects.py`` rewrites the files; the seeds make them the same every time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull

from softgrasp_env.scene.objects import MESHES, mesh_mass_properties

OUT = Path(__file__).resolve().parent.parent / "softgrasp_env" / "scene" / "meshes"
SEEDS = {"pebble-0": 11, "pebble-1": 23, "pebble-2": 37}


def _polygon(rng: np.random.Generator, k: int, rx: float, ry: float, z: float, turn: float,
             shift: np.ndarray) -> np.ndarray:  # fmt: skip
    t = np.sort(rng.uniform(0.0, 2.0 * np.pi, k)) + turn
    jitter = rng.uniform(0.85, 1.1, k)
    return np.column_stack((shift[0] + rx * jitter * np.cos(t), shift[1] + ry * jitter * np.sin(t), np.full(k, z)))


def pebble(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles counter-clockwise from outside) of the first pebble of ``seed`` that
    stands and fits."""
    rng = np.random.default_rng(seed)
    while True:
        rx, ry = rng.uniform(0.022, 0.034, 2)
        h = rng.uniform(0.06, 0.09)
        base = _polygon(rng, int(rng.integers(6, 10)), rx, ry, 0.0, 0.0, np.zeros(2))
        f = rng.uniform(0.4, 0.8)
        top = _polygon(rng, int(rng.integers(5, 9)), f * rx, f * ry, h, rng.uniform(0, np.pi),
                       rng.uniform(-0.006, 0.006, 2))  # fmt: skip
        m = int(rng.integers(6, 12))
        zs = rng.uniform(0.2 * h, 0.8 * h, m)
        ts = rng.uniform(0.0, 2.0 * np.pi, m)
        g = rng.uniform(0.9, 1.15, m)
        mid = np.column_stack((g * rx * np.cos(ts), g * ry * np.sin(ts), zs))
        pts = np.vstack((base, top, mid))
        hull = ConvexHull(pts)
        verts = pts[hull.vertices]
        remap = {int(v): k for k, v in enumerate(hull.vertices)}
        tris = []
        for simplex, eq in zip(hull.simplices, hull.equations, strict=True):
            a, b, c = (pts[i] for i in simplex)
            if np.cross(b - a, c - a) @ eq[:3] < 0.0:
                simplex = simplex[[0, 2, 1]]
            tris.append([remap[int(i)] for i in simplex])
        tris = np.array(tris)
        _, centroid, _ = mesh_mass_properties(verts, tris)
        on_ground = verts[np.abs(verts[:, 2]) < 1e-12]
        ground_hull = ConvexHull(on_ground[:, :2])
        # distance of the centroid's foot inside the base polygon (equations: n . x + d <= 0 inside)
        inside = -(ground_hull.equations[:, :2] @ centroid[:2] + ground_hull.equations[:, 2]).max()
        reach = np.hypot(verts[:, 0] - centroid[0], verts[:, 1] - centroid[1]).max()
        if inside >= 0.005 and reach <= 0.045:
            return verts, tris


def write_obj(path: Path, verts: np.ndarray, tris: np.ndarray, name: str, seed: int) -> None:
    lines = [f"# {name}: softgrasp_env's convex mesh, scripts/make_objects.py seed {seed}; metres, z up, base at z = 0"]
    lines += [f"v {x:.9f} {y:.9f} {z:.9f}" for x, y, z in verts]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in tris]
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for name in MESHES:
        verts, tris = pebble(SEEDS[name])
        write_obj(OUT / f"{name}.obj", verts, tris, name, SEEDS[name])
        vol, c, _ = mesh_mass_properties(verts, tris)
        print(f"{name}: {len(verts)} vertices, {len(tris)} triangles, {vol * 1e6:.1f} cm^3, centroid height "
              f"{c[2] * 1000:.1f} mm, top {verts[:, 2].max() * 1000:.1f} mm")  # fmt: skip


if __name__ == "__main__":
    main()
