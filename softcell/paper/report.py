"""The reproduction report: what ran, every figure, the paper's findings beside ours.

:func:`write_report` reads the files :func:`softcell.paper.reproduce.reproduce` wrote and writes
``report.md`` and ``report.html`` (the same content; the HTML needs no stylesheet or script
beyond its own). The findings of the paper beside ours come from
:func:`softcell.paper.findings.findings`.
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Sequence
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.io.files import atomic_files, json_text
from softcell.io.pages import Block, html_page, markdown
from softcell.paper.findings import findings
from softcell.schema import REGIME_NAMES

# ---------------------------------------------------------------------------------------------
# The report
# ---------------------------------------------------------------------------------------------

CAPTIONS = {
    "fig2": "Fig. 2. Trajectories of the bot and the cell GC at R = 4 cm (a) and 12 cm (b) "
    "over 60 s of one realization from the end of the discarded start, their speeds over the "
    "first 10 s of it (c, d), the cell MSD for every R with its standard error (e), and the "
    "best scaling collapse of the decoupled radii (f). Backgrounds: the regime of the radius "
    "(purple coupled, pink intermediate, green decoupled).",
    "fig3": "Fig. 3. (a) Cell speed at R = 12 cm over 30 s, stops shaded grey, time average "
    "dashed; PDFs of go (b) and stop (c) durations over their mean for R >= 6 cm (the "
    "tracked video's as triangles); (d) <tau_g> and <tau_s> against R, regimes "
    "shaded (purple coupled, pink intermediate, green decoupled). The paper's (b) holds both "
    "PDFs.",
    "fig4": "Fig. 4. Theory against fits of the cell MSD: (a) ballistic velocity (filled "
    "circles) and v0 hat (open squares), (b) fitted MSD slope and D hat = 2 v0_hat^2 <tau_g>; "
    "the tracked video's values (triangles) are from its analysed span, stated in the legend.",
    "figS1": "Fig. S1 (the paper's panel b). MSD of the free bot and of the bot inside "
    "membranes of every R, with standard errors.",
    "figS2": "Fig. S2. Simulated PDFs of go (a) and stop (b) durations t' = tau / <tau> over "
    "their mean, every R, against exp(-t').",
    "figS3": "Fig. S3 (the paper's panel b). MSD of the bot and the cell at R = 12 cm, with "
    "standard errors; the background is the radius's regime (green: decoupled).",
    "figT": "Beyond the paper. (a) The cell's velocity autocorrelation C(tau) / C(0) at three "
    "radii, measured (solid, standard error shaded) and the renewal theory's for the measured "
    "go durations (dotted: zero beyond the longest go phase); (b) the cell MSD over the renewal "
    "theory's (solid) and over the exponential theory's (dashed), every R; (c) the mean cosine "
    "between consecutive go displacements (0 in both theories).",
}

#: The free bot tumbling about a pivot off its centre (pivot_run_and_tumble), by folder:
#: the pivot offset (cm) of the paper's robot and of its published digital twin.
PIVOTS = {"free_bot_pivot1": 1.0, "free_bot_pivot1.53": 1.53}


def _fmt(x: float, digits: int = 3) -> str:
    return "nan" if not np.isfinite(x) else f"{x:.{digits}g}"


def _per_radius(analysis: xr.Dataset) -> Block:
    """The cell's numbers per radius, each ± its standard error across realizations."""
    header = [
        "R (cm)",
        "regime",
        "GC distance / R",
        "<tau_g> (s)",
        "<tau_s> (s)",
        "ballistic v (cm/s)",
        "v0 hat (cm/s)",
        "D hat, affine fit (cm2/s)",
        "D hat theory (cm2/s)",
        "go phases",
        "shape index P/sqrt(A)",
    ]
    rows = []
    for i, r in enumerate(analysis["radius"].values):
        point = analysis.isel(radius=i)
        a = point.sel(body="cell")

        def pm(source: xr.Dataset, name: str, digits: int = 3) -> str:
            value, error = float(source[name]), float(source[f"{name}_error"])
            text = _fmt(value, digits)
            return text if not np.isfinite(error) else f"{text} ± {error:.2g}"

        rows.append(
            [
                f"{r:g}",
                REGIME_NAMES[int(analysis["regime"].values[i])],
                pm(point, "gc_distance_ratio", 2),
                pm(a, "mean_go_duration"),
                pm(a, "mean_stop_duration"),
                pm(a, "ballistic_velocity"),
                pm(a, "v0_hat"),
                pm(a, "msd_slope_affine"),
                pm(a, "msd_slope_theory"),
                str(int(a.go_events)),
                pm(point, "ipr_mean", 4),
            ]
        )
    return Block("table", (header, rows))


