#!/usr/bin/python3
"""Plots of one mrslam run: plot_run.py DIR

Reads DIR/metrics.csv, DIR/tracks.csv and DIR/summary.json (written by the evaluator) and writes
  DIR/plots/trajectories.png  every robot's true and estimated trajectory in G1 (the first robot's
                              frame), landmarks' true and estimated tracks, starts and rendezvous
                              (like paper A's figures 3-5 and 10-13);
  DIR/plots/errors.png        per robot: x, y and heading error over time with +-3 sigma bands,
                              and the landmark RMSE (like paper A's figures 6-9);
  DIR/plots/overview.png      one page: trajectories, position error, summary table.
Runs with Debian's /usr/bin/python3 and python3-matplotlib (Agg backend, no display needed).
Exit codes: 0 plots written, 1 bad or missing input, 3 matplotlib missing.
"""

import csv
import json
import math
import os
import sys

EXIT_BAD_INPUT = 1
EXIT_NO_MATPLOTLIB = 3

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
except ImportError as error:  # pragma: no cover - depends on the machine
    sys.stderr.write(f"plot_run.py: error: cannot import matplotlib ({error}); "
                     "install it with: sudo apt-get install python3-matplotlib\n")
    sys.exit(EXIT_NO_MATPLOTLIB)

ROBOT_COLORS = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:pink",
                "tab:olive", "tab:cyan", "tab:gray"]
TRUTH_LANDMARK_COLOR = "0.35"
DPI = 130


def fail(message):
    sys.stderr.write(f"plot_run.py: error: {message}\n")
    sys.exit(EXIT_BAD_INPUT)


