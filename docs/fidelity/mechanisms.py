"""The numbers and figures of docs/fidelity.md's mechanism studies, from the runs it lists.

    python docs/fidelity/mechanisms.py --full RESULTS --free-bot FB --convergence CONV \
        -o docs/fidelity

RESULTS is a ``softcell reproduce --full`` folder (its ``contact.nc``), FB holds one
``softcell analyze`` output per free-bot variant (``<variant>.nc``), CONV one simulation
folder per numerical variant (``default``, ``rtol``, ``cutoff``, ``nodes``). Writes
``mechanisms.json`` and ``figures/contact_torque.png`` and prints the tables as Markdown.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import softcell
from softcell.analysis import fits

#: Free-bot variants: the file stem and what it is.
FREE_BOT = {
    "centre": "turns about its centre, T0 / gamma_R = 5.3 rad/s (the defaults)",
    "centre_w346": "about its centre at 3.46 rad/s (T0 = 98.6 N cm)",
    "pivot153": "about a pivot 1.53 cm off-centre, 5.3 rad/s",
    "pivot153_w": "about a pivot 1.53 cm off-centre, 3.46 rad/s",
}
#: Long-lag window of the free bot's D (s): its phases never stop, so <tau_g> sets none.
FREE_LAG = 10.0
CONVERGENCE = {
    "default": "defaults (rtol = atol = 1e-6, Lambda_c = 16, N = 1024)",
    "rtol": "rtol = atol = 1e-7",
    "cutoff": "Lambda_c = 24",
    "nodes": "N = 2048",
}
KEYS = ("mean_go_duration", "mean_stop_duration", "v0_hat", "msd_slope")


def free_bot(folder: Path) -> dict:
    """D = D hat / 4 (cm^2/s) of each free-bot variant, its standard error across
    realizations, and the bot's mean turn cosine."""
    out = {}
    for stem, what in FREE_BOT.items():
        a = softcell.read_dataset(folder / f"{stem}.nc").sel(body="bot")
        lag = a["lag"].values
        each = [fits.msd_slope(lag, m, FREE_LAG)[0] / 4 for m in a["msd_realization"].values]
        out[stem] = {
            "what": what,
            "D": fits.msd_slope(lag, a["msd"].values, FREE_LAG)[0] / 4,
            "D_error": float(np.std(each, ddof=1) / np.sqrt(len(each))),
            "realizations": len(each),
        }
    return out


def convergence(folder: Path) -> dict:
    """The key numbers of every numerical variant per radius, with standard errors across
    realizations (the same seed: common random numbers)."""
    from softcell.analysis.bootstrap import sweep_estimates

    out = {}
    for name, what in CONVERGENCE.items():
        analysis = softcell.analyze(softcell.open_dataset(folder / name))
        est = sweep_estimates(analysis, seed=0)
        out[name] = {
            "what": what,
            "radius": analysis["radius"].values.tolist(),
            **{k: est[k].value.tolist() for k in KEYS},
            **{f"{k}_error": est[k].error.tolist() for k in KEYS},
        }
    return out


def contact(results: Path, figures: Path) -> dict:
    """The membrane's torque and force on the bot per radius, and its figure."""
    from matplotlib.figure import Figure

    c = softcell.read_dataset(results / "contact.nc")
    r = c["radius"].values
    fig = Figure(figsize=(5.5, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.semilogy(r, c["contact_torque_max"].values, "o-", label="largest |torque|")
    ax.semilogy(r, c["contact_torque_rms"].values, "s-", label="RMS torque")
    t0 = float(c["drive_torque"].values[0])
    ax.axhline(t0, color="k", lw=1, label=f"drive torque T0 = {t0:g} N cm")
    ax.set_xlabel("R (cm)")
    ax.set_ylabel("torque on the bot (N cm)")
    ax.legend(fontsize=7)
    figures.mkdir(parents=True, exist_ok=True)
    fig.savefig(figures / "contact_torque.png", dpi=150)
    return {
        name: c[name].values.tolist()
        for name in ("radius", "contact_torque_rms", "contact_torque_max", "contact_force_rms")
    } | {"contact_fraction": c["contact_fraction"].values.tolist(), "drive_torque": t0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", type=Path, required=True)
    parser.add_argument("--free-bot", type=Path, required=True)
    parser.add_argument("--convergence", type=Path, required=True)
    parser.add_argument("-o", "--output", type=Path, required=True)
    args = parser.parse_args()
    result = {
        "contact": contact(args.full, args.output / "figures"),
        "free_bot": free_bot(args.free_bot),
        "convergence": convergence(args.convergence),
    }
    (args.output / "mechanisms.json").write_text(json.dumps(result, indent=1) + "\n")
    for row in result["free_bot"].values():
        print(f"| {row['what']} | {row['D']:.1f} ± {row['D_error']:.1f} |")
    for row in result["convergence"].values():
        for i, radius in enumerate(row["radius"]):
            cells = " | ".join(f"{row[k][i]:.4g} ± {row[k + '_error'][i]:.2g}" for k in KEYS)
            print(f"| {row['what']} | {radius:g} | {cells} |")


if __name__ == "__main__":
    main()
