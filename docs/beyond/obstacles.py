"""A cell in a channel, with and without a constriction: the figure and numbers of
docs/beyond.md's section on obstacles.

    python docs/beyond/obstacles.py -o docs/beyond [--runs DIR]

Simulates (into DIR, default a temporary folder) one ring of R = 5 cm running and tumbling
for 600 s from the origin, 8 realizations of root seed 0, in a closed channel 14 cm wide and
89 cm long (walls 1 cm thick, centre lines at y = +-7.5 cm and x = -30, 60 cm), once open and
once with a constriction: two
posts of radius 3 cm on the walls at x = 15 cm, which leave a gap of 9 cm, less than the
ring's diameter. Writes ``obstacles.json`` (per variant: how many realizations crossed
x = 15 cm, when first, the shape index of the membrane inside the gap and elsewhere, the
deepest point of the membrane inside an obstacle) and ``obstacles.png``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

import softcell
from softcell.model.configuration import RunConfig, with_obstacle_term
from softcell.model.obstacle_layout import parse_obstacles, surface_distances

RADIUS, DURATION, REALIZATIONS, SEED = 5.0, 600.0, 8, 0
CHANNEL = (
    "wall -30 -7.5 60 -7.5 1; wall -30 7.5 60 7.5 1; wall -30 -7.5 -30 7.5 1; wall 60 -7.5 60 7.5 1"
)
GATE_X = 15.0
VARIANTS = {
    "open": CHANNEL,
    "constriction": f"{CHANNEL}; post {GATE_X:g} -7.5 3; post {GATE_X:g} 7.5 3",
}


def run(folder: Path, obstacles: str) -> Path:
    config = with_obstacle_term(
        RunConfig(parameters={"radius": RADIUS, "duration": DURATION, "obstacles": obstacles})
    )
    softcell.simulate(config, folder, realizations=REALIZATIONS, seed=SEED, workers=2)
    return folder


def shape_index(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Perimeter^2 / (4 pi area) of the polygon through the stored nodes (1 for a circle)."""
    dx, dy = np.roll(x, -1, axis=-1) - x, np.roll(y, -1, axis=-1) - y
    perimeter = np.hypot(dx, dy).sum(axis=-1)
    area = 0.5 * np.abs((x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y).sum(axis=-1))
    return perimeter**2 / (4 * np.pi * area)


def summary(ds, obstacles: str) -> dict:
    cx, mx, my = ds["cell_x"].values, ds["membrane_x"].values, ds["membrane_y"].values
    times = ds["time"].values
    crossed = [np.flatnonzero(c > GATE_X) for c in cx]
    first = [float(times[c[0]]) for c in crossed if c.size]
    index = shape_index(mx, my)
    gate = np.abs(cx - GATE_X) < RADIUS
    return {
        "obstacles": obstacles,
        "realizations": int(cx.shape[0]),
        "crossed": len(first),
        "first_crossing_s": sorted(first),
        "shape_index_at_gate": float(index[gate].mean()) if gate.any() else None,
        "shape_index_elsewhere": float(index[~gate].mean()),
        "deepest_cm": float(surface_distances(mx, my, obstacles).min()),
        "time_at_gate_fraction": float(gate.mean()),
    }


def figure(data: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Rectangle

    fig, axes = plt.subplots(
        len(data), 1, figsize=(7.2, 1.75 * len(data)), sharex=True, layout="constrained"
    )
    for ax, (name, (ds, obstacles)) in zip(axes, data.items(), strict=True):
        for o in parse_obstacles(obstacles):
            if o.kind == "post":
                ax.add_patch(Circle((o.x, o.y), o.radius, color="0.45"))
            else:
                half = o.half_thickness  # an axis-aligned wall, its round ends squared
                x0, x1 = sorted((o.x0, o.x1))
                y0, y1 = sorted((o.y0, o.y1))
                ax.add_patch(
                    Rectangle(
                        (x0 - half, y0 - half),
                        x1 - x0 + 2 * half,
                        y1 - y0 + 2 * half,
                        color="0.45",
                    )
                )
        r = 0
        for r in range(ds.sizes["realization"]):
            one = ds.isel(realization=r)
            ax.plot(one["cell_x"], one["cell_y"], lw=0.6, alpha=0.8, color=f"C{r}")
        one = ds.isel(realization=int(np.argmax(ds["cell_x"].max("time").values)))
        pick = int(np.argmax(one["cell_x"].values))
        for t in (0, pick // 2, pick):
            x, y = one["membrane_x"].values[t], one["membrane_y"].values[t]
            ax.fill(x, y, facecolor="none", edgecolor="k", lw=0.8)
        ax.set_aspect("equal")
        ax.set_xlim(-31, 61)
        ax.set_ylim(-8.2, 8.2)
        ax.set_ylabel("y (cm)")
        ax.set_title(
            f"{name}: cell centres of {ds.sizes['realization']} realizations over "
            f"{DURATION:g} s; rings at three times of the farthest",
            fontsize=9,
        )
    axes[-1].set_xlabel("x (cm)")
    fig.savefig(out, dpi=150)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--runs", type=Path)
    args = parser.parse_args()
    runs = args.runs or Path(tempfile.mkdtemp(prefix="softcell-obstacles-"))
    data, numbers = {}, {}
    for name, obstacles in VARIANTS.items():
        ds = softcell.open_dataset(run(runs / name, obstacles))
        data[name] = (ds, obstacles)
        numbers[name] = summary(ds, obstacles)
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "obstacles.json").write_text(json.dumps(numbers, indent=1) + "\n")
    figure(data, args.output / "obstacles.png")
    print(json.dumps(numbers, indent=1))


if __name__ == "__main__":
    main()
