"""Plots saw-latency's CSV in the style of the paper's Fig. 4 (latency per configuration).

usage: plot_latency.py TABLE.csv OUT.png
Bars are medians, whiskers reach p99; the y axis is logarithmic (0.02 µs to milliseconds).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Path (prefix of the CSV's path column) -> legend label, in drawing order.
SERIES = [
    ("qualified read, two threads", "sawrt, in process"),
    ("qualified read over the shared-memory bridge", "sawrt, shared-memory bridge"),
    ("qualified read, both gateways", "sawrt, both gateways (bridge, DDS, bridge)"),
    ("qualified read, DDS peer", "DDS peer -> sawrt gateway -> bridge"),
    ("raw Fast DDS", "raw Fast DDS (baseline)"),
    ("ZeroC Ice", "ZeroC Ice 3.7 (baseline, the paper's)"),
]


def main(table, out):
    rows = list(csv.DictReader(open(table)))
    configs = []
    for r in rows:
        if r["configuration"] not in configs:
            configs.append(r["configuration"])
    fig, ax = plt.subplots(figsize=(9, 4.8))
    width = 0.8 / len(SERIES)
    for k, (prefix, label) in enumerate(SERIES):
        xs, medians, lo, hi = [], [], [], []
        for i, c in enumerate(configs):
            for r in rows:
                if r["configuration"] == c and r["path"].startswith(prefix) and int(r["n"]) > 0:
                    med, p99 = float(r["median_us"]), float(r["p99_us"])
                    xs.append(i + (k - (len(SERIES) - 1) / 2) * width)
                    medians.append(med)
                    lo.append(0)
                    hi.append(max(p99 - med, 0))
        if xs:
            ax.bar(xs, medians, width, label=label, yerr=[lo, hi], capsize=2)
            for x, m, h in zip(xs, medians, hi):
                ax.text(x, (m + h) * 1.1, f"{m:.3g}", ha="center", va="bottom", fontsize=7, rotation=90)
    ax.set_xticks(range(len(configs)))
    ax.set_xticklabels(configs)
    ax.set_yscale("log")
    ax.set_ylim(top=ax.get_ylim()[1] * 4)
    ax.set_ylabel("qualified read of a double, round trip (µs)\nbar: median, whisker: p99")
    ax.set_title("Networking overhead (the paper's Fig. 4), sawrt beside Ice and raw Fast DDS")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