def _video_blocks(out: Path, video: dict[str, Any]) -> list[Block]:
    from softcell.io.netcdf import read_dataset

    folder = out / "video"
    sets = [
        ("tracked video, 0.3 cm/s", read_dataset(folder / "tracked_analysis.nc")),
        ("simulation, same span, 0.3 cm/s", read_dataset(folder / "simulated_analysis_0.3.nc")),
        ("simulation, same span, 0.03 cm/s", read_dataset(folder / "simulated_analysis.nc")),
    ]
    quantities = [
        ("mean cell speed (cm/s)", "mean_speed"),
        ("v0 hat (cm/s)", "v0_hat"),
        ("<tau_g> (s)", "mean_go_duration"),
        ("<tau_s> (s)", "mean_stop_duration"),
        ("go phases", "go_events"),
        ("ballistic v (cm/s)", "ballistic_velocity"),
    ]
    rows = [
        [label] + [_fmt(float(ds[name].sel(body="cell"))) for _, ds in sets]
        for label, name in quantities
    ]
    shifted = sets[0][1]
    moves = []
    for kind in ("go", "stop"):
        m = np.asarray(shifted[f"mean_{kind}_duration_shifted"].sel(body="cell").values)
        moves.append(f"<tau_{kind[0]}>: {_fmt(m[0])} / {_fmt(m[1])} / {_fmt(m[2])} s")
    summary = ", ".join(f"{k} {v}" for k, v in video["tracking_summary"].items())
    notes = video.get("notes", [])
    return [
        Block("h2", "The experimental pipeline"),
        Block(
            "p",
            f"As the paper sets experiments beside simulations, realization 0 at "
            f"R = {video['radius']:g} cm ({video['source']}) was filmed from "
            f"t = {video['span'][0]:g} s to {video['span'][1]:g} s as the paper's "
            f"camera would ({video['design']['fps']:g} frames/s, "
            f"{video['design']['px_per_cm']:g} px/cm, {video['size_px'][0]}x"
            f"{video['size_px'][1]} px, Gaussian noise {video['design']['noise']:g} grey "
            f"levels, blur {video['design']['blur']:g} px, noise seed "
            f"{video['noise_seed']}), tracked with the paper's contour tracker and "
            "analysed with the experiments' threshold. Tracking outcome per frame: "
            f"{summary}.",
        ),
        Block("table", (["quantity", *[name for name, _ in sets]], rows)),
        Block(
            "p",
            "The experiments' threshold moved by -0.1 / 0 / +0.1 cm/s moves the tracked "
            "means to " + "; ".join(moves) + " (the paper: they barely move).",
        ),
        *([Block("p", "About the film: " + "; ".join(notes) + ".")] if notes else []),
    ]


def _tracked(out: Path, video: dict[str, Any] | None):
    """The analysis of the tracked film, when the reproduction made one."""
    from softcell.io.netcdf import read_dataset

    path = out / "video" / "tracked_analysis.nc"
    return read_dataset(path) if video is not None and path.exists() else None


def _findings_blocks(rows) -> list[Block]:
    """The findings table, then the rule of each verdict."""
    return [
        Block("h2", "Findings: the paper beside this run"),
        Block(
            "table",
            (
                ["finding", "paper", "measured here (± standard error)", "verdict", "cause"],
                [[f.topic, f.paper, f.measured, f.verdict, f.cause or "-"] for f in rows],
            ),
        ),
        Block(
            "p",
            "Errors are standard errors from a bootstrap over realizations (resampled "
            "within each radius, seeded by the run's seed). Each verdict follows the rule "
            "below; 'holds by construction' marks a finding that follows from how it is "
            "measured, whatever the physics.",
        ),
        Block("table", (["finding", "verdict rule"], [[f.topic, f.rule] for f in rows])),
    ]


def _pivots(out: Path) -> dict[float, Any]:
    """The free bot's analyses tumbling about a pivot, by its offset (cm), that ``out``
    holds."""
    from softcell.io.netcdf import read_dataset

    return {
        offset: read_dataset(out / f"{folder}_analysis.nc")
        for folder, offset in PIVOTS.items()
        if (out / f"{folder}_analysis.nc").exists()
    }