def to_float(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def read_csv(path):
    if not os.path.exists(path):
        fail(f"{path} not found")
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def finite(values):
    return [v for v in values if not math.isnan(v)]


class Run:
    """The evaluator's outputs of one run, grouped for plotting."""

    def __init__(self, directory):
        self.dir = directory
        summary_path = os.path.join(directory, "summary.json")
        if not os.path.exists(summary_path):
            fail(f"{summary_path} not found")
        with open(summary_path) as f:
            self.summary = json.load(f)
        self.robot_ids = list(self.summary.get("robots", {}).keys())

        # metrics[robot][column] -> list of floats, in step order
        self.metrics = {}
        for row in read_csv(os.path.join(directory, "metrics.csv")):
            robot = row.get("robot", "")
            columns = self.metrics.setdefault(robot, {})
            for key, value in row.items():
                if key != "robot":
                    columns.setdefault(key, []).append(to_float(value))
        for robot in self.metrics:
            if robot not in self.robot_ids:
                self.robot_ids.append(robot)
        for robot, columns in self.metrics.items():
            order = sorted(range(len(columns.get("step", []))), key=lambda i: columns["step"][i])
            for key in columns:
                columns[key] = [columns[key][i] for i in order]

        # tracks[(kind, robot, id)] -> (steps, xs, ys) in step order
        self.tracks = {}
        for row in read_csv(os.path.join(directory, "tracks.csv")):
            key = (row.get("kind", ""), row.get("robot", ""), row.get("id", ""))
            steps, xs, ys = self.tracks.setdefault(key, ([], [], []))
            steps.append(to_float(row.get("step")))
            xs.append(to_float(row.get("x_m")))
            ys.append(to_float(row.get("y_m")))
        for key, (steps, xs, ys) in list(self.tracks.items()):
            order = sorted(range(len(steps)), key=lambda i: steps[i])
            self.tracks[key] = ([steps[i] for i in order], [xs[i] for i in order], [ys[i] for i in order])

        self.time_of_step = {}
        for columns in self.metrics.values():
            for step, t in zip(columns.get("step", []), columns.get("time_s", [])):
                self.time_of_step.setdefault(step, t)

    def color(self, robot):
        index = self.robot_ids.index(robot) if robot in self.robot_ids else len(self.robot_ids)
        return ROBOT_COLORS[index % len(ROBOT_COLORS)]

    def frame_name(self):
        return self.robot_ids[0] if self.robot_ids else "r1"

    def tracks_of(self, kind, robot=None):
        return [(key, value) for key, value in sorted(self.tracks.items())
                if key[0] == kind and (robot is None or key[1] == robot)]

    def rendezvous(self):
        """Encounters as (robot, peer, step, event), each unordered pair and step once."""
        seen = set()
        events = []
        for robot, data in self.summary.get("robots", {}).items():
            for event in data.get("rendezvous", []) or []:
                peer = event.get("peer")
                step = event.get("step")
                if peer is None or step is None:
                    continue
                key = (min(robot, peer), max(robot, peer), step)
                if key in seen:
                    continue
                seen.add(key)
                events.append((robot, peer, step, event))
        return events

    def position_at(self, kind, robot, step):
        track = self.tracks.get((kind, robot, robot)) or next(
            (v for k, v in self.tracks.items() if k[0] == kind and k[1] == robot), None)
        if track is None:
            return None
        steps, xs, ys = track
        best = min(range(len(steps)), key=lambda i: abs(steps[i] - step), default=None)
        return None if best is None else (xs[best], ys[best])

    def title(self):
        s = self.summary
        return f"{s.get('scenario', '?')}, seed {s.get('seed', '?')}, {s.get('steps', '?')} steps"


def draw_trajectories(ax, run, legend_outside=True, legend_font=8):
    """Every robot's true (solid) and estimated (dashed) path in G1, landmark tracks, rendezvous."""
    handles = []
    # True landmark tracks (a moving landmark is a line, a static one a point).
    for _, (steps, xs, ys) in run.tracks_of("truth_landmark"):
        ax.plot(xs, ys, "-", color=TRUTH_LANDMARK_COLOR, linewidth=1.0, zorder=2)
        ax.plot(xs[-1:], ys[-1:], "x", color=TRUTH_LANDMARK_COLOR, markersize=5, zorder=3)
        ax.plot(xs[:1], ys[:1], "o", color=TRUTH_LANDMARK_COLOR, markersize=4, markerfacecolor="none", zorder=3)
    if run.tracks_of("truth_landmark"):
        handles.append(Line2D([], [], color=TRUTH_LANDMARK_COLOR, linestyle="-", marker="x", markersize=5,
                              label="landmark, true track (o start, x end)"))
    for robot in run.robot_ids:
        color = run.color(robot)
        estimated = run.tracks_of("estimate_landmark", robot)
        for _, (steps, xs, ys) in estimated:
            ax.plot(xs, ys, ":", color=color, linewidth=1.2, alpha=0.8, zorder=4)
            ax.plot(xs[-1:], ys[-1:], "+", color=color, markersize=6, zorder=5)
        if estimated:
            handles.append(Line2D([], [], color=color, linestyle=":", marker="+", label=f"landmarks in {robot}'s map"))
    for robot in run.robot_ids:
        color = run.color(robot)
        for kind, style, label, width in (("truth_robot", "-", "true", 1.8), ("estimate_robot", "--", "estimated", 1.4)):
            for _, (steps, xs, ys) in run.tracks_of(kind, robot):
                ax.plot(xs, ys, style, color=color, linewidth=width, zorder=6)
                if kind == "truth_robot":
                    ax.plot(xs[:1], ys[:1], "o", color=color, markersize=8, markeredgecolor="black", zorder=8)
                else:
                    ax.plot(xs[:1], ys[:1], "s", color="none", markeredgecolor=color, markersize=9, zorder=8)
            handles.append(Line2D([], [], color=color, linestyle=style, linewidth=width, label=f"{robot} {label}"))
    handles.append(Line2D([], [], color="0.2", marker="o", linestyle="none", markersize=7, markeredgecolor="black",
                          label="robot start (true)"))
    handles.append(Line2D([], [], color="0.2", marker="s", linestyle="none", markersize=7, markerfacecolor="none",
                          label="robot start (estimated)"))
    rendezvous = run.rendezvous()
    for robot, peer, step, _ in rendezvous:
        a = run.position_at("truth_robot", robot, step)
        b = run.position_at("truth_robot", peer, step)
        if a is None or b is None:
            continue
        ax.plot([a[0], b[0]], [a[1], b[1]], "-", color="black", linewidth=1.0, zorder=9)
        ax.plot([a[0], b[0]], [a[1], b[1]], "*", color="gold", markeredgecolor="black", markersize=14, zorder=10)
        ax.annotate(f"{robot}-{peer} @ {step}", ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2), textcoords="offset points",
                    xytext=(6, 6), fontsize=8, zorder=11,
                    bbox=dict(boxstyle="round,pad=0.2", facecolor="white", alpha=0.8, edgecolor="none"))
    if rendezvous:
        handles.append(Line2D([], [], color="black", marker="*", markerfacecolor="gold", markersize=12,
                              label="rendezvous (true positions)"))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x in G1 [m]  (G1 = {run.frame_name()}'s frame)")
    ax.set_ylabel("y in G1 [m]")
    ax.grid(True, linewidth=0.4, alpha=0.5)
    if legend_outside:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=legend_font,
                  borderaxespad=0.0)
    else:  # below the axes, in columns
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3, fontsize=legend_font,
                  framealpha=0.85)
    return handles


