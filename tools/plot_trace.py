#!/usr/bin/python3
"""Plots det Sigma over time from an aia trace.csv (the paper's figures 3c/3d).

Left panel, per robot: the sum over targets of robot i's det Sigma_i^k (the
paper's per-node sum, its figures 3c and 5a); failed robots dashed. Right
panel, per target: min over robots of det Sigma_i^k, the team's uncertainty,
which the mission judges against eps (figure 3d). Both on a log scale, with
the threshold eps as a dashed line.

eps comes from --eps, else from the summary next to the trace: PREFIX.summary.json
for PREFIX.trace.csv (written by `aia render`), else summary.json in the same
folder (written by `aia run`).

Usage:
  tools/plot_trace.py renders/default/trace.csv --out renders/default/trace.png

Later plots follow the same pattern: a function FIGURE(trace, summary, args)
that returns a matplotlib figure, registered in FIGURES and picked with
--figure; the helpers below (robot_color, load_trace, load_summary) are
importable by other scripts under tools/.
"""

import argparse
import colorsys
import csv
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tool_io import BadInput, pyplot, save_figure  # noqa: E402

plt = pyplot()  # headless; where matplotlib is missing, its first use says so


def robot_color(i):
    """Robot i's colour, the same as in the MJCF and the videos (world/mjcf.cc)."""
    h = (0.08 + i * 0.61803398875) % 1.0
    return colorsys.hsv_to_rgb(h, 0.75, 0.9)


class Trace:
    """trace.csv as arrays: steps (T,), min_det (T, M), det (T, N, M)."""

    def __init__(self, steps, min_det, det):
        self.steps = steps
        self.min_det = min_det
        self.det = det

    @property
    def num_robots(self):
        return self.det.shape[1]

    @property
    def num_targets(self):
        return self.det.shape[2]


