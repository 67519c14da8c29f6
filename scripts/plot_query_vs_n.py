#!/usr/bin/python3
"""Query time against the number of stored frames, every search mode on one plot.

Usage:
  scripts/plot_query_vs_n.py OUT.svg DISTRACTORS.json... [--nodes BENCH.json]

DISTRACTORS.json: what `lsgd bench --distractors N --json F` wrote (one per
N; every mode in its "modes"). BENCH.json: what plain `lsgd bench --mode nodes
--json F` wrote; its query_growth rows give the nodes mode's query time as
the map grows (nodes cannot take distractors: their groups are built by
running Algorithm 1 over every frame). Prints the table it plotted.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    out, args = argv[1], argv[2:]
    nodes = None
    if "--nodes" in args:
        k = args.index("--nodes")
        nodes = args[k + 1]
        args = args[:k] + args[k + 2:]
    inputs = args + ([nodes] if nodes else [])
    if any(os.path.realpath(out) == os.path.realpath(p) for p in inputs):
        sys.exit(f"plot_query_vs_n.py: {out} is one of the inputs; it is never overwritten")
    series = {}  # mode -> [(frames, median, p95)]
    for path in args:
        with open(path) as f:
            j = json.load(f)
        for m in j["modes"]:
            series.setdefault(m["mode"], []).append((m["frames"], m["query_ms_median"], m["query_ms_p95"]))
    if nodes:
        with open(nodes) as f:
            j = json.load(f)
        rows = j["query_growth"]["rows"]
        series["nodes (no distractors)"] = [(r["stored_frames"], r["query_ms_median"], None) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for mode, points in sorted(series.items()):
        points.sort()
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=mode)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("stored frames")
    ax.set_ylabel("query ms (median)")
    ax.set_title("Query time against map size (1241x376, compact, single thread)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out)
    print("| mode | stored frames | query ms median | p95 |")
    print("|---|---|---|---|")
    for mode, points in sorted(series.items()):
        for frames, median, p95 in points:
            print(f"| {mode} | {frames:,} | {median:.2f} | {'-' if p95 is None else f'{p95:.2f}'} |")


if __name__ == "__main__":
    main(sys.argv)
