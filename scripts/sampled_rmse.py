#!/usr/bin/python3
"""Each robot's online position RMSE of a run over every N-th step and the last only:
sampled_rmse.py RUN N

RUN is a run's output directory (its metrics.csv, as mrslam_launch writes it); the steps are
those mrslam_batch --every N scores, so a run's agents can be set beside a reference solved at
those steps only (docs/results/joint-graph.md). Prints one line per robot and the median.
"""

import csv
import math
import os
import statistics
import sys


def sampled_rmse(metrics_path, every):
    """Robot id -> RMSE of position_err_m over the steps k with k % every == 0 or k the last."""
    errors = {}
    last = 0
    with open(metrics_path, newline="") as f:
        for row in csv.DictReader(f):
            step = int(row["step"])
            last = max(last, step)
            errors.setdefault(row["robot"], {})[step] = float(row["position_err_m"])
    out = {}
    for robot, by_step in errors.items():
        kept = [e for k, e in by_step.items() if k % every == 0 or k == last]
        if kept:
            out[robot] = math.sqrt(sum(e * e for e in kept) / len(kept))
    return out


def main(argv):
    if len(argv) != 3 or not argv[2].isdigit() or int(argv[2]) < 1:
        sys.exit("usage: sampled_rmse.py RUN N (N >= 1)")
    path = os.path.join(argv[1], "metrics.csv")
    if not os.path.isfile(path):
        sys.exit(f"sampled_rmse.py: no metrics.csv in {argv[1]}")
    rmse = sampled_rmse(path, int(argv[2]))
    if not rmse:
        sys.exit(f"sampled_rmse.py: {path} holds no robot's errors")
    for robot in sorted(rmse):
        print(f"{robot} {rmse[robot]:.3f}")
    print(f"median {statistics.median(rmse.values()):.3f}")


if __name__ == "__main__":
    main(sys.argv)
