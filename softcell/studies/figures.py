"""The studies' figures: ``softcell beyond`` (static friction, the arena) and ``softcell study
sensitivity`` (the paper's unknowns), drawn from their measured values and written atomically.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from softcell.io.files import atomic_write
from softcell.paper.figures import plain_log_ticks


def _save(fig, path: Path, dpi: int) -> None:
    """Write ``fig`` as PNG to ``path`` atomically (a crash leaves no half figure), and close
    it."""
    import matplotlib.pyplot as plt

    with atomic_write(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
    plt.close(fig)


#: Width (in) of every study figure: shown at a docs page's width (about 800 px) its
#: smallest text, 8 pt, is 11 px high.
WIDTH = 8.0


def _grid(plt, panels: int, height: float = 3.1):
    """A figure of ``panels`` axes two to a row, ``WIDTH`` wide and ``height`` (in) a row;
    returns the figure, the panels' axes and the spare axes of an odd count (for a legend,
    its frame and ticks off), or None."""
    rows = (panels + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(WIDTH, height * rows), constrained_layout=True)
    axes = list(np.ravel(axes))
    spare = axes[panels] if len(axes) > panels else None
    if spare is not None:
        spare.set_axis_off()
    return fig, axes[:panels], spare


def _legend_in(spare, ax) -> None:
    """``ax``'s legend in the spare axes of :func:`_grid`."""
    handles, labels = ax.get_legend_handles_labels()
    spare.legend(handles, labels, loc="center", fontsize=9, frameon=False)