def mark_rendezvous(ax, run, robot):
    for r, peer, step, _ in run.rendezvous():
        if robot in (r, peer):
            t = run.time_of_step.get(float(step))
            if t is not None and not math.isnan(t):
                ax.axvline(t, color="goldenrod", linestyle="--", linewidth=1.0)


def plot_trajectories(run, path):
    fig, ax = plt.subplots(figsize=(10, 7))
    draw_trajectories(ax, run)
    ax.set_title(f"Trajectories in G1 — {run.title()}")
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)


def plot_errors(run, path):
    robots = [r for r in run.robot_ids if r in run.metrics]
    if not robots:
        fail("metrics.csv has no rows")
    n = len(robots)
    rows = [("x_err_m", "sigma_x_m", "x error [m]"), ("y_err_m", "sigma_y_m", "y error [m]"),
            ("heading_err_deg", "sigma_heading_deg", "heading error [deg]"),
            ("landmark_rmse_m", None, "landmark RMSE [m]")]
    fig, axes = plt.subplots(len(rows), n, figsize=(4.2 * n + 0.8, 10.5), sharex="col", squeeze=False)
    for c, robot in enumerate(robots):
        columns = run.metrics[robot]
        t = columns.get("time_s", [])
        color = run.color(robot)
        for r, (value_key, sigma_key, label) in enumerate(rows):
            ax = axes[r][c]
            values = columns.get(value_key, [])
            if sigma_key and sigma_key in columns:
                band = [3.0 * s for s in columns[sigma_key]]
                ax.fill_between(t, [-b for b in band], band, color=color, alpha=0.18, linewidth=0,
                                label="±3σ (filter)")
                ax.plot(t, band, "-", color=color, linewidth=0.6, alpha=0.6)
                ax.plot(t, [-b for b in band], "-", color=color, linewidth=0.6, alpha=0.6)
            ax.plot(t, values, "-", color=color, linewidth=1.3, label="error (estimate − truth)" if sigma_key else
                    "RMSE over map landmarks")
            if sigma_key:
                ax.axhline(0.0, color="black", linewidth=0.5)
            mark_rendezvous(ax, run, robot)
            ax.grid(True, linewidth=0.4, alpha=0.5)
            if c == 0:
                ax.set_ylabel(label)
            if r == 0:
                ax.set_title(f"robot {robot} (own frame G{robot.lstrip('r') or '?'})")
            if r == len(rows) - 1:
                ax.set_xlabel("time [s]")
            if c == n - 1 and r in (0, len(rows) - 1):
                handles, labels = ax.get_legend_handles_labels()
                if run.rendezvous():
                    handles.append(Line2D([], [], color="goldenrod", linestyle="--", label="rendezvous"))
                ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8,
                          borderaxespad=0.0)
    fig.suptitle(f"Estimation errors with ±3σ bands — {run.title()}")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)


def fmt(value, decimals):
    if isinstance(value, (int, float)) and not (isinstance(value, float) and math.isnan(value)):
        return f"{value:.{decimals}f}"
    return "-"


