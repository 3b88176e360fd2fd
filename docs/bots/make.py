"""The figure, numbers and movie of docs/bots.md's study of several bots in one ring.

    python docs/bots/make.py -o docs/bots [--runs DIR] [--overwrite] [--medium]

Runs ``softcell study bots --quick`` (root seed 0, every core) into DIR (default a temporary
folder; a finished study there is kept, unless made with other code: then ``--overwrite``
recomputes it), copies its ``bots.png`` and ``bots.json`` into the output folder, and
animates the first 20 s of realization 0 of 16 aligned elongated bots (at real time, 20
frames/s, 1 s trails) as an H.264 MP4 in the ``_static/gallery`` folder beside the output
folder, with its last frame as ``bots_frame.png``. With ``--medium``, also runs the medium
design (every radius, up to 32 elongated bots) into DIR/medium and copies its ``bots.png``
and ``bots.json`` as ``bots_medium.png`` and ``bots_medium.json``.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

import softcell
from softcell.studies.bots import MEDIUM, QUICK, bots
from softcell.video.animate import animate

SEED = 0
MOVIE_POINT = "R12_elongated_K16_aligned"
END = 20.0


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--runs", type=Path, help="where the study goes (kept)")
    parser.add_argument(
        "--overwrite", action="store_true", help="recompute runs in DIR made with other code"
    )
    parser.add_argument("--medium", action="store_true", help="the medium design too")
    args = parser.parse_args(argv)
    runs = args.runs or Path(tempfile.mkdtemp(prefix="softcell-bots-"))
    bots(runs, design=QUICK, seed=SEED, overwrite=args.overwrite)
    args.output.mkdir(parents=True, exist_ok=True)
    for name in ("bots.png", "bots.json"):
        shutil.copyfile(runs / name, args.output / name)
    ds = softcell.open_dataset(runs / MOVIE_POINT / "point000_realization0000.nc")
    ds = ds.sel(time=slice(0, END), fine_time=slice(0, END))  # the window fits these 20 s
    movie = args.output.parent / "_static" / "gallery" / "bots.mp4"
    animate(ds, movie, realizations=[0], fps=20, trail=1.0, height=600, progress=False)
    _last_frame(movie, args.output / "bots_frame.png")
    if args.medium:
        bots(runs / "medium", design=MEDIUM, seed=SEED, overwrite=args.overwrite)
        for name in ("bots.png", "bots.json"):
            target = name.replace("bots", "bots_medium")
            shutil.copyfile(runs / "medium" / name, args.output / target)
    print(f"wrote {args.output} and {movie}")


def _last_frame(movie: Path, png: Path) -> None:
    import av

    with av.open(str(movie)) as container:
        frames = list(container.decode(video=0))
    frames[-1].to_image().save(png)


if __name__ == "__main__":
    main()
