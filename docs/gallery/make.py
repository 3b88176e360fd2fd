"""The movies of docs/gallery.md.

    python docs/gallery/make.py -o docs/gallery [--runs DIR]

(the movies go to the ``_static/gallery`` folder beside the output folder).

Simulates (into DIR, default a temporary folder; root seed 0) four realizations of one cell of
R = 6 cm for 30 s, and 16 cells of R = 5 cm at an area fraction of 0.35 in a periodic box for
30 s, then animates its first 20 s as an H.264 MP4 into docs/_static/gallery (360 px high,
30 frames/s, real time, constant rate factor 28) with ``softcell.video.animate.animate``, the
function behind ``softcell animate``, and keeps its frame at t = 15 s as a PNG beside this
script.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import softcell
from softcell.model.configuration import RunConfig
from softcell.video.animate import animate

SEED, DURATION = 0, 30.0
CLIP = 20.0  # s of each run in its movie
STILL = 15.0  # s: where the page's still is taken
CROWD_BOX = round(math.sqrt(16 * math.pi * 5.0**2 / 0.35), 1)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--runs", type=Path, help="where the simulations go (kept)")
    args = parser.parse_args(argv)
    runs = args.runs or Path(tempfile.mkdtemp(prefix="softcell-gallery-"))
    one = RunConfig(parameters={"radius": 6.0, "duration": DURATION})
    softcell.simulate(one, runs / "one", realizations=4, seed=SEED)
    crowd = RunConfig(
        parameters={"radius": 5.0, "duration": DURATION}, assembly={"cells": 16, "box": CROWD_BOX}
    )
    softcell.simulate(crowd, runs / "crowd", seed=SEED)
    movies = args.output.parent / "_static" / "gallery"
    movies.mkdir(parents=True, exist_ok=True)
    for name in ("one", "crowd"):
        ds = softcell.open_dataset(runs / name)
        movie = movies / f"{name}.mp4"
        movie.unlink(missing_ok=True)
        animate(ds, movie, fps=30, speed=1.0, end=CLIP, height=360, crf=28)
        still(movie, STILL, args.output / f"{name}.png")


def still(movie: Path, at: float, out: Path) -> None:
    """The frame of ``movie`` at ``at`` seconds of movie time, as a PNG."""
    import av
    import matplotlib.image

    with av.open(str(movie)) as container:
        stream = container.streams.video[0]
        for frame in container.decode(stream):
            if frame.time is not None and frame.time >= at:
                matplotlib.image.imsave(out, frame.to_ndarray(format="rgb24"))
                return
    raise RuntimeError(f"{movie} is shorter than {at} s")


if __name__ == "__main__":
    main()