def summary_rows(run):
    header = ["robot", "pos. RMSE\n[m]", "head. RMSE\n[deg]", "lmk RMSE\n[m]", "dead reck.\nRMSE [m]",
              "landmarks\nmapped", "frames\nknown", "rendezvous\n(peer@step: err m, deg)"]
    rows = []
    for robot in run.robot_ids:
        data = run.summary.get("robots", {}).get(robot, {})
        events = [f"{e.get('peer', '?')}@{e.get('step', '?')}: {fmt(e.get('transform_error_m'), 2)}, "
                  f"{fmt(e.get('transform_error_deg'), 1)}" for e in data.get("rendezvous", []) or []]
        rows.append([robot, fmt(data.get("position_rmse_m"), 3), fmt(data.get("heading_rmse_deg"), 2),
                     fmt(data.get("landmark_rmse_m"), 3), fmt(data.get("dead_reckoning_rmse_m"), 3),
                     fmt(data.get("landmarks_mapped"), 0), ", ".join(data.get("frames_known", []) or []) or "-",
                     "\n".join(events) or "-"])
    return header, rows


def plot_overview(run, path):
    fig = plt.figure(figsize=(16, 9.5))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.15, 1.0], height_ratios=[1.0, 1.0], wspace=0.18, hspace=0.3)
    ax_traj = fig.add_subplot(grid[:, 0])
    draw_trajectories(ax_traj, run, legend_outside=False, legend_font=7)
    ax_traj.set_title("Trajectories and landmark tracks in G1")

    ax_err = fig.add_subplot(grid[0, 1])
    for robot in run.robot_ids:
        columns = run.metrics.get(robot)
        if not columns:
            continue
        ax_err.plot(columns.get("time_s", []), columns.get("position_err_m", []), "-", color=run.color(robot),
                    linewidth=1.3, label=f"{robot} position error")
        sx, sy = columns.get("sigma_x_m"), columns.get("sigma_y_m")
        if sx and sy:
            bound = [3.0 * math.hypot(a, b) for a, b in zip(sx, sy)]
            ax_err.plot(columns.get("time_s", []), bound, ":", color=run.color(robot), linewidth=1.0,
                        label=f"{robot} 3σ (√(σx²+σy²))")
        mark_rendezvous(ax_err, run, robot)
    if run.rendezvous():
        ax_err.plot([], [], "--", color="goldenrod", label="rendezvous")
    ax_err.set_xlabel("time [s]")
    ax_err.set_ylabel("position error [m]")
    ax_err.set_ylim(bottom=0)
    ax_err.grid(True, linewidth=0.4, alpha=0.5)
    ax_err.legend(fontsize=8, loc="upper left")
    ax_err.set_title("Position error in each robot's own frame")

    ax_table = fig.add_subplot(grid[1, 1])
    ax_table.axis("off")
    header, rows = summary_rows(run)
    table = ax_table.table(cellText=rows, colLabels=header, loc="upper center", cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(8.5)
    lines = max([1] + [cell.count("\n") + 1 for row in rows for cell in row])
    table.scale(1.0, 1.6 + 0.9 * (lines - 1))
    for (r, _), cell in table.get_celld().items():
        if r == 0:
            cell.set_height(cell.get_height() * 1.4)
            cell.set_facecolor("#e8e8e8")
    table.auto_set_column_width(list(range(len(header))))
    s = run.summary
    wall = s.get("wall_seconds")
    ax_table.set_title(f"Summary — {run.title()}" + (f", {wall:.1f} s wall time" if isinstance(wall, (int, float))
                                                      else ""))
    fig.suptitle(f"mrslam run overview: {run.title()}", fontsize=14)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        sys.stderr.write(__doc__)
        return 0 if len(argv) == 2 else EXIT_BAD_INPUT
    run = Run(argv[1])
    out = os.path.join(argv[1], "plots")
    os.makedirs(out, exist_ok=True)
    written = []
    for name, plot in (("trajectories.png", plot_trajectories), ("errors.png", plot_errors),
                       ("overview.png", plot_overview)):
        path = os.path.join(out, name)
        plot(run, path)
        written.append(path)
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
