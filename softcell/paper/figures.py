"""The paper's figures, panel for panel, from analysis Datasets (PNG and PDF, cm and s).

:func:`make_figures` draws Fig. 2 (trajectories, speeds, MSD, scaling collapse), Fig. 3 (stop
and go: a shaded speed series, PDFs, mean durations against R), Fig. 4 (theory against fits),
S1 (free bot against bot in the membrane), S2 (simulated PDFs) and S3 (bot and cell MSD at
R = 12 cm). The inputs are the analysis of a radius sweep and, for the panels that need them,
the sweep's simulation Dataset (trajectories), the free bot's analysis (S1) and the analysis
of a tracked video (the experiments' markers). A figure whose input is missing is not drawn,
and :class:`FigureSet` says which and why.

Backgrounds follow the paper: purple for the coupled regime, pink for the intermediate one,
green for the decoupled one (from the analysis's ``regime``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from softcell.errors import SoftcellError
from softcell.io.files import atomic_files
from softcell.schema import REGIME_NAMES

#: Background colour of each regime (``regime`` flag value), as in the paper.
REGIME_COLORS = {0: "#b39ddb", 1: "#f8bbd0", 2: "#a5d6a7"}
SIM_COLOR, EXP_COLOR = "#00acc1", "#fb8c00"  # cyan circles, orange triangles (Fig. 3c)
FORMATS = ("png", "pdf")


#: Figures :func:`make_figures` may write, each in every format of :data:`FORMATS`.
FIGURES = ("fig2", "fig3", "fig4", "figS1", "figS2", "figS3", "figT")
#: The figures that show a tracked video's markers.
WITH_TRACKED = ("fig3", "fig4")


@dataclass
class FigureSet:
    """What :func:`softcell.make_figures` wrote.

    Attributes
    ----------
    files : dict
        The files written, by figure name (``"fig2"``: its PNG and PDF paths).
    skipped : dict
        The figures left out, by name, with the reason (an input missing).
    """

    files: dict[str, list[Path]] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)

    def update(self, other: FigureSet) -> None:
        """Add ``other``'s files and skipped figures, in the order of ``FIGURES``."""
        files, skipped = {**self.files, **other.files}, {**self.skipped, **other.skipped}
        self.files = {k: files[k] for k in FIGURES if k in files}
        self.skipped = {k: skipped[k] for k in FIGURES if k in skipped}


def _figure(width: float, height: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _radius_index(analysis: xr.Dataset, radius: float) -> int | None:
    if "radius" not in analysis.dims:
        return None
    radii = analysis["radius"].values
    i = int(np.argmin(np.abs(radii - radius)))
    return i if abs(radii[i] - radius) < 1e-9 else None


def _regime_at(analysis: xr.Dataset, i: int) -> int:
    return int(analysis["regime"].values[i])


def _shade_regimes(ax, analysis: xr.Dataset) -> None:
    """Shade each radius's slot of an R axis with its regime's colour, each regime named
    once for the legend."""
    radii = analysis["radius"].values
    edges = np.concatenate([[radii[0] - 0.5], 0.5 * (radii[1:] + radii[:-1]), [radii[-1] + 0.5]])
    named = set()
    for k, regime in enumerate(int(r) for r in analysis["regime"].values):
        if regime in REGIME_COLORS:
            ax.axvspan(edges[k], edges[k + 1], color=REGIME_COLORS[regime], alpha=0.35, lw=0,
                       label=None if regime in named else REGIME_NAMES[regime])  # fmt: skip
            named.add(regime)
    ax.set_xlim(edges[0], edges[-1])


def _background(ax, regime: int) -> None:
    if regime in REGIME_COLORS:
        ax.set_facecolor(REGIME_COLORS[regime] + "55")


def _radius_colors(radii: np.ndarray):
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    span = max(float(radii.max() - radii.min()), 1e-12)
    return [cmap(0.9 * (r - radii.min()) / span) for r in radii]


def _radius_dashes(radii: np.ndarray) -> list[str]:
    """Line styles alternating solid and dashed along the radii: neighbours whose colours
    are close (the greens and yellows of R >= 10 cm) still tell apart."""
    return ["-" if k % 2 == 0 else "--" for k in range(len(radii))]


def _label(ax, letter: str) -> None:
    ax.set_title(f"({letter})", loc="left", fontsize=10, fontweight="bold")


def _msd_axes(ax) -> None:
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"$\tau$ (s)")
    ax.set_ylabel(r"$\Delta$ (cm$^2$)")