def write_report(
    out: str | os.PathLike[str],
    *,
    design,
    seed: int,
    steps: dict[str, float],
    notes: Sequence[str],
    figures,
    video: dict[str, Any] | None,
) -> tuple[Path, Path]:
    """Write ``out/report.md`` and ``out/report.html`` from the files of a reproduction.

    Also writes ``out/findings.json``: the findings table as a list of objects.

    Returns
    -------
    (Path, Path)
        The Markdown and HTML reports.
    """
    from softcell.io.netcdf import read_dataset

    out = Path(out)
    analysis = read_dataset(out / "analysis.nc")
    free_path = out / "free_bot_analysis.nc"
    free_bot = read_dataset(free_path) if free_path.exists() else None
    params = json.loads(analysis.attrs["softcell_parameters"])
    units = json.loads(analysis.attrs.get("softcell_parameter_units", "{}"))
    components = json.loads(analysis.attrs.get("softcell_components", "{}"))
    options = json.loads(analysis.attrs["softcell_analysis_options"])
    command = f"softcell reproduce --{design.name} -o {out} --seed {seed}"
    contact_path = out / "contact.nc"
    contact = read_dataset(contact_path) if contact_path.exists() else None
    rows = findings(analysis, free_bot, seed, _tracked(out, video), contact, _pivots(out))

    blocks = [
        Block("h1", 'softcell: reproduction of "Run and tumble dynamics of a soft robotic cell"'),
        Block(
            "p",
            f"softcell {__version__}, {datetime.now(UTC):%Y-%m-%d %H:%M} UTC, "
            f"{platform.python_implementation()} {platform.python_version()} on "
            f"{platform.machine()} with {os.cpu_count()} cores.",
        ),
        Block("code", command),
        Block(
            "p",
            f"Design '{design.name}': {design.describe()}. What ran, in full, and every "
            "parameter follow the figures.",
        ),
        *_findings_blocks(rows),
        Block("h2", "Per radius (cell GC)"),
        _per_radius(analysis),
        Block(
            "p",
            "Errors are standard errors across realizations (a bootstrap over them). The "
            "shape index is the membrane's perimeter over the square root of its area, "
            "averaged over samples and realizations: 2 sqrt(pi) = 3.545 for a circle, larger "
            "the more the membrane departs from one (the paper's IPR).",
        ),
    ]
    if video is not None:
        blocks += _video_blocks(out, video)
    blocks.append(Block("h2", "Figures"))
    for name, files in figures.files.items():
        by_suffix = {p.suffix: p.relative_to(out).as_posix() for p in files}
        blocks.append(
            Block(
                "figure",
                (by_suffix.get(".png", ""), by_suffix.get(".pdf", ""), CAPTIONS.get(name, name)),
            )
        )
    for name, why in figures.skipped.items():
        blocks.append(Block("p", f"{name} was not drawn: {why}."))
    blocks += [
        Block("h2", "What ran"),
        Block(
            "list",
            [
                f"Design '{design.name}': {design.describe()}."
                + (f" {design.caveat}" if design.caveat else ""),
                f"Components: {', '.join(f'{k} = {v}' for k, v in components.items())}.",
                f"Seed {seed}: realization r of radius index p draws from SeedSequence({seed}, "
                "spawn_key=(p, r)); the free bot's realization r uses (0, r), so it shares its "
                "drive schedule with realization r at the smallest radius.",
                "Analysis options: " + ", ".join(f"{k} = {v}" for k, v in sorted(options.items())),
                "Wall time per step: " + ", ".join(f"{k} {v:.0f} s" for k, v in steps.items()),
                *notes,
            ],
        ),
        Block(
            "p",
            "Parameters (every file also carries them, with the seed, the component "
            "names and the package version):",
        ),
        Block(
            "table",
            (
                ["parameter", "value", "unit"],
                [
                    [k, json.dumps(v) if isinstance(v, list) else str(v), units.get(k, "")]
                    for k, v in sorted(params.items())
                ],
            ),
        ),
    ]
    md, page = out / "report.md", out / "report.html"
    title = "softcell reproduction report"
    summary = json_text(
        {
            "softcell_version": __version__,
            "design": design.name,
            "seed": seed,
            "findings": [asdict(f) for f in rows],
        },
        indent=1,
    )
    with atomic_files() as staging:
        for path, text in (
            (md, markdown(blocks)),
            (page, html_page(blocks, title)),
            (out / "findings.json", summary),
        ):
            staging.path(path).write_text(text, encoding="utf-8")
    return md, page
