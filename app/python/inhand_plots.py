"""The evaluation's plots, drawn by matplotlib: `python3 -m inhand_plots EVAL_DIR`.

`inhand evaluate` runs this after writing its tables: for each scenario, Fig. 7 of the paper
(the change of the object's position and orientation over one run, the truth dashed black and
every set in its colour; the terminal errors over all runs as bars) from `fig7_SCENARIO.csv`,
and one figure of every scenario's terminal errors from `table1.json`. Each figure is written as
PNG, SVG (text kept as text) and PDF, without time stamps, so that the same data gives the same
files. Every plot has one value axis, ticks and labels with units on both axes and a legend.
"""
import argparse
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import inhand  # noqa: E402  (the sets' colours)

AXES = (("x_mm", "x [mm]"), ("y_mm", "y [mm]"), ("z_mm", "z [mm]"),
        ("roll_deg", "roll [deg]"), ("pitch_deg", "pitch [deg]"), ("yaw_deg", "yaw [deg]"))
FORMATS = ("png", "svg", "pdf")
SET_ORDER = ("j", "jt", "ja", "jf", "jta", "jtf", "jaf", "jtaf")

plt.rcParams.update({
    "svg.fonttype": "none",  # text stays <text> in the SVG
    "svg.hashsalt": "inhand",  # ids do not change from run to run
    "font.size": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
})


def colour(name):
    r, g, b = inhand.set_colour(name)
    return (r / 255.0, g / 255.0, b / 255.0)


def ordered(sets):
    return sorted(sets, key=lambda s: (SET_ORDER.index(s) if s in SET_ORDER else 99, s))


def save(fig, base):
    written = []
    for fmt in FORMATS:
        path = f"{base}.{fmt}"
        fig.savefig(path, dpi=100, metadata={"Date": None} if fmt == "svg" else
                    {"CreationDate": None} if fmt == "pdf" else None)
        written.append(path)
    plt.close(fig)
    return written


def read_series(path):
    """fig7_SCENARIO.csv: t, series (a set or 'truth') and the six changes."""
    series = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            s = series.setdefault(row["series"], {"t": [], **{k: [] for k, _ in AXES}})
            s["t"].append(float(row["t"]))
            for k, _ in AXES:
                s[k].append(float(row[k]))
    return series


def error_bars(ax, cells, sets, key, unit, title):
    """One bar per set: mean with the runs' standard deviation; the paper's value as a marker."""
    xs = range(len(sets))
    means = [cells[s][f"{key}_mean"] for s in sets]
    stds = [cells[s][f"{key}_std"] for s in sets]
    ax.bar(xs, means, yerr=stds, capsize=4, color=[colour(s) for s in sets], edgecolor="black",
           linewidth=0.5)
    paper = [(i, cells[s].get(f"paper_{key}")) for i, s in enumerate(sets)]
    paper = [(i, v) for i, v in paper if v is not None]
    if paper:
        ax.plot([i for i, _ in paper], [v for _, v in paper], linestyle="none", marker="_",
                markersize=22, markeredgewidth=2.5, color="black", label="paper")
        ax.legend(loc="upper right")
    ax.set_xticks(list(xs), sets)
    ax.set_xlabel("set")
    ax.set_ylabel(f"{title} [{unit}]")
    ax.set_ylim(bottom=0)
    ax.grid(axis="x", visible=False)