def friction_figures(
    folder: Path, variants: Sequence[Any], results: dict[str, Any], free_seconds: float
) -> list[str]:
    """``friction.png`` (<tau_s>, <tau_g> and the shape during stops against R, per
    variant) and ``arena.png`` (the long free-bot MSDs, open floor and arena, with the
    confined-square formula) in ``folder``; returns their names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes, spare = _grid(plt, 3)
    for v in variants:
        r = results[v.name]
        axes[0].plot(r["radius"], r["mean_stop_duration"], "o-", label=v.label)
        axes[1].plot(r["radius"], r["mean_go_duration"], "o-", label=v.label)
        axes[2].plot(r["radius"], np.array(r["ipr_excess_stop"]), "o-", label=v.label)
    axes[0].set(xlabel="R (cm)", ylabel="<tau_s> (s)", title="mean stop duration (cell)")
    axes[1].set(xlabel="R (cm)", ylabel="<tau_g> (s)", title="mean go duration (cell)")
    axes[2].set(
        xlabel="R (cm)", ylabel="IPR - 2 sqrt(pi)", yscale="log", title="shape excess during stops"
    )
    plain_log_ticks(axes[2])
    _legend_in(spare, axes[0])
    _save(fig, folder / "friction.png", dpi=110)

    from softcell.analysis.fits import confined_square_msd

    fig, ax = plt.subplots(figsize=(6, 4.2), constrained_layout=True)
    renewal = results[variants[0].name]["free_renewal_d"]
    long = results.get("free_bot_long", {})
    for name, r in long.items():
        ax.loglog(r["lag"], r["msd"], label=f"free bot, {name} ({free_seconds:g} s runs)")
    if "arena" in long:
        lag = np.asarray(long["arena"]["lag"])
        d = long["arena"]["confined_d"]
        ax.loglog(
            lag,
            confined_square_msd(lag, d, 100.0),
            "k--",
            label=f"confined fit, D = {d:.1f} cm$^2$/s",
        )
        ax.loglog(
            lag,
            confined_square_msd(lag, renewal, 100.0),
            "k:",
            label=f"confined formula at the renewal D = {renewal:.2f}",
        )
        ax.axhline(100.0**2 / 3, color="0.6", lw=0.8, label="L^2 / 3")
    ax.set(xlabel="lag (s)", ylabel="MSD (cm$^2$)", title="free bot: open floor and 1 m arena")
    ax.legend(fontsize=8)
    _save(fig, folder / "arena.png", dpi=120)
    return ["friction.png", "arena.png"]


def _groups(variants: Sequence[Any]) -> dict[str, list[Any]]:
    groups: dict[str, list[Any]] = {}
    for v in variants[1:]:
        groups.setdefault(v.unknown or v.name, []).append(v)
    return groups


#: The figure's rows: (key, axis label, log scale, offset subtracted).
_ROWS = (
    ("mean_go_duration", "<tau_g> (s)", False, 0.0),
    ("gc_distance_ratio", "GC distance / R", False, 0.0),
    ("ipr", "IPR - 2 sqrt(pi)", True, 2 * math.sqrt(math.pi)),
    ("bot_msd_ratio", "bot MSD / free bot's", False, 0.0),
)


def values_figure(
    folder: Path,
    variants: Sequence[Any],
    results: dict[str, dict[str, Any]],
    defaults: dict[str, str],
) -> str:
    """``sensitivity.png`` in ``folder``: per unknown (columns), the measured values against
    R (cm) of every variant beside the reference's, with their standard errors; returns its
    name."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = _groups(variants)
    reference = variants[0]
    fig, axes = plt.subplots(
        len(_ROWS),
        len(groups),
        figsize=(2.9 * len(groups), 9.5),
        sharex=True,
        sharey="row",
        constrained_layout=True,
        squeeze=False,
    )
    for col, (unknown, members) in enumerate(groups.items()):
        for row, (key, ylabel, log, offset) in enumerate(_ROWS):
            ax = axes[row, col]
            for v, style in (
                (reference, dict(color="k", marker="o")),
                *((m, dict(marker="s^v"[j % 3])) for j, m in enumerate(members)),
            ):
                r = results[v.name]
                value = np.asarray(r[key]["value"]) - offset
                ax.errorbar(
                    r["radius"],
                    value,
                    yerr=r[key]["sem"],
                    ms=3.5,
                    lw=1,
                    capsize=2,
                    label=f"{v.label}"
                    if v is not reference
                    else f"default ({defaults.get(unknown, '')})",
                    **style,
                )
            if key == "gc_distance_ratio":
                for level in results[reference.name]["regime_bounds"].values():
                    ax.axhline(level["level"], color="0.6", lw=0.8, ls="--")
            if log:
                ax.set_yscale("log")
            if col == 0:
                ax.set_ylabel(ylabel)
            if row == len(_ROWS) - 1:
                ax.set_xlabel("R (cm)")
        axes[0, col].set_title(unknown, fontsize=10)
        axes[0, col].legend(fontsize=6.5, loc="best")
    fig.suptitle(
        "The quick design over one unknown at a time (error bars: standard error "
        "across realizations)",
        fontsize=10,
    )
    _save(fig, folder / "sensitivity.png", dpi=110)
    return "sensitivity.png"


_VERDICT_CODE = {"agrees": 2, "partly": 1, "differs": 0, "holds by construction": 3}
_VERDICT_TEXT = {2: "agrees", 1: "partly", 0: "differs", 3: "by\nconstruction"}


