"""The verbs of videos: ``render`` (a simulation filmed), ``track`` (a film into the schema),
``animate`` (a movie to watch) and ``export`` (GSD for OVITO, movement's poses dataset)."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from softcell.cli import flags
from softcell.errors import SchemaError, SoftcellError


def _add_render(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="simulation file or sweep directory")
    flags.output(p, "video: .mkv/.avi (lossless, for tracking) or .mp4")
    flags.overwrite(p, "replace an existing video")
    p.add_argument("--realization", type=int, default=0)
    p.add_argument("--point", help="sweep point, e.g. radius=1 (an index)")
    p.add_argument("--px-per-cm", type=float, default=10.0, help="scale [px/cm] (default 10)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--size", help="frame size WIDTHxHEIGHT [px] (default: fits the cell)")
    p.add_argument("--start", type=float, help="first frame time [s]")
    p.add_argument("--end", type=float, help="last frame time [s]")
    p.add_argument("--noise", type=float, default=0.0, help="Gaussian noise [grey levels]")
    p.add_argument("--blur", type=float, default=0.0, help="Gaussian blur [px]")
    p.add_argument(
        "--illumination", type=float, default=0.0, help="relative amplitude of uneven illumination"
    )
    flags.seed(p, "seed of the noise")
    p.add_argument("--no-head-mark", action="store_true", help="no mark at the bot's head")
    flags.no_verify(p)
    flags.quiet(p)
    p.set_defaults(func=_cmd_render)


def _cmd_render(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs, read_failure
    from softcell.model.limits import check_seed
    from softcell.schema import validate
    from softcell.video.render import parse_point, parse_size, render

    check_seed(args.seed)  # before anything is read
    check_output(args.output, "video", inputs=[args.input], overwrite=args.overwrite)
    ds = open_inputs([args.input], verify=args.verify)
    point = parse_point(args.point, "--point") if args.point else {}
    size = parse_size(args.size, "--size") if args.size else None
    try:
        validate(ds)
    except SchemaError as exc:
        raise SoftcellError(f"{args.input} cannot be rendered: {exc}") from None
    if "cell" in ds.dims:
        raise SoftcellError(
            f"{args.input} is an assembly of {ds.sizes['cell']} cells: render films one cell "
            "(the camera's view of the paper's experiments)"
        )
    try:
        info = render(
            ds,
            args.output,
            realization=args.realization,
            point=point,
            px_per_cm=args.px_per_cm,
            fps=args.fps,
            size=size,
            start=args.start,
            end=args.end,
            noise=args.noise,
            blur=args.blur,
            illumination=args.illumination,
            seed=args.seed,
            head_mark=not args.no_head_mark,
            progress=not args.quiet,
        )
    except (OSError, RuntimeError) as exc:  # netCDF's "HDF error" names no file
        raise read_failure([args.input], exc) from None
    for note in info.notes:
        print(f"note: {note}")
    print(
        f"{info.times.size} frames of {info.frame.width}x{info.frame.height} px written to "
        f"{info.path}; lower-left corner at {info.frame.x0:.6f},{info.frame.y0:.6f} cm "
        f"(track it with --px-per-cm {info.frame.px_per_cm:g} "
        f"--origin={info.frame.x0:.6f},{info.frame.y0:.6f})"
    )
    return 0


def _add_track(p: argparse.ArgumentParser) -> None:
    p.add_argument("video", type=Path)
    flags.output(p, "tracked file (.nc)")
    flags.overwrite(p, "replace an existing file that is not a softcell tracking file")
    p.add_argument("--px-per-cm", type=float, help="scale [px/cm]")
    p.add_argument(
        "--arena-size", type=float, help="world width of the frame [cm], to derive the scale"
    )
    p.add_argument("--origin", help="world position X,Y [cm] of the lower-left corner")
    camera = p.add_argument_group(
        "camera",
        "calibrate from the plate seen in the first frame (perspective, lens, "
        "parallax) instead of a linear scale; positions in plate coordinates, origin "
        "at the plate corner seen at the lower left",
    )
    camera.add_argument("--plate-size", type=float, help="side of the square plate [cm]")
    camera.add_argument(
        "--camera",
        type=Path,
        help="OpenCV calibration file (camera_matrix, distortion_coefficients)",
    )
    camera.add_argument(
        "--camera-height",
        type=float,
        help="camera height above the plate [cm] (default: from --camera, or "
        "estimated from the plate when the camera is tilted)",
    )
    camera.add_argument(
        "--ring-height",
        type=float,
        default=0.0,
        help="height of the membrane's wall [cm] (parallax; default 0)",
    )
    camera.add_argument(
        "--bot-height", type=float, default=0.0, help="height of the bot [cm] (parallax; default 0)"
    )
    p.add_argument(
        "--ring-color",
        default="red",
        help="the paper's colour: red (also orange), green, blue, yellow",
    )
    p.add_argument(
        "--ring-threshold",
        type=float,
        help="colourfulness of paper, (R - max(G, B)) / R for red (default: per frame)",
    )
    p.add_argument(
        "--dark-fraction",
        type=float,
        default=0.5,
        help="bot pixels are darker than this fraction of the plate (default 0.5)",
    )
    p.add_argument(
        "--overlay",
        type=Path,
        help="also write the frames with what was tracked drawn on them (.mkv/.avi/.mp4)",
    )
    p.add_argument("--fps", type=float, help="frame rate [1/s] (default: the file's)")
    p.add_argument("--nodes", type=int, default=64, help="membrane points (default 64)")
    p.add_argument(
        "--radius",
        type=float,
        help="membrane radius R [cm]: expected perimeter 2 pi R (default: learned)",
    )
    flags.quiet(p)
    p.set_defaults(func=_cmd_track)


def _cmd_track(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output, no_input
    from softcell.io.netcdf import write_dataset
    from softcell.video.track import codec, parse_origin, track

    origin = parse_origin(args.origin, "--origin") if args.origin else (0.0, 0.0)
    if not args.video.is_file():
        raise no_input(args.video, "video file")
    check_output(args.output, "tracking", inputs=[args.video], overwrite=args.overwrite)
    if args.overlay is not None:
        if os.path.abspath(args.overlay) == os.path.abspath(args.output):
            raise SoftcellError(
                f"--overlay {args.overlay} is the tracked file -o: give another name"
            )
        codec(args.overlay)  # a video suffix, or a clear error
        check_output(
            args.overlay, "video", inputs=[args.video], overwrite=args.overwrite, option="--overlay"
        )
    ds = track(
        args.video,
        px_per_cm=args.px_per_cm,
        arena_size=args.arena_size,
        origin=origin,
        plate_size=args.plate_size,
        camera=args.camera,
        camera_height=args.camera_height,
        ring_height=args.ring_height,
        bot_height=args.bot_height,
        ring_color=args.ring_color,
        ring_threshold=args.ring_threshold,
        dark_fraction=args.dark_fraction,
        fps=args.fps,
        nodes=args.nodes,
        radius=args.radius,
        overlay=args.overlay,
        progress=not args.quiet,
    )
    path = write_dataset(ds, args.output)
    print(
        f"{ds.sizes['time']} frames tracked, {ds.attrs['softcell_tracking_summary']}, "
        f"written to {path}"
    )
    failures = json.loads(ds.attrs["softcell_tracking_failures"])
    for reason, count in failures.items():
        print(f"  {count} frame(s) lost: {reason}")
    if args.overlay is not None:
        print(f"overlay written to {args.overlay}")
    return 0


def _add_animate(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="simulation file or directory")
    flags.output(p, "movie: .mp4 (H.264) or .gif (slides)")
    flags.overwrite(p, "replace an existing movie")
    p.add_argument(
        "--realizations",
        help="realizations side by side, e.g. 0,1,2 (default: the first up to 4; one for an "
        "assembly, all its cells in one panel)",
    )
    p.add_argument("--point", help="sweep point, e.g. radius=1 (an index)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument(
        "--speed", type=float, default=1.0, help="simulated seconds per movie second (default 1)"
    )
    p.add_argument("--start", type=float, default=0.0, help="first frame time [s] (default 0)")
    p.add_argument("--end", type=float, help="last frame time [s] (default: the record's end)")
    p.add_argument("--trail", type=float, default=5.0, help="trail length [s] (default 5)")
    p.add_argument("--height", type=int, default=480, help="frame height [px] (default 480)")
    p.add_argument(
        "--crf",
        type=int,
        default=20,
        help="H.264 quality: 0 lossless .. 51 smallest (default 20; 28 for the web)",
    )
    flags.no_verify(p)
    flags.quiet(p)
    p.set_defaults(func=_cmd_animate)


def _cmd_animate(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs
    from softcell.video.animate import animate
    from softcell.video.render import check_point, parse_point

    check_output(args.output, "video", inputs=[args.input], overwrite=args.overwrite)
    realizations = None
    if args.realizations:
        try:
            realizations = [int(v) for v in args.realizations.split(",")]
        except ValueError:
            raise SoftcellError(
                f"--realizations {args.realizations} is not allowed: must be indices, e.g. 0,1"
            ) from None
        flags.distinct("--realizations", realizations)
    point = parse_point(args.point, "--point") if args.point else {}
    ds = open_inputs([args.input], verify=args.verify)
    check_point(ds, point, "--point")
    ds = ds.isel(point)
    movie = animate(
        ds,
        args.output,
        realizations=realizations,
        fps=args.fps,
        speed=args.speed,
        start=args.start,
        end=args.end,
        trail=args.trail,
        height=args.height,
        crf=args.crf,
        progress=not args.quiet,
    )
    print(
        f"{movie.path}: {movie.frames} frames at {movie.fps:g}/s, {movie.size[0]}x"
        f"{movie.size[1]} px, t = {movie.span[0]:g} .. {movie.span[1]:.6g} s"
    )
    return 0


def _add_export(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "input", type=Path, help="simulation or tracking file, or a folder of one point's files"
    )
    flags.output(p, "trajectory: .gsd, or .nc for movement")
    p.add_argument(
        "--to",
        choices=["gsd", "movement"],
        help="gsd (OVITO, freud, MDAnalysis; a simulation) or movement's poses dataset "
        "(netCDF; a tracked video or a simulation); default: from the output's suffix",
    )
    flags.overwrite(p, "replace an existing file softcell did not export")
    p.add_argument(
        "--realization", type=int, help="which realization (needed when the input holds several)"
    )
    p.add_argument(
        "--every", type=int, default=1, help="gsd: write every N-th stored sample (default 1)"
    )
    flags.no_verify(p)
    p.set_defaults(func=_cmd_export)


def _export_format(args: argparse.Namespace) -> str:
    """``--to``, or the format the output's suffix names; refused in one line when neither
    says."""
    suffix = args.output.suffix.lower()
    implied = {".gsd": "gsd", ".nc": "movement"}.get(suffix)
    if args.to is None and implied is None:
        raise SoftcellError(
            f"-o {args.output}: give a .gsd (GSD) or .nc (movement) file, or --to gsd|movement"
        )
    to = args.to or implied
    if to == "movement" and args.every != 1:
        raise SoftcellError("--every belongs to --to gsd; movement keeps every sample")
    return to


def _cmd_export(args: argparse.Namespace) -> int:
    from softcell.io.export import check_gsd_path, to_gsd, to_movement
    from softcell.io.files import check_output, no_input
    from softcell.io.netcdf import open_inputs

    if not args.input.exists():
        raise no_input(args.input, "simulation or tracking file")
    to = _export_format(args)
    if to == "gsd":
        check_gsd_path(args.output)
    check_output(args.output, "export", inputs=[args.input], overwrite=args.overwrite)
    with open_inputs([args.input], verify=args.verify) as ds:
        if to == "gsd":
            done = to_gsd(ds, args.output, realization=args.realization, every=args.every)
        else:
            done = to_movement(ds, args.output, realization=args.realization)
    what = "particles" if to == "gsd" else "keypoints x individuals"
    print(
        f"{done.path}: {done.frames} frames of {done.particles} {what}, "
        f"t = {done.span[0]:g} .. {done.span[1]:.6g} s"
    )
    return 0


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "render": ("a top-view movie of one simulated realization", _add_render),
    "animate": (
        "a movie to watch (MP4 or GIF): realizations side by side, or an assembly's cells, "
        "with trails, stop and go",
        _add_animate,
    ),
    "export": (
        "a simulation as a GSD trajectory (OVITO, freud, MDAnalysis), or a tracked video or "
        "simulation as movement's poses dataset (napari)",
        _add_export,
    ),
    "track": ("track a top-view video into the simulation schema", _add_track),
}