def fig7(scenario, series, cells, runs, base):
    fig = plt.figure(figsize=(15, 11), layout="constrained")
    # A thin first row holds the legend (matplotlib 3.6 lays out no legend outside the axes).
    grid = fig.add_gridspec(4, 6, height_ratios=(0.12, 1, 1, 1))
    sets = [s for s in ordered(series) if s != "truth"]
    for a, (key, label) in enumerate(AXES):
        ax = fig.add_subplot(grid[1 + a // 3, 2 * (a % 3):2 * (a % 3) + 2])
        for s in sets:
            ax.plot(series[s]["t"], series[s][key], color=colour(s), linewidth=1.0, label=s)
        if "truth" in series:
            ax.plot(series["truth"]["t"], series["truth"][key], color="black", linewidth=1.6,
                    linestyle=(0, (5, 3)), label="truth")
        ax.set_title(f"change in {label.split(' ')[0]}")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"change in {label}")
        if a == 0:
            handles, labels = ax.get_legend_handles_labels()
    legend = fig.add_subplot(grid[0, :])
    legend.axis("off")
    legend.legend(handles, labels, loc="center", ncol=len(labels), frameon=False)
    if cells:
        bar_sets = ordered(cells)
        error_bars(fig.add_subplot(grid[3, 0:3]), cells, bar_sets, "position_mm", "mm",
                   f"terminal position error, {runs} run{'s' if runs != 1 else ''}")
        error_bars(fig.add_subplot(grid[3, 3:6]), cells, bar_sets, "orientation_deg", "deg",
                   f"terminal orientation error, {runs} run{'s' if runs != 1 else ''}")
    fig.suptitle(f"{scenario}: one run's pose over time (Fig. 7) and the terminal errors of all "
                 "runs (mean, standard deviation, the paper's value)")
    return save(fig, base)


def terminal_errors(table, base):
    scenarios = list(table)
    sets = ordered({s for cells in table.values() for s in cells})
    fig, axes = plt.subplots(2, 1, figsize=(max(10, 2.2 * len(scenarios) + 3), 8),
                             layout="constrained")
    width = 0.8 / max(1, len(sets))
    for ax, key, unit, title in ((axes[0], "position_mm", "mm", "terminal position error"),
                                 (axes[1], "orientation_deg", "deg",
                                  "terminal orientation error")):
        for k, s in enumerate(sets):
            xs, means, stds = [], [], []
            for i, sc in enumerate(scenarios):
                if s in table[sc]:
                    xs.append(i + (k - (len(sets) - 1) / 2) * width)
                    means.append(table[sc][s][f"{key}_mean"])
                    stds.append(table[sc][s][f"{key}_std"])
            ax.bar(xs, means, width, yerr=stds, capsize=3, color=colour(s), edgecolor="black",
                   linewidth=0.5, label=s)
            paper = [(x, table[sc][s].get(f"paper_{key}"))
                     for x, sc in zip(xs, [sc for sc in scenarios if s in table[sc]])]
            paper = [(x, v) for x, v in paper if v is not None]
            if paper:
                ax.plot([x for x, _ in paper], [v for _, v in paper], linestyle="none",
                        marker="_", markersize=10, markeredgewidth=2, color="black",
                        label="paper" if k == 0 else None)
        ax.set_xticks(range(len(scenarios)), scenarios)
        ax.set_xlabel("scenario")
        ax.set_ylabel(f"{title} [{unit}]")
        ax.set_ylim(bottom=0)
        ax.grid(axis="x", visible=False)
        ax.legend(ncol=len(sets) + 1, loc="upper left")
    runs = max(c["runs"] for cells in table.values() for c in cells.values())
    fig.suptitle(f"Terminal errors over {runs} run{'s' if runs != 1 else ''} per scenario\n"
                 "(mean and standard deviation; the paper's values as black marks)")
    return save(fig, base)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m inhand_plots", description=__doc__.split(
        "\n")[0])
    parser.add_argument("eval_dir", help="the folder inhand evaluate wrote")
    args = parser.parse_args(argv)
    table_path = os.path.join(args.eval_dir, "table1.json")
    try:
        with open(table_path) as f:
            table = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"inhand_plots: {table_path}: {e}")
    written = []
    for scenario, cells in table.items():
        data = os.path.join(args.eval_dir, f"fig7_{scenario}.csv")
        if not os.path.exists(data):
            continue
        runs = max((c["runs"] for c in cells.values()), default=0)
        written += fig7(scenario, read_series(data), cells, runs,
                        os.path.join(args.eval_dir, f"fig7_{scenario}"))
    if table:
        written += terminal_errors(table, os.path.join(args.eval_dir, "terminal_errors"))
    print(f"inhand_plots: {len(written)} files written to {args.eval_dir}")


if __name__ == "__main__":
    main()