def verdicts_figure(
    folder: Path, variants: Sequence[Any], results: dict[str, dict[str, Any]]
) -> str:
    """``verdicts.png`` in ``folder``: the verdict per finding (rows) and variant (columns);
    returns its name."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    topics = list(results[variants[0].name]["verdicts"])
    grid = np.array(
        [
            [_VERDICT_CODE.get(results[v.name]["verdicts"].get(t, ""), np.nan) for v in variants]
            for t in topics
        ],
        dtype=float,
    )
    fig, ax = plt.subplots(
        figsize=(max(6.5, 3.5 + 0.75 * len(variants)), 0.9 + 0.42 * len(topics)),
        constrained_layout=True,
    )
    colors = ["#e57373", "#ffb74d", "#81c784", "#90caf9"]
    cmap = ListedColormap(colors).with_extremes(bad="#dddddd")
    ax.imshow(np.ma.masked_invalid(grid), cmap=cmap, vmin=-0.5, vmax=3.5, aspect="auto")
    reference = grid[:, :1]
    for (i, j), code in np.ndenumerate(grid):
        text = _VERDICT_TEXT.get(int(code), "n/m") if np.isfinite(code) else "n/m"
        flipped = (
            j > 0 and not (np.isnan(code) and np.isnan(reference[i, 0])) and code != reference[i, 0]
        )
        ax.text(
            j,
            i,
            text,
            ha="center",
            va="center",
            fontsize=7,
            fontweight="bold" if flipped else "normal",
        )
    ax.set_xticks(
        range(len(variants)), [v.name for v in variants], rotation=40, ha="right", fontsize=8
    )
    ax.set_yticks(range(len(topics)), topics, fontsize=8)
    ax.set_title(
        "verdict per finding and variant\n(bold: not the defaults'; n/m: not measured)", fontsize=9
    )
    _save(fig, folder / "verdicts.png", dpi=110)
    return "verdicts.png"


def _values(points: Sequence[dict[str, Any]], key: str) -> np.ndarray:
    """``key`` of every point as floats, None as NaN."""
    return np.array([np.nan if p[key] is None else p[key] for p in points], dtype=float)


def _rate_line(ax, gap, points, keys, style, bot_gap) -> None:
    """One radius's line of a rate panel: the values with their errors, where no cell
    passed the 95 % limit alone (an open triangle), and its bot width as a dotted line when
    it falls within the grid."""
    key, sem, upper = keys
    value, limit = _values(points, key), _values(points, upper)
    value[np.isfinite(limit)] = np.nan
    ax.errorbar(gap, value, yerr=_values(points, sem), fmt="o-", capsize=3, **style)
    ax.plot(gap, limit, "v", color=style["color"], mfc="none", ms=8)
    if min(gap) <= bot_gap:
        ax.axvline(bot_gap, color=style["color"], ls=":", lw=1)


def constriction_figure(
    path: Path,
    points: Sequence[dict[str, Any]],
    radii: Sequence[float],
    open_gap: float,
    bot_width: float,
) -> str:
    """``softcell study constriction``'s figure at ``path``: (a) passages per 100 s against
    the gap w / 2R, one line per radius, with standard errors across realizations and, where
    no cell passed, the Poisson 95 % upper limit as an open downward triangle (no point);
    the open channel at w / 2R = ``open_gap``; each radius's bot width ``bot_width`` (cm)
    over 2R as a dotted line where it falls within the grid. (b) The same over the open
    channel's rate. (c) The membrane's shape index P / sqrt(A) with the centre in the gap.
    Returns the caption's sentence on the bot widths outside the grid (empty if none)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes, spare = _grid(plt, 3, height=3.4)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    panels = (
        (axes[0], "rate", "rate_sem", "rate_upper_95"),
        (axes[1], "transmission", "transmission_sem", "transmission_upper_95"),
    )
    for i, radius in enumerate(radii):
        mine = [p for p in points if p["radius"] == radius]
        # side by side within a gap, so that equal limits of several radii all show
        gap = _values(mine, "gap") + 0.012 * (i - (len(radii) - 1) / 2)
        style = {"color": colours[i % len(colours)], "label": f"R = {radius:g} cm"}
        for ax, key, sem, upper in panels:
            _rate_line(ax, gap, mine, (key, sem, upper), style, bot_width / (2 * radius))
        axes[2].plot(gap, _values(mine, "shape_index_in_gap"), "o-", **style)
    axes[0].plot([], [], "kv", mfc="none", label="none passed: 95 % upper limit")
    ticks = sorted({p["gap"] for p in points})
    outside = [r for r in radii if bot_width / (2 * r) < ticks[0]]
    if len(outside) < len(radii):
        axes[0].plot([], [], "k:", lw=1, label="bot width 2b / 2R")
    axes[0].plot([], [], color="0.7", lw=0.8, label="w = 2R")
    axes[2].axhline(2 * math.sqrt(math.pi), color="0.5", lw=1, label="circle, 2 sqrt(pi)")
    for ax in axes:
        ax.set_xticks(ticks, [("open" if t >= open_gap else f"{t:g}") for t in ticks])
        ax.set_xlabel("gap w / 2R (open: no partition)")
        ax.axvline(1.0, color="0.7", lw=0.8)
    axes[0].set(ylabel="passages per 100 s", title="(a) how often the cell passes")
    axes[1].set(ylabel="rate / rate with no partition", title="(b) over the rate with no partition")
    for ax in axes[:2]:
        ax.set_ylim(bottom=0)
    axes[2].set(ylabel="shape index P / sqrt(A)", title="(c) shape with the centre in the gap")
    _legend_in(spare, axes[0])
    axes[2].legend(fontsize=8)
    _save(fig, path, dpi=110)
    if not outside:
        return ""
    widths = ", ".join(f"{bot_width / (2 * r):.2g} at R = {r:g} cm" for r in outside)
    return f"The bot's width 2b = {bot_width:g} cm is w / 2R = {widths}: below every gap."