def _trajectory(ax, simulations: xr.Dataset, radius: float, span: float, analysis) -> None:
    sel = simulations.sel(radius=radius).isel(realization=0)
    t = np.asarray(sel["time"].values)
    t0 = t[0] + float(json_option(analysis, "discard"))
    use = (t >= t0) & (t <= t0 + span) & np.isfinite(np.asarray(sel["cell_x"].values))
    for body, color in (("bot", "0.35"), ("cell", "C3")):
        ax.plot(
            np.asarray(sel[f"{body}_x"].values)[use],
            np.asarray(sel[f"{body}_y"].values)[use],
            color=color,
            lw=0.8,
            label=f"{body} GC" if body == "cell" else "bot",
        )
    first = int(np.argmax(use))
    ax.plot(
        np.append(sel["membrane_x"].values[first], sel["membrane_x"].values[first][0]),
        np.append(sel["membrane_y"].values[first], sel["membrane_y"].values[first][0]),
        color="C3",
        lw=0.6,
        ls=":",
        label=f"membrane at t = {t[first]:.0f} s",
    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.legend(fontsize=7, loc="best")


def json_option(analysis: xr.Dataset, name: str):
    """An analysis option stored in the analysis file (``softcell_analysis_options``)."""
    return json.loads(analysis.attrs["softcell_analysis_options"])[name]


def _speed_series(
    ax, analysis: xr.Dataset, i: int, span: float, bodies=("bot", "cell"), shade: bool = False
) -> None:
    point = analysis.isel(radius=i, realization=0)
    t = np.asarray(analysis["time"].values)
    dt = np.diff(t)
    fine = np.flatnonzero(np.isclose(dt, dt.min()))
    use = np.zeros(t.size, dtype=bool)
    use[fine[0] : fine[0] + int(round(span / dt.min())) + 1] = True
    for body, color in zip(bodies, ("0.35", "C3"), strict=False):
        s = np.asarray(point["speed"].sel(body=body).values)
        ax.plot(t[use], s[use], color=color, lw=0.7, label=f"{body}")
    if shade:
        lab = np.asarray(point["stopgo_label"].sel(body=bodies[-1]).values)[use]
        tt = t[use]
        stop = lab == 0
        edges = np.flatnonzero(np.diff(np.concatenate([[0], stop.astype(int), [0]])))
        for a, b in zip(edges[::2], edges[1::2], strict=True):
            ax.axvspan(tt[a], tt[min(b, tt.size - 1)], color="0.8", lw=0)
        mean = float(np.nanmean(np.asarray(point["speed"].sel(body=bodies[-1]).values)))
        ax.axhline(mean, color="red", ls="--", lw=1, label="time average")
    ax.set_xlim(t[use][0], t[use][-1])
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|v| (cm/s)")
    # Room above the data for the legend: it never covers a speed spike.
    ax.set_ylim(0, 1.3 * np.nanmax(ax.get_ylim()[1]))
    ax.legend(fontsize=7, loc="upper right", ncol=3)


def _band(ax, lag: np.ndarray, msd: np.ndarray, sem: np.ndarray, color) -> None:
    """The MSD's standard error as a shaded band (clipped above 0 for the log axis)."""
    low = np.maximum(msd - sem, msd * 1e-3)
    ax.fill_between(lag, low, msd + sem, color=color, alpha=0.25, lw=0)


def _msd_all(ax, analysis: xr.Dataset, body: str = "cell") -> None:
    radii = analysis["radius"].values
    lag = analysis["lag"].values
    for r, color, ls in zip(radii, _radius_colors(radii), _radius_dashes(radii), strict=True):
        m = analysis["msd"].sel(radius=r, body=body).values
        ax.plot(lag, m, color=color, ls=ls, lw=1, label=f"R = {r:g} cm")
        _band(ax, lag, m, analysis["msd_sem"].sel(radius=r, body=body).values, color)
    _msd_axes(ax)
    ax.legend(fontsize=7, ncol=2)


def _collapse(ax, analysis: xr.Dataset) -> str:
    metric = analysis["collapse_metric"].values
    if not np.isfinite(metric).any():
        ax.text(
            0.5,
            0.5,
            "fewer than two decoupled radii:\nno collapse",
            ha="center",
            transform=ax.transAxes,
        )
        return "none"
    exponents = list(
        zip(
            analysis["collapse_msd_exponent"].values,
            analysis["collapse_lag_exponent"].values,
            strict=True,
        )
    )
    best = int(np.nanargmin(metric))
    # The paper's pair (1/3, -1) always; the best of the four too when it is another.
    paper = int(np.argmin([abs(a - 1 / 3) + abs(b + 1) for a, b in exponents]))
    radii = np.atleast_1d(analysis["collapse_metric"].attrs["radii"])
    lag = analysis["lag"].values
    shown = [paper] if best == paper else [paper, best]
    for k, style in zip(shown, ("-", "--"), strict=False):
        a, b = (float(v) for v in exponents[k])
        for r, color in zip(radii, _radius_colors(radii), strict=True):
            end = float(analysis["diffusive_window_start"].sel(radius=r, body="cell"))
            use = lag <= end
            ax.plot(
                lag[use] * r**b,
                analysis["msd"].sel(radius=r, body="cell").values[use] * r**a,
                style,
                color=color,
                lw=1,
                label=f"R = {r:g} cm" if k == paper else None,
            )
    a, b = (float(v) for v in exponents[paper])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(rf"$\tau\,R^{{{b:+g}}}$ (s cm$^{{{b:+g}}}$)")
    ax.set_ylabel(rf"$\Delta\,R^{{{a:+.2g}}}$ (cm$^{{{2 + a:.3g}}}$)")
    ax.legend(fontsize=7, ncol=2)
    text = f"the paper's (1/3, -1): spread {metric[paper]:.3f} decades"
    if best != paper:
        ab = exponents[best]
        text += f"\nbest of four ({ab[0]:+.2g}, {ab[1]:+g}, dashed): {metric[best]:.3f}"
    ax.text(0.02, 0.92, text, transform=ax.transAxes, fontsize=8, va="top")
    return str(analysis["collapse_variant"].values[best])


def _titled(ax, letter: str, text: str) -> None:
    """The panel letter in bold, then ``text``."""
    _label(ax, letter)
    ax.set_title(text, loc="right", fontsize=8)


def _span_text(analysis: xr.Dataset, i: int, span: float) -> str:
    """ "R = 4 cm, coupled (background), t = 15-75 s" for point i and a span (s) from the
    first sample the analysis kept (the end of the discarded start)."""
    t0 = float(analysis["time"].values[0])
    regime = REGIME_NAMES.get(_regime_at(analysis, i), "unknown")
    return (
        f"R = {float(analysis['radius'][i]):g} cm, {regime} (background), "
        f"t = {t0:g}-{t0 + span:g} s"
    )


#: Time spans (s) of Fig. 2's trajectories (a, b) and speed series (c, d), from the end of
#: the discarded start.
TRAJECTORY_SPAN, SPEED_SPAN = 60.0, 10.0


def figure2(analysis: xr.Dataset, simulations: xr.Dataset):
    """Fig. 2: trajectories at R = 4 and 12 cm, their speed series, MSDs, collapse; panels
    in reading order (a, b / c, d / e, f)."""
    fig = _figure(8, 8.4)
    axes = fig.subplots(3, 2)
    for col, radius in enumerate((4.0, 12.0)):
        i = _radius_index(analysis, radius)
        ax_t, ax_v = axes[0, col], axes[1, col]
        _label(ax_t, "ab"[col])
        _label(ax_v, "cd"[col])
        if i is None:
            for ax in (ax_t, ax_v):
                ax.text(
                    0.5,
                    0.5,
                    f"R = {radius:g} cm not simulated",
                    ha="center",
                    transform=ax.transAxes,
                )
            continue
        _background(ax_t, _regime_at(analysis, i))
        _background(ax_v, _regime_at(analysis, i))
        _trajectory(ax_t, simulations, radius, TRAJECTORY_SPAN, analysis)
        _speed_series(ax_v, analysis, i, SPEED_SPAN)
        _titled(ax_t, "ab"[col], _span_text(analysis, i, TRAJECTORY_SPAN))
        _titled(ax_v, "cd"[col], _span_text(analysis, i, SPEED_SPAN))
    _titled(axes[2, 0], "e", "cell MSD, every R (standard error shaded)")
    _msd_all(axes[2, 0], analysis)
    _titled(axes[2, 1], "f", "scaling collapse, decoupled radii")
    _collapse(axes[2, 1], analysis)
    return fig


def _pdf_panel(
    ax, analysis: xr.Dataset, kind: str, radii: Sequence[float], tracked: xr.Dataset | None = None
) -> None:
    x = analysis["scaled_duration"].values
    colors = _radius_colors(np.asarray(radii))
    for r, color in zip(radii, colors, strict=True):
        y = analysis[f"{kind}_pdf"].sel(radius=r, body="cell").values
        ax.plot(x, np.where(y > 0, y, np.nan), "o", ms=3, color=color, label=f"R = {r:g} cm")
    if tracked is not None:
        y = tracked[f"{kind}_pdf"].sel(body="cell").values
        ax.plot(
            tracked["scaled_duration"].values,
            np.where(y > 0, y, np.nan),
            "^",
            ms=4,
            color=EXP_COLOR,
            label="tracked video",
        )
    # The x axis ends where the data in view do (the last bin above the axis' floor, over
    # every R drawn).
    drawn = [analysis[f"{kind}_pdf"].sel(radius=r, body="cell").values for r in radii]
    filled = np.flatnonzero(np.any(np.array(drawn) >= PDF_FLOOR, axis=0))
    end = float(x[filled[-1]]) + float(x[1] - x[0]) if filled.size else 6.0
    grid = np.linspace(0, end, 200)
    symbol = r"\tau_\mathrm{g}" if kind == "go" else r"\tau_\mathrm{s}"
    ax.plot(
        grid,
        np.exp(-grid),
        "k--",
        lw=1,
        label=rf"$e^{{-t'}}$, $t' = {symbol}/\langle {symbol}\rangle$",
    )
    ax.set_yscale("log")
    ax.set_xlim(0, end)
    ax.set_ylim(PDF_FLOOR, 3)
    ax.set_xlabel(rf"$t' = {symbol}/\langle {symbol}\rangle$")
    ax.set_ylabel(r"$\mathcal{P}(t')$")
    ax.legend(fontsize=7, ncol=2)


#: The lowest probability density the duration PDFs show.
PDF_FLOOR = 1e-3


def _tracked_radius(tracked: xr.Dataset) -> float:
    return float(json.loads(tracked.attrs.get("softcell_parameters", "{}")).get("radius", np.nan))


def _against_radius(
    ax,
    analysis: xr.Dataset,
    name: str,
    label: str,
    tracked: xr.Dataset | None = None,
    body: str = "cell",
    error: str | None = None,
    marker: str = "o",
    color: str = SIM_COLOR,
    legend: str = "simulations",
    size: float = 6.0,
    filled: bool = False,
) -> None:
    radii = analysis["radius"].values
    y = analysis[name].sel(body=body).values
    yerr = analysis[error].sel(body=body).values if error else None
    ax.errorbar(
        radii,
        y,
        yerr=yerr,
        fmt=marker,
        color=color,
        mfc=color if filled else "none",
        ms=size,
        capsize=2,
        label=legend,
    )
    if tracked is not None:
        ax.plot(
            [_tracked_radius(tracked)],
            [float(tracked[name].sel(body=body))],
            "^",
            color=EXP_COLOR,
            ms=7,
            label="tracked video",
        )
    ax.margins(y=0.12)
    ax.set_xlabel("R (cm)")
    ax.set_ylabel(label)


def figure3(analysis: xr.Dataset, tracked: xr.Dataset | None = None):
    """Fig. 3: the cell speed at R = 12 cm with stops shaded, PDFs of t/<t>, <tau_g> and
    <tau_s> against R with the regimes shaded."""
    fig = _figure(8, 8.4)
    grid = fig.add_gridspec(3, 2)
    ax_a = fig.add_subplot(grid[0, :])
    _label(ax_a, "a")
    i = _radius_index(analysis, 12.0)
    i = analysis.sizes["radius"] - 1 if i is None else i
    _background(ax_a, _regime_at(analysis, i))
    _speed_series(ax_a, analysis, i, 30.0, bodies=("cell",), shade=True)
    ax_a.set_title(_span_text(analysis, i, 30.0) + "; stops shaded grey", loc="right", fontsize=8)
    # The paper's PDFs are of the decoupled radii; a sweep without any shows all it has.
    radii = [r for r in analysis["radius"].values if r >= 6] or list(analysis["radius"].values)
    for col, kind in enumerate(("go", "stop")):
        ax = fig.add_subplot(grid[1, col])
        _titled(ax, "bc"[col], f"{kind} durations, R >= {min(radii):g} cm")
        _pdf_panel(ax, analysis, kind, radii, tracked)
    for col, (name, symbol) in enumerate(
        (("mean_go_duration", r"\tau_\mathrm{g}"), ("mean_stop_duration", r"\tau_\mathrm{s}"))
    ):
        ax = fig.add_subplot(grid[2, col])
        if col == 0:
            _titled(ax, "d", "background: the regime")
        _shade_regimes(ax, analysis)
        _against_radius(ax, analysis, name, rf"$\langle {symbol}\rangle$ (s)", tracked)
        # From 0, so a change reads at its true size; room above the highest error bar.
        top = ax.dataLim.y1  # -inf when no radius has a value
        ax.set_ylim(0, 1.15 * top if np.isfinite(top) and top > 0 else None)
        ax.legend(fontsize=7, loc="lower right")
    return fig


def figure4(analysis: xr.Dataset, tracked: xr.Dataset | None = None):
    """Fig. 4: (a) the fitted ballistic velocity against the theory's v0 hat, (b) the fitted
    MSD slope against the theory's D hat = 2 v0_hat^2 <tau_g>, for the cell against R."""
    fig = _figure(8, 3.8)
    ax_a, ax_b = fig.subplots(1, 2)
    for ax, letter, fit, error, theory, label, hat in (
        (
            ax_a,
            "a",
            "ballistic_velocity",
            "ballistic_velocity_error",
            "v0_hat",
            "velocity (cm/s)",
            r"$\hat v_0^\mathrm{sim}$",
        ),
        (
            ax_b,
            "b",
            "msd_slope",
            "msd_slope_error",
            "msd_slope_theory",
            r"$\hat D$ (cm$^2$/s)",
            r"$\hat D^\mathrm{sim}$",
        ),
    ):
        _titled(ax, letter, "background: the regime")
        _shade_regimes(ax, analysis)
        # The theory as large open squares under the fits' small filled circles: both show.
        _against_radius(
            ax, analysis, theory, label, None, marker="s", color="k", legend=hat, size=9
        )
        _against_radius(
            ax,
            analysis,
            fit,
            label,
            None,
            error=error,
            legend="fit of the MSD",
            size=4,
            filled=True,
        )
        if tracked is not None:
            r, span = _tracked_radius(tracked), _record_span(tracked)
            for name, marker in ((fit, "^"), (theory, "v")):
                ax.plot(
                    [r],
                    [float(tracked[name].sel(body="cell"))],
                    marker,
                    color=EXP_COLOR,
                    ms=7,
                    label=f"tracked video ({span:g} s), {'fit' if name == fit else 'theory'}",
                )
        ax.set_yscale("log")
        plain_log_ticks(ax)
        ax.legend(fontsize=7)
    return fig


def _record_span(analysis: xr.Dataset) -> float:
    """The analysed span (s) of a record: its last kept time less its first."""
    t = np.asarray(analysis["time"].values, dtype=float)
    return round(float(t[-1] - t[0]))


def plain_log_ticks(ax, axis: str = "y") -> None:
    """Plain numbers on a log axis (1, 2, 3, 5, 10; 0.2, 0.3, 0.5), not 6x10^-1: every power
    of ten, and the minor ticks at 2, 3 and 5 times one."""
    from matplotlib.ticker import FuncFormatter

    def minor(v: float, _) -> str:
        leading = v / 10 ** np.floor(np.log10(v)) if v > 0 else 0.0
        return f"{v:g}" if np.isclose(leading, (2, 3, 5)).any() else ""

    target = ax.yaxis if axis == "y" else ax.xaxis
    target.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    target.set_minor_formatter(FuncFormatter(minor))


def figure_s1(analysis: xr.Dataset, free_bot: xr.Dataset):
    """S1 (b): MSD of the free bot against the bot inside membranes of every R."""
    fig = _figure(5.5, 4.2)
    ax = fig.subplots()
    radii = analysis["radius"].values
    lag = analysis["lag"].values
    for r, color, ls in zip(radii, _radius_colors(radii), _radius_dashes(radii), strict=True):
        m = analysis["msd"].sel(radius=r, body="bot").values
        ax.plot(lag, m, color=color, ls=ls, lw=1, label=f"in membrane, R = {r:g} cm")
        _band(ax, lag, m, analysis["msd_sem"].sel(radius=r, body="bot").values, color)
    free, free_sem = (free_bot[v].sel(body="bot") for v in ("msd", "msd_sem"))
    free = free.isel({d: 0 for d in free.dims if d != "lag"})
    free_sem = free_sem.isel({d: 0 for d in free_sem.dims if d != "lag"})
    ax.plot(free_bot["lag"].values, free.values, "k-", lw=2, label="free bot")
    _band(ax, free_bot["lag"].values, free.values, free_sem.values, "k")
    _msd_axes(ax)
    ax.set_title("bot MSD, free and inside membranes (standard error shaded)", fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    return fig


def figure_s2(analysis: xr.Dataset):
    """S2: simulated PDFs of go (a) and stop (b) durations over their means, every R."""
    fig = _figure(8, 3.8)
    for ax, kind, letter in zip(fig.subplots(1, 2), ("go", "stop"), "ab", strict=True):
        _label(ax, letter)
        _pdf_panel(ax, analysis, kind, list(analysis["radius"].values))
    return fig


def figure_s3(analysis: xr.Dataset, radius: float = 12.0):
    """S3 (b): MSD of the bot and of the cell at R = 12 cm, with their standard errors."""
    fig = _figure(5.5, 4.2)
    ax = fig.subplots()
    i = _radius_index(analysis, radius)
    i = analysis.sizes["radius"] - 1 if i is None else i
    _background(ax, _regime_at(analysis, i))
    regime = REGIME_NAMES.get(_regime_at(analysis, i), "unknown")
    ax.set_title(f"background: the {regime} regime", loc="right", fontsize=8)
    lag = analysis["lag"].values
    for body, color in (("bot", "0.35"), ("cell", "C3")):
        m = analysis["msd"].isel(radius=i).sel(body=body).values
        e = analysis["msd_sem"].isel(radius=i).sel(body=body).values
        ax.plot(lag, m, color=color, label=body)
        ax.fill_between(lag, m - e, m + e, color=color, alpha=0.25, lw=0)
    _msd_axes(ax)
    ax.legend(fontsize=8, title=f"R = {float(analysis['radius'][i]):g} cm", title_fontsize=8)
    return fig


def figure_theory(analysis: xr.Dataset):
    """Beyond the paper: (a) the cell's velocity autocorrelation C(tau) / C(0), measured and
    the renewal theory's, at three radii; (b) the cell MSD over the two theories' MSDs
    (exponential phases dashed, the measured go durations solid), every R; (c) the mean
    cosine between consecutive go displacements against R (0 in both theories)."""
    fig = _figure(8, 6.4)
    grid = fig.add_gridspec(2, 2)
    ax_a, ax_b = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])
    ax_c = fig.add_subplot(grid[1, :])
    radii = analysis["radius"].values
    colors = dict(zip(radii, _radius_colors(radii), strict=True))
    cell = analysis.sel(body="cell")
    tau = analysis["correlation_lag"].values
    _label(ax_a, "a")
    shown = [r for r in (4.0, 8.0, 12.0) if r in radii] or list(radii[:: max(len(radii) // 3, 1)])
    for r in shown:
        c = cell["velocity_autocorrelation"].sel(radius=r).values
        each = cell["velocity_autocorrelation_realization"].sel(radius=r).values
        n = np.isfinite(each).sum(axis=0)
        err = np.nanstd(each, axis=0, ddof=1) / np.sqrt(np.maximum(n, 1)) / c[0]
        ax_a.plot(tau, c / c[0], color=colors[r], lw=1.2, label=f"R = {r:g} cm")
        ax_a.fill_between(tau, c / c[0] - err, c / c[0] + err, color=colors[r], alpha=0.3, lw=0)
        theory = cell["velocity_autocorrelation_renewal"].sel(radius=r).values
        ax_a.plot(tau, theory / theory[0], color=colors[r], lw=1, ls=":")
    ax_a.axhline(0, color="0.5", lw=0.5)
    ax_a.set_xlim(0, min(6.0, float(tau[-1])))
    ax_a.set_xlabel(r"$\tau$ (s)")
    ax_a.set_ylabel(r"$C(\tau)/C(0)$ (cell)")
    ax_a.legend(fontsize=7, title="solid: measured; dotted: renewal theory", title_fontsize=7)
    _label(ax_b, "b")
    lag = analysis["lag"].values
    for r in radii:
        m, c = cell["msd"].sel(radius=r).values, colors[r]
        renewal = cell["msd_theory_renewal"].sel(radius=r).values
        ax_b.plot(lag, m / renewal, color=c, lw=1, label=f"{r:g}")
        ax_b.plot(lag, m / cell["msd_theory"].sel(radius=r).values, color=c, lw=0.7, ls="--")
    ax_b.axhline(1, color="k", lw=0.6)
    ax_b.set_xscale("log")
    ax_b.set_yscale("log")
    plain_log_ticks(ax_b)
    ax_b.set_xlabel(r"$\tau$ (s)")
    ax_b.set_ylabel("cell MSD / theory")
    ax_b.set_title("solid: renewal; dashed: exponential phases", fontsize=7)
    ax_b.legend(fontsize=7, ncol=2, title="R (cm)", title_fontsize=7)
    _label(ax_c, "c")
    _shade_regimes(ax_c, analysis)
    turns = cell["go_turn_cosine_realization"].values
    pairs = cell["go_turn_pairs"].values
    n = (pairs > 0).sum(axis=-1)
    err = np.nanstd(turns, axis=-1, ddof=1) / np.sqrt(np.maximum(n, 1))
    ax_c.errorbar(radii, cell["go_turn_cosine"].values, yerr=err, fmt="o", color=SIM_COLOR, ms=4)
    ax_c.axhline(0, color="k", lw=0.6)
    ax_c.set_xlabel("R (cm)")
    ax_c.set_ylabel("mean cos(turn) between go phases")
    ax_c.legend(fontsize=7, title="background: the regime", title_fontsize=7)
    return fig


def _metadata(fmt: str, name: str) -> dict[str, str]:
    from softcell._version import __version__

    creator = f"softcell {__version__} ({name})"
    return {
        "png": {"Software": creator},
        "pdf": {"Creator": creator},
        "svg": {"Creator": creator},
    }.get(fmt, {})


#: What the figure of the velocity correlations (beyond the paper) reads; an analysis made
#: before softcell 0.3 lacks it, and the figure is left out.
THEORY_NEEDS = (
    "velocity_autocorrelation",
    "velocity_autocorrelation_realization",
    "velocity_autocorrelation_renewal",
    "msd_theory_renewal",
    "go_turn_cosine",
)

#: Variables each input of :func:`make_figures` must hold.
NEEDS = {
    "analysis": (
        "msd",
        "msd_sem",
        "lag",
        "scaled_duration",
        "stop_pdf",
        "go_pdf",
        "mean_go_duration",
        "mean_stop_duration",
        "ballistic_velocity",
        "msd_slope",
        "v0_hat",
        "msd_slope_theory",
        "regime",
    ),
    "tracked": (
        "scaled_duration",
        "stop_pdf",
        "go_pdf",
        "mean_go_duration",
        "mean_stop_duration",
        "ballistic_velocity",
        "msd_slope",
        "v0_hat",
        "msd_slope_theory",
    ),
    "free_bot": ("msd", "msd_sem", "lag"),
}


def check_inputs(
    analysis: xr.Dataset,
    *,
    simulations: xr.Dataset | None = None,
    free_bot: xr.Dataset | None = None,
    tracked: xr.Dataset | None = None,
) -> None:
    """Raise a one-line :class:`SoftcellError` unless the inputs are what the figures read:
    analyses (``softcell analyze``) holding the variables of :data:`NEEDS`, the analysis of a
    radius sweep, and a simulation Dataset."""
    for role, ds in (("analysis", analysis), ("free_bot", free_bot), ("tracked", tracked)):
        if ds is None:
            continue
        origin = ds.attrs.get("softcell_origin")
        missing = [v for v in NEEDS[role] if v not in ds.variables]
        if origin != "analysis" or missing:
            what = (
                f"lacks {', '.join(missing)}"
                if origin == "analysis"
                else f"is a {origin or 'non-softcell'} file, not an analysis"
            )
            raise SoftcellError(
                f"the {role.replace('_', ' ')} input {what}: give the output "
                "of `softcell analyze`" + (" on a tracked video" if role == "tracked" else "")
            )
    if "radius" not in analysis.dims:
        raise SoftcellError(
            "the figures need the analysis of a radius sweep (a 'radius' "
            "dimension); this analysis has dims "
            f"{', '.join(analysis.dims) or 'none'}"
        )
    if simulations is not None:
        from softcell.schema import validate

        validate(simulations)


def make_figures(
    analysis: xr.Dataset,
    out: str | os.PathLike[str],
    *,
    simulations: xr.Dataset | None = None,
    free_bot: xr.Dataset | None = None,
    tracked: xr.Dataset | None = None,
    formats: Sequence[str] = FORMATS,
    only: Sequence[str] | None = None,
) -> FigureSet:
    """Draw every figure the inputs allow into ``out`` (``fig2.png``, ``fig2.pdf``, ...).

    Parameters
    ----------
    analysis : xarray.Dataset
        Analysis of a ``radius`` sweep (:func:`softcell.analyze`), lengths in cm, times in s.
    simulations : xarray.Dataset, optional
        The sweep's simulation Dataset, for the trajectories of Fig. 2 (a, b).
    free_bot : xarray.Dataset, optional
        Analysis of free-bot runs, for S1.
    tracked : xarray.Dataset, optional
        Analysis of a tracked video, drawn as the experiments' markers in Fig. 3 and 4.
    out : path-like
        Folder the figures are written to (created if missing).
    formats : sequence of str
        File formats (matplotlib's names).
    only : sequence of str, optional
        Draw only these figures (of ``softcell.paper.figures.FIGURES``); by default every one.

    Returns
    -------
    FigureSet
        The files written per figure, and the figures left out with the reason.
    """
    check_inputs(analysis, simulations=simulations, free_bot=free_bot, tracked=tracked)
    out = Path(out)
    result = FigureSet()
    plans = {
        "fig2": (
            lambda: figure2(analysis, simulations),
            simulations is None,
            "needs the simulations (trajectories)",
        ),
        "fig3": (lambda: figure3(analysis, tracked), False, ""),
        "fig4": (lambda: figure4(analysis, tracked), False, ""),
        "figS1": (
            lambda: figure_s1(analysis, free_bot),
            free_bot is None,
            "needs the free bot's analysis",
        ),
        "figS2": (lambda: figure_s2(analysis), False, ""),
        "figS3": (lambda: figure_s3(analysis), False, ""),
        "figT": (
            lambda: figure_theory(analysis),
            any(v not in analysis.variables for v in THEORY_NEEDS),
            "needs the velocity autocorrelation (an analysis by softcell >= 0.3)",
        ),
    }
    if only is not None:
        unknown = sorted(set(only) - set(plans))
        if unknown:
            raise ValueError(f"no figure named {', '.join(unknown)}: the figures are {FIGURES}")
        plans = {name: plan for name, plan in plans.items() if name in only}
    with atomic_files() as staging:  # the whole set, or nothing (a full disk)
        for name, (draw, missing, why) in plans.items():
            if missing:
                result.skipped[name] = why
                continue
            fig = draw()
            files = []
            for fmt in formats:
                path = out / f"{name}.{fmt}"
                fig.savefig(staging.path(path), format=fmt, dpi=150, metadata=_metadata(fmt, name))
                files.append(path)
            result.files[name] = files
    return result
