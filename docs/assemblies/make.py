"""The figures, numbers and movie of docs/assemblies.md's constriction study.

    python docs/assemblies/make.py -o docs/assemblies [--runs DIR]

Runs ``softcell study constriction`` (the full grid, root seed 0, every core) into DIR
(default a temporary folder; a finished study there is kept), copies its
``constriction.png`` and ``constriction.json`` into the output folder, and animates the
first passage of the narrowest gap any R = 5 cm cell passed: 40 s about the moment its
centre crossed the partition's line, from the study's
0.1 s samples at twice real time (20 frames/s), as an H.264 MP4 in the ``_static/gallery``
folder beside the output folder, with its frame at the passage as ``passage.png``. Then
runs the study once more at R = 5 cm only, gaps 0.7, 0.8 and 0.9, with the bending stiffness
k ten times lower (into DIR/soft_k), and copies its summary as ``constriction_soft_k.json``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

import softcell
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.studies.constriction import (
    FULL,
    ConstrictionDesign,
    channel,
    constriction,
    passage_samples,
)

SEED, RADIUS, HALF_WINDOW = 0, 5.0, 20.0


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--runs", type=Path, help="where the study goes (kept)")
    args = parser.parse_args(argv)
    runs = args.runs or Path(tempfile.mkdtemp(prefix="softcell-constriction-"))
    constriction(runs, design=FULL, seed=SEED)
    args.output.mkdir(parents=True, exist_ok=True)
    for name in ("constriction.png", "constriction.json"):
        shutil.copyfile(runs / name, args.output / name)
    result = json.loads((runs / "constriction.json").read_text())
    movie = args.output.parent / "_static" / "gallery" / "constriction.mp4"
    movie.parent.mkdir(parents=True, exist_ok=True)
    passage = first_passage(runs, result)
    if passage is None:
        sys.exit("no R = 5 cm cell passed any gap: no movie")
    path, at, gap = passage
    from softcell.video.animate import animate

    sys.path.insert(0, str(Path(__file__).parents[1] / "gallery"))
    from make import still  # the gallery's frame grabber

    ds = softcell.open_dataset(path)
    movie.unlink(missing_ok=True)
    start = max(at - HALF_WINDOW, 0.0)
    animate(ds, movie, fps=20, speed=2.0, start=start, end=at + HALF_WINDOW, height=400, crf=28)
    still(movie, (at - start) / 2.0, args.output / "passage.png")
    print(f"movie: {path.name} (w / 2R = {gap:g}), passage at t = {at:.1f} s")
    soft = ConstrictionDesign("soft k", (RADIUS,), (0.7, 0.8, 0.9), 6, 600.0)
    k = MODEL_PARAMETERS["bending_stiffness"].default / 10
    constriction(runs / "soft_k", design=soft, seed=SEED, parameters={"bending_stiffness": k})
    shutil.copyfile(runs / "soft_k" / "constriction.json", args.output / "constriction_soft_k.json")


def first_passage(runs: Path, result: dict) -> tuple[Path, float, float] | None:
    """(file, time in s when the centre crossed the partition's line, gap) of the first
    passage at R = RADIUS through the narrowest gap
    any cell of that radius passed, or None."""
    gaps = result["design"]["gaps"]
    passed = [p for p in result["points"] if p["radius"] == RADIUS and sum(p["passages"]) > 0]
    if not passed:
        return None
    point = min(passed, key=lambda p: p["gap"])
    index, gate = gaps.index(point["gap"]), channel(RADIUS, point["gap"])[1]
    for r, count in enumerate(point["passages"]):
        if count:
            path = runs / f"R{RADIUS:g}" / f"point{index:03d}_realization{r:04d}.nc"
            ds = softcell.open_dataset(path)
            x = ds["cell_x"].values.reshape(-1)
            done = passage_samples(x, gate)[0]
            # the moment its centre crossed the partition's line, on the way
            before = np.flatnonzero(np.sign(x[:done] - gate.x) != np.sign(x[done] - gate.x))
            return path, float(ds["time"].values[before[-1] + 1]), point["gap"]
    return None


if __name__ == "__main__":
    main()