def crowding_figure(path: Path, points: Sequence[dict[str, Any]], radii: Sequence[float]) -> None:
    """``softcell study crowding``'s figure at ``path``: D hat (cm^2/s), <tau_g> (s) and
    the shape index against the area fraction, one line per radius with standard errors
    across realizations; the lone cell (no area fraction) at 0, as an open marker."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes, spare = _grid(plt, 3)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    panels = (
        ("msd_slope", "D hat (cm$^2$/s)", "(a) long-time D hat of the cells"),
        ("mean_go_duration", "<tau_g> (s)", "(b) mean go duration"),
        ("ipr_mean", "shape index P / sqrt(A)", "(c) mean shape index"),
    )
    for i, radius in enumerate(radii):
        c = colours[i % len(colours)]
        mine = [p for p in points if p["radius"] == radius and not p.get("missing")]
        alone = next((p for p in mine if p["fraction"] is None), None)
        crowd = [p for p in mine if p["fraction"] is not None]
        phi = [p["fraction"] for p in crowd]
        for ax, (key, label, title) in zip(axes, panels, strict=True):
            ax.errorbar(
                phi, _values(crowd, key), yerr=_values(crowd, f"{key}_sem"), fmt="o-",
                color=c, capsize=3, label=f"R = {radius:g} cm",
            )  # fmt: skip
            if alone is not None:
                ax.errorbar(
                    [0.0], [alone[key]], yerr=[alone[f"{key}_sem"]], fmt="o", mfc="none",
                    color=c, capsize=3,
                )  # fmt: skip
            ax.set(xlabel="area fraction phi", ylabel=label, title=title)
    axes[0].set_ylim(bottom=0)
    axes[1].set_ylim(bottom=0)
    axes[2].axhline(2 * math.sqrt(math.pi), color="0.5", lw=1, label="circle, 2 sqrt(pi)")
    axes[0].errorbar([], [], fmt="o", mfc="none", color="0.3", label="a lone cell (at phi = 0)")
    _legend_in(spare, axes[0])
    axes[2].legend(fontsize=8)
    _save(fig, path, dpi=110)


def strategies_figure(
    path: Path, points: Sequence[dict[str, Any]], strategies: Sequence[str]
) -> None:
    """``softcell study strategies``'s figure at ``path``: D hat (cm^2/s, log scale),
    <tau_g> and <tau_s> (s) and the shape index against R (cm), one line per strategy with
    standard errors across realizations."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes, _ = _grid(plt, 4)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    panels = (
        ("msd_slope", "D hat (cm$^2$/s)", "(a) long-time D hat of the cell"),
        ("mean_go_duration", "<tau_g> (s)", "(b) mean go duration"),
        ("mean_stop_duration", "<tau_s> (s)", "(c) mean stop duration"),
        ("ipr_mean", "shape index P / sqrt(A)", "(d) mean shape index"),
    )
    for i, strategy in enumerate(strategies):
        mine = [p for p in points if p["strategy"] == strategy and not p.get("missing")]
        radius = [p["radius"] for p in mine]
        for ax, (key, label, title) in zip(axes, panels, strict=True):
            ax.errorbar(
                radius, _values(mine, key), yerr=_values(mine, f"{key}_sem"), fmt="o-",
                color=colours[i % len(colours)], capsize=3, label=strategy,
            )  # fmt: skip
            ax.set(xlabel="membrane radius R (cm)", ylabel=label, title=title)
    axes[0].set_yscale("log")  # the strategies' D hat span three decades
    for ax in axes[1:3]:
        ax.set_ylim(bottom=0)
    axes[3].axhline(2 * math.sqrt(math.pi), color="0.5", lw=1, label="circle, 2 sqrt(pi)")
    axes[0].legend(fontsize=8, loc="center left")
    _save(fig, path, dpi=110)


