"""Overlays sawrt's and cyclictest's wake-up histograms (cyclictest format) written by saw-jitter.

usage: plot_jitter.py DIR OUT_PREFIX   (writes OUT_PREFIX-idle.png, and -load.png if measured)
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    bins = []
    for line in open(path):
        if line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) >= 2:
            bins.append((int(parts[0]), int(parts[1])))
    return bins


def main(directory, prefix):
    for tag in ("idle", "load"):
        saw = os.path.join(directory, f"saw-{tag}.txt")
        cyc = os.path.join(directory, f"cyclictest-{tag}.txt")
        if not (os.path.exists(saw) and os.path.exists(cyc)):
            continue
        fig, ax = plt.subplots(figsize=(7, 4))
        for path, label in ((cyc, "cyclictest"), (saw, "sawrt 1 kHz task")):
            data = [(us, n) for us, n in read(path) if n > 0]
            if data:
                ax.step([d[0] for d in data], [d[1] for d in data], where="post", label=label)
        ax.set_yscale("log")
        ax.set_xscale("symlog", linthresh=100)
        ax.set_xlabel("wake-up latency (µs)")
        ax.set_ylabel("wake-ups")
        ax.set_title(f"1 kHz wake-up latency, {tag}: sawrt beside cyclictest (same priority and CPU)")
        ax.legend()
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        fig.savefig(f"{prefix}-{tag}.png", dpi=100)
        print(f"wrote {prefix}-{tag}.png")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
