#!/usr/bin/python3
"""Heat maps of paper B's grid: plot_grid.py DIR

Reads DIR/grid.csv (written by mrslam_grid) and writes DIR/plots/grid_<metric>.png: per metric
(landmark RMSE, robot RMSE, static completeness) one heat map per filter (rows dynamism, columns
speed, the mean over the runs in each cell), and DIR/plots/grid_ratio.png: ekf_ela / ekf.
Runs with Debian's /usr/bin/python3 and python3-matplotlib (Agg backend, no display needed).
Exit codes: 0 plots written, 1 bad or missing input, 3 matplotlib missing.
"""

import csv
import os
import sys
from collections import defaultdict

EXIT_BAD_INPUT = 1
EXIT_NO_MATPLOTLIB = 3

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as error:  # pragma: no cover - depends on the machine
    print(f"plot_grid.py: matplotlib is missing ({error}); install python3-matplotlib", file=sys.stderr)
    sys.exit(EXIT_NO_MATPLOTLIB)

METRICS = [("landmark_rmse_m", "landmark RMSE (m)"), ("robot_rmse_m", "robot RMSE (m)"),
           ("static_completeness", "static completeness"),
           ("static_only_completeness", "static completeness, static-only assignment")]


def load(path):
    cells = defaultdict(list)  # (filter, dynamism, speed, metric) -> values
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            for metric, _ in METRICS:
                value = float(row[metric])
                if value == value:  # not NaN
                    cells[(row["filter"], float(row["dynamism"]), float(row["speed_mps"]), metric)].append(value)
    return cells


def mean(values):
    return sum(values) / len(values) if values else float("nan")


def heat(ax, grid, dyn, speeds, title, fmt="{:.2f}"):
    image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
    ax.set_xticks(range(len(speeds)), [f"{s:g}" for s in speeds])
    ax.set_yticks(range(len(dyn)), [f"{100 * d:.0f}%" for d in dyn])
    ax.set_xlabel("landmark speed (m/s)")
    ax.set_ylabel("dynamism")
    ax.set_title(title)
    for i in range(len(dyn)):
        for j in range(len(speeds)):
            ax.text(j, i, fmt.format(grid[i][j]), ha="center", va="center", color="w", fontsize=8)
    plt.colorbar(image, ax=ax)


def main():
    if len(sys.argv) != 2:
        print("usage: plot_grid.py DIR", file=sys.stderr)
        return EXIT_BAD_INPUT
    folder = sys.argv[1]
    try:
        cells = load(os.path.join(folder, "grid.csv"))
    except (OSError, KeyError, ValueError) as error:
        print(f"plot_grid.py: cannot read {folder}/grid.csv: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    filters = sorted({k[0] for k in cells})
    dyn = sorted({k[1] for k in cells})
    speeds = sorted({k[2] for k in cells})
    if not filters:
        print("plot_grid.py: grid.csv has no rows", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = os.path.join(folder, "plots")
    os.makedirs(out, exist_ok=True)
    for metric, label in METRICS:
        fig, axes = plt.subplots(1, len(filters), figsize=(5 * len(filters), 4), squeeze=False)
        for ax, name in zip(axes[0], filters):
            grid = [[mean(cells[(name, d, s, metric)]) for s in speeds] for d in dyn]
            heat(ax, grid, dyn, speeds, f"{name}: {label}")
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"grid_{metric}.png"), dpi=100)
        plt.close(fig)
    if "ekf" in filters and "ekf_ela" in filters:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4), squeeze=False)
        for ax, (metric, label) in zip(axes[0], METRICS[:2]):
            grid = [[mean(cells[("ekf_ela", d, s, metric)]) / mean(cells[("ekf", d, s, metric)]) for s in speeds]
                    for d in dyn]
            heat(ax, grid, dyn, speeds, f"ekf_ela / ekf: {label}")
        fig.tight_layout()
        fig.savefig(os.path.join(out, "grid_ratio.png"), dpi=100)
        plt.close(fig)
    print(f"plots written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