#: The panels of the bots study's figure: quantity, axis label, title.
BOTS_PANELS = (
    ("boundary_fraction", "fraction", "(a) bots within 2 a of the membrane"),
    ("asphericity", "asphericity", "(b) membrane asphericity"),
    ("polar_order", "|<e^(i theta)>|", "(c) polar order of the bots"),
    ("velocity", "v (cm/s)", "(d) cell's speed v"),
    ("persistence", "tau_p (s)", "(e) cell's persistence time"),
    ("d_hat", "D hat (cm$^2$/s)", "(f) cell's D hat = 2 v$^2$ tau_p"),
)


def bots_figure(path: Path, points: Sequence[dict[str, Any]]) -> None:
    """``softcell study bots``'s figure at ``path``: six quantities against the bots per
    area (cm^-2, log scale), one line per shape and alignment, a marker per radius, with
    standard errors across realizations; the even spread's boundary fraction dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes, _ = _grid(plt, 6, height=2.9)
    axes = np.asarray(axes)
    ran = [p for p in points if not p.get("missing") and not p.get("does_not_fit")]
    kinds = sorted({(p["shape"], p["alignment"] > 0) for p in ran if p["count"] > 1})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    radii = sorted({p["radius"] for p in ran})
    for i, kind in enumerate(kinds):
        for j, radius in enumerate(radii):
            _bots_line(axes, ran, kind, radius, colours[i % len(colours)], _MARKERS[j % 5],
                       first=(i == 0, j == 0))  # fmt: skip
    if len(radii) > 1:
        for j, radius in enumerate(radii):
            axes.flat[1].plot([], [], _MARKERS[j % 5], color="0.3", label=f"R = {radius:g} cm")
        axes.flat[1].legend(fontsize=8)
    ticks: list[float] = []
    for value in sorted({round(p["per_area"], 4) for p in ran}):
        if not ticks or value >= 2.5 * ticks[-1]:  # labels that do not run into each other
            ticks.append(value)
    _bots_axes(axes, ticks)
    _save(fig, path, dpi=110)


_MARKERS = "osD^v"


def _bots_line(axes, ran, kind, radius, colour, marker, first) -> None:
    """One shape and alignment at one radius, in every panel (one bot at its start)."""
    shape, aligned = kind
    line = sorted(
        (p for p in ran
         if p["shape"] == shape and p["radius"] == radius
         and (p["count"] == 1 or (p["alignment"] > 0) == aligned)),
        key=lambda p: p["count"],
    )  # fmt: skip
    x = [p["per_area"] for p in line]
    label = f"{shape}, {'aligned' if aligned else 'free'}" if first[1] else None
    for ax, (key, ylabel, title) in zip(axes.flat, BOTS_PANELS, strict=True):
        ax.errorbar(x, _values(line, key), yerr=_values(line, f"{key}_sem"), fmt=marker + "-",
                    color=colour, capsize=3, label=label, ms=5)  # fmt: skip
        ax.set(xscale="log", xlabel="bots per area, K / pi R$^2$ (cm$^{-2}$)", ylabel=ylabel,
               title=title)  # fmt: skip
    if first[0]:
        axes.flat[0].plot(x, [p["uniform_boundary_fraction"] for p in line], ls="--",
                          color="0.5", lw=1, label="even spread" if first[1] else None)  # fmt: skip


def _bots_axes(axes, ticks) -> None:
    """Plain tick labels at the points' bots per area; every quantity from zero."""
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    for ax in axes.flat:
        ax.set_ylim(bottom=0)
        ax.set_xticks(ticks)
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
    axes.flat[0].legend(fontsize=8)
