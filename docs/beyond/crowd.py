"""Many cells: the strip of frames and the numbers of docs/beyond.md's section on assemblies.

    python docs/beyond/crowd.py -o docs/beyond [--runs DIR]

Simulates (into DIR, default a temporary folder), with root seed 0:

- a crowd: 16 rings of R = 5 cm at an area fraction of 0.35 in a periodic box of side 59.9 cm,
  from a square lattice, for 60 s, three realizations (the frames show realization 0);
- a corral: 8 rings of R = 5 cm in a walled box of side 44 cm around a post of radius 4 cm at
  its centre, placed at random at least 0.5 cm apart, for 60 s.

Writes ``crowd.png`` (four frames of each), ``crowd_analysis.png`` (the crowd's analysis:
the bots' polar order, g(r), cluster sizes, the shape index against the local area fraction)
and ``crowd.json`` (per run: the cells' mean displacement over realization 0, the deepest
any membrane point went into another ring and into the post, in contact lengths; for the
crowd, the analysis' numbers with standard errors across the realizations).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from pathlib import Path

import numpy as np
from matplotlib.path import Path as Polygon

import softcell
from softcell.model.configuration import RunConfig, with_obstacle_term

RADIUS, DURATION, SEED = 5.0, 60.0, 0
CROWD = {"cells": 16, "box": round(math.sqrt(16 * math.pi * RADIUS**2 / 0.35), 1)}
POST = "post 0 0 4"
CORRAL = {"cells": 8, "box": 44.0, "boundary": "walls", "placement": "random", "gap": 0.5}
FRAMES = (0.0, 20.0, 40.0, 60.0)


CROWD_REALIZATIONS = 3
ANALYSIS = {"discard": 5.0, "crowd_every": 0.5}


def run(folder: Path, assembly: dict, obstacles: str = "", realizations: int = 1) -> Path:
    parameters = {"radius": RADIUS, "duration": DURATION}
    if obstacles:
        parameters["obstacles"] = obstacles
    config = with_obstacle_term(RunConfig(parameters=parameters, assembly=assembly))
    softcell.simulate(config, folder, seed=SEED, realizations=realizations)
    return folder


def _mean_and_error(values: np.ndarray) -> list[float]:
    """Mean over realizations (leading axis, each first averaged over the rest) and its
    standard error."""
    per = values.reshape(values.shape[0], -1).mean(axis=1)
    return [round(float(per.mean()), 3), round(float(per.std(ddof=1) / math.sqrt(per.size)), 3)]


def crowd_analysis(ds, out: Path) -> dict:
    """The crowd's analysis: a figure and its numbers."""
    import matplotlib.pyplot as plt

    a = softcell.analyze(ds, ANALYSIS)
    cells = int(ds.sizes["cell"])
    independent = math.sqrt(math.pi) / 2 / math.sqrt(cells)  # E|mean of M random headings|
    g, g_err = a["pair_correlation"].values, a["pair_correlation_error"].values
    r = a["pair_distance"].values
    peak = int(np.nanargmax(g))
    numbers = {
        "realizations": int(ds.sizes["realization"]),
        "polar_order": _mean_and_error(a["polar_order"].values),
        "polar_order_independent_headings": round(independent, 3),
        "mean_cluster_size": _mean_and_error(a["mean_cluster_size"].values),
        "largest_cluster": _mean_and_error(a["largest_cluster"].values),
        "pair_correlation_peak": [round(float(g[peak]), 2), round(float(g_err[peak]), 2)],
        "pair_correlation_peak_at_2R": round(float(r[peak]), 3),
        "neighbour_exchange_rate_per_s": _mean_and_error(a["neighbour_exchange_rate"].values),
        "local_area_fraction": _mean_and_error(a["local_area_fraction"].values),
    }
    fig, axes = plt.subplots(2, 2, figsize=(8, 6.2), layout="constrained")
    axes = axes.ravel()
    ax = axes[0]
    for i in range(a.sizes["realization"]):
        ax.plot(a["time"], a["polar_order"].isel(realization=i), lw=0.8, label=f"realization {i}")
    ax.axhline(independent, color="k", ls="--", lw=0.8, label="independent headings")
    ax.set(xlabel="time (s)", ylabel="polar order of the bots", ylim=(0, 1))
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.errorbar(r, g, yerr=g_err, fmt="o-", ms=2.5, lw=0.8, capsize=2)
    ax.axhline(1.0, color="k", ls="--", lw=0.8)
    ax.set(xlabel="centre distance r / 2R", ylabel="pair correlation g(r)")
    ax = axes[2]
    size = a["cluster_size"].values
    ax.bar(size, a["cluster_size_fraction"].values, color="tab:blue")
    ax.set(xlabel="cluster size (cells in contact)", ylabel="fraction of cells")
    ax = axes[3]
    count = a["shape_index_by_density_count"].values
    shown = count >= 10
    ax.errorbar(
        a["area_fraction_bin"].values[shown],
        a["shape_index_by_density"].values[shown],
        yerr=a["shape_index_by_density_error"].values[shown],
        fmt="o",
        ms=3,
        capsize=2,
    )
    ax.axhline(2 * math.sqrt(math.pi), color="k", ls="--", lw=0.8, label=r"circle, $2\sqrt{\pi}$")
    ax.set(xlabel="local area fraction", ylabel="shape index P / sqrt(A)")
    ax.legend(fontsize=8)
    fig.suptitle(
        f"{cells} cells of R = 5 cm at an area fraction of 0.35 (periodic box), "
        f"{numbers['realizations']} realizations of 60 s,\nfrom {ANALYSIS['discard']:g} s, "
        "samples 0.5 s apart; error bars: standard errors across realizations",
        fontsize=10,
    )
    fig.savefig(out / "crowd_analysis.png", dpi=110)
    return numbers