def load_trace(path):
    """Reads step,target,min_det,det_r0..det_r{N-1} rows into a Trace
    (step,time,target,... with mission.decisions async: the time column is
    dropped, steps are then the sensing ticks)."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            timed = header is not None and header[:2] == ["step", "time"]
            if timed:
                header = header[:1] + header[2:]
            if header is None or header[:3] != ["step", "target", "min_det"]:
                raise BadInput(f"{path}: not an aia trace (header {header})")
            robots = [h for h in header[3:] if h.startswith("det_r")]
            rows = [(reader.line_num, r[:1] + r[2:] if timed else r)
                    for r in reader if r]
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise BadInput(f"{path}: {getattr(e, 'strerror', None) or e}") from None
    if not rows:
        raise BadInput(f"{path}: no rows")

    def whole(line, text, what):
        try:
            value = int(text)
        except ValueError:
            value = -1
        if value < 0:
            raise BadInput(f"{path}:{line}: {what}: must be a whole number "
                           f">= 0, got {text!r}")
        return value

    def real(line, text, what):
        try:
            return float(text)
        except ValueError:
            raise BadInput(f"{path}:{line}: {what}: not a number, got "
                           f"{text!r}") from None

    parsed = []
    for line, r in rows:
        if len(r) != 3 + len(robots):
            raise BadInput(f"{path}:{line}: {len(r)} fields, the header has "
                           f"{3 + len(robots)}")
        parsed.append((whole(line, r[0], "step"), whole(line, r[1], "target"),
                       real(line, r[2], "min_det") if r[2] else np.nan,
                       [real(line, x, "det") for x in r[3:]]))
    steps = sorted({p[0] for p in parsed})
    # Targets are numbered 0..M-1 (every target has a row at every step).
    num_targets = max(p[1] for p in parsed) + 1
    index = {s: n for n, s in enumerate(steps)}
    min_det = np.full((len(steps), num_targets), np.nan)
    det = np.full((len(steps), len(robots), num_targets), np.nan)
    for step, k, low, dets in parsed:
        t = index[step]
        min_det[t, k] = low  # NaN: no robot active
        det[t, :, k] = dets
    return Trace(np.array(steps), min_det, det)


def summary_path(trace_path):
    """The summary written with a trace, or None."""
    folder, name = os.path.split(trace_path)
    candidates = []
    if name.endswith(".trace.csv"):
        candidates.append(os.path.join(folder, name[: -len(".trace.csv")] + ".summary.json"))
    candidates.append(os.path.join(folder, "summary.json"))
    for c in candidates:
        if os.path.isfile(c):
            return c
    return None


def load_summary(trace_path, explicit=None):
    path = explicit or summary_path(trace_path)
    if path is None:
        return {}
    try:
        with open(path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise BadInput(f"{path}: {getattr(e, 'strerror', None) or e}") from None
    if not isinstance(summary, dict):
        raise BadInput(f"{path}: not a run's summary (a JSON object)")
    eps = summary.get("eps")
    if eps is not None and (isinstance(eps, bool) or
                            not isinstance(eps, (int, float))):
        raise BadInput(f"{path}: eps: must be a number, got {eps!r}")
    failed = summary.get("failed_robots", [])
    if not isinstance(failed, list):
        raise BadInput(f"{path}: failed_robots: must be a list, got {failed!r}")
    return summary


def _threshold(ax, eps):
    if eps is not None:
        ax.axhline(eps, color="tab:blue", linestyle="--", linewidth=1.2, label=f"eps = {eps:g}")


def figure_uncertainty(trace, summary, args):
    """det Sigma per robot (sum over targets) and per target (min over robots)."""
    eps = args.eps if args.eps is not None else summary.get("eps")
    failed = set(summary.get("failed_robots", []))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)

    per_robot = np.nansum(trace.det, axis=2)  # (T, N)
    for i in range(trace.num_robots):
        ax_kw = dict(color=robot_color(i), linewidth=1.2)
        if i in failed:
            ax_kw.update(linestyle="--", label=f"robot {i} (failed)")
        elif trace.num_robots <= 12:
            ax_kw["label"] = f"robot {i}"
        left.plot(trace.steps, per_robot[:, i], **ax_kw)
    if trace.num_robots == 0:  # a trace written with `aia run --trace min`
        left.text(0.5, 0.5, "per-robot columns not in this trace\n(aia run --trace full)",
                  ha="center", va="center", transform=left.transAxes, fontsize=9)
    _threshold(left, eps)
    left.set_title(r"per robot $i$: sum over targets $k$ of $\det \Sigma_i^k$", fontsize=10)

    cmap = plt.get_cmap("tab10" if trace.num_targets <= 10 else "viridis")
    for k in range(trace.num_targets):
        color = cmap(k if trace.num_targets <= 10 else k / max(1, trace.num_targets - 1))
        label = f"target {k}" if trace.num_targets <= 12 else None
        right.plot(trace.steps, trace.min_det[:, k], color=color, linewidth=1.2, label=label)
    _threshold(right, eps)
    right.set_title(r"per target $k$: min over robots $i$ of $\det \Sigma_i^k$", fontsize=10)

    for ax in (left, right):
        ax.set_yscale("log")
        ax.set_xlabel("decision step t")
        ax.grid(True, which="major", alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        if handles:
            ax.legend(fontsize=7, ncol=2, loc="best", framealpha=0.8)
    left.set_ylabel(r"$\det \Sigma$")
    title = args.title
    if title is None and summary:
        title = "{scenario}: {policy}, seed {seed}, {robots} robots, {targets} targets".format(
            **{k: summary.get(k, "?") for k in ("scenario", "policy", "seed", "robots", "targets")})
        if summary.get("success"):
            title += f", localized at step {summary.get('flowtime')}"
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


FIGURES = {"uncertainty": figure_uncertainty}


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Plot det Sigma over time from an aia trace.csv (per robot and per "
        "target, log scale, with the eps line).")
    parser.add_argument("trace", help="trace.csv written by `aia run` or `aia render`")
    parser.add_argument("--out", help="PNG to write (default: the trace's name with .png)")
    parser.add_argument("--figure", choices=sorted(FIGURES), default="uncertainty",
                        help="which figure (default: uncertainty)")
    parser.add_argument("--summary", help="summary JSON (default: found next to the trace)")
    parser.add_argument("--eps", type=float, help="threshold line (default: eps from the summary)")
    parser.add_argument("--title", help="figure title (default: from the summary)")
    parser.add_argument("--dpi", type=int, default=120, help="resolution (default: 120)")
    args = parser.parse_args(argv)
    if args.dpi < 1:
        raise BadInput(f"--dpi: must be at least 1, got {args.dpi}")
    trace = load_trace(args.trace)
    summary = load_summary(args.trace, args.summary)
    out = args.out or os.path.splitext(args.trace)[0] + ".png"
    fig = FIGURES[args.figure](trace, summary, args)
    save_figure(fig, out, args.dpi, inputs=[args.trace])
    print(out)
    return 0


if __name__ == "__main__":
    from tool_io import run
    run(main)