def _segment_distances(points: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """Each point's distance (cm) to the closed polygon ``ring`` (its edges)."""
    a, b = ring, np.roll(ring, -1, axis=0)
    ab = b - a
    ap = points[:, None, :] - a[None]
    t = np.clip((ap * ab[None]).sum(-1) / (ab * ab).sum(-1)[None], 0.0, 1.0)
    d = ap - t[..., None] * ab[None]
    return np.hypot(d[..., 0], d[..., 1]).min(axis=1)


def deepest(ds, box: float, periodic: bool) -> float:
    """The deepest any stored membrane point went into another ring (cm), every 0.1 s, the
    rings as polygons of their 64 stored points (whose sagitta is 0.006 cm)."""
    worst = 0.0
    mx, my = ds["membrane_x"].values[0], ds["membrane_y"].values[0]
    # every 0.1 s, whatever the membrane record's sampling (an assembly keeps it every 0.1 s)
    every = max(1, round(0.1 / float(np.diff(ds["time"].values[:2])[0])))
    for t in range(0, mx.shape[0], every):
        cells = mx.shape[1]
        centres = np.stack([mx[t].mean(axis=-1), my[t].mean(axis=-1)], axis=1)
        for c in range(cells):
            points = np.stack([mx[t, c], my[t, c]], axis=1)
            for d in range(cells):
                if d == c:
                    continue
                shift = np.zeros(2)
                if periodic:
                    shift = -box * np.round((centres[d] - centres[c]) / box)
                ring = np.stack([mx[t, d], my[t, d]], axis=1) + shift
                inside = Polygon(ring).contains_points(points)
                if inside.any():
                    worst = max(worst, float(_segment_distances(points[inside], ring).max()))
    return worst


def into_post(ds, obstacles: str) -> float:
    """The deepest any stored membrane point went into an obstacle (cm)."""
    from softcell.model.obstacle_layout import surface_distances

    x, y = ds["membrane_x"].values, ds["membrane_y"].values
    return max(0.0, float(-surface_distances(x, y, obstacles).min()))


def summary(ds, box: float, periodic: bool, obstacles: str = "") -> dict:
    lam = float(ds.attrs["parameter_contact_length"])
    cx, cy = ds["cell_x"].values[0], ds["cell_y"].values[0]
    moved = np.hypot(cx[-1] - cx[0], cy[-1] - cy[0])
    return {
        "cells": int(ds.sizes["cell"]),
        "box_cm": box,
        "boundary": str(ds["domain_box"].attrs["boundary"]),
        "mean_displacement_cm": round(float(moved.mean()), 2),
        "deepest_into_a_ring_lambda": round(deepest(ds, box, periodic) / lam, 2),
        **(
            {"deepest_into_the_post_lambda": round(into_post(ds, obstacles) / lam, 2)}
            if obstacles
            else {}
        ),
    }


def draw(axes, ds, box: float, walls: bool, obstacles: str) -> None:
    import matplotlib.pyplot as plt

    times = ds["time"].values
    colors = plt.get_cmap("tab20")(np.linspace(0, 1, ds.sizes["cell"]))
    for ax, when in zip(axes, FRAMES, strict=True):
        t = int(np.argmin(np.abs(times - when)))
        mx, my = ds["membrane_x"].values[0, t], ds["membrane_y"].values[0, t]
        bx, by = ds["bot_x"].values[0, : t + 1], ds["bot_y"].values[0, : t + 1]
        angle = ds["bot_angle"].values[0, t]
        for c, color in enumerate(colors):
            shift = (
                np.zeros(2)
                if walls
                else -box * np.round(np.array([mx[c].mean(), my[c].mean()]) / box)
            )
            for dx in (-box, 0.0, box) if not walls else (0.0,):
                for dy in (-box, 0.0, box) if not walls else (0.0,):
                    x = np.append(mx[c], mx[c][0]) + shift[0] + dx
                    y = np.append(my[c], my[c][0]) + shift[1] + dy
                    ax.plot(x, y, color=color, lw=1.2)
                    ax.plot(
                        bx[-200:, c] + shift[0] + dx,
                        by[-200:, c] + shift[1] + dy,
                        color=color,
                        lw=0.5,
                        alpha=0.6,
                    )
                    tip = np.array([bx[-1, c], by[-1, c]]) + shift + (dx, dy)
                    ax.plot(*tip, "o", color=color, ms=2)
                    ax.plot(
                        *np.stack(
                            [tip, tip + 3 * np.array([np.cos(angle[c]), np.sin(angle[c])])], axis=1
                        ),
                        color="k",
                        lw=0.6,
                    )
        half = box / 2
        ax.plot(
            [-half, half, half, -half, -half],
            [-half, -half, half, half, -half],
            color="k",
            lw=1.5 if walls else 0.6,
            ls="-" if walls else "--",
        )
        if obstacles:
            ax.add_patch(plt.Circle((0, 0), 4.0, color="0.3"))
        ax.set_xlim(-half - 1, half + 1)
        ax.set_ylim(-half - 1, half + 1)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"t = {times[t]:.0f} s", fontsize=9)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--runs", type=Path, help="where the simulations go (kept)")
    args = parser.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = args.runs or Path(tempfile.mkdtemp(prefix="softcell-crowd-"))
    crowd = run(runs / "crowd", CROWD, realizations=CROWD_REALIZATIONS)
    corral = run(runs / "corral", CORRAL, POST)
    ds_crowd, ds_corral = softcell.open_dataset(crowd), softcell.open_dataset(corral)
    numbers = {
        "crowd": summary(ds_crowd, CROWD["box"], True),
        "corral": summary(ds_corral, CORRAL["box"], False, POST),
    }
    fig, axes = plt.subplots(2, 4, figsize=(8, 4.6), layout="constrained")
    draw(axes[0], ds_crowd, CROWD["box"], False, "")
    draw(axes[1], ds_corral, CORRAL["box"], True, POST)
    for row in axes:
        x0 = row[0].get_xlim()[0] + 2
        y0 = row[0].get_ylim()[0] + 2
        row[0].plot([x0, x0 + 10], [y0, y0], color="k", lw=2.5)
        row[0].text(x0 + 5, y0 + 0.8, "10 cm", ha="center", va="bottom", fontsize=8)
    axes[0, 0].set_ylabel(f"16 cells,\nperiodic box {CROWD['box']:g} cm", fontsize=9)
    axes[1, 0].set_ylabel(f"8 cells, walled box\n{CORRAL['box']:g} cm, a post", fontsize=9)
    fig.suptitle(
        "Assemblies of soft cells (R = 5 cm): membranes, bots (dot and heading)\nand the "
        "bots' last 2 s of path",
        fontsize=10,
    )
    args.output.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.output / "crowd.png", dpi=110)
    numbers["crowd"]["analysis"] = crowd_analysis(ds_crowd, args.output)
    (args.output / "crowd.json").write_text(json.dumps(numbers, indent=2) + "\n")
    print(json.dumps(numbers, indent=2))


if __name__ == "__main__":
    main()
