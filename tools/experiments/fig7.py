#!/usr/bin/env python3
"""Reproduces the paper's Fig. 7: master/slave tracking with injected delays, with and without
the Euler-prediction local model. Runs saw-rt on the stepped clock (deterministic, faster than
real time), writes PNG plots and a table of lag and RMS tracking error into docs/experiments.md."""
import argparse
import os
import pathlib
import subprocess
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
DELAYS_MS = [0, 10, 20, 50]
DURATION = 12.0
SETTLE = 2.0  # seconds ignored at the start of each run

HANDS = {
    "line": "{type: line, from: [0.0, 0, 0], to: [0.04, 0, 0], duration: 1.0, back_and_forth: true, stiffness: 200}",
    "sinusoid": "{type: sinusoid, amplitude: [0.03, 0, 0], frequency: 0.5, stiffness: 200}",
}


def deployment(hand: str, delay_ms: int, predict: bool) -> str:
    delay = f"{delay_ms}ms"
    chain_master = "master_delay" if delay_ms else "master"
    delays = ""
    links = ""
    if delay_ms:
        delays = f"""
  - {{name: master_delay, type: delay, task: {{period: 1ms}}, params: {{delay: {delay}}}}}"""
        links = """
  - {client: master_delay, required: source, server: master, provided: arm}"""
    return f"""deployment: {{name: fig7, clock: stepped}}
components:
  - {{name: master, type: sim_haptic_device, task: {{period: 1ms}}, params: {{model: omni, hand: {HANDS[hand]}}}}}
  - {{name: slave, type: sim_haptic_device, task: {{period: 1ms}}, params: {{model: omni}}}}{delays}
  - name: teleop
    type: teleop
    task: {{period: 1ms}}
    params:
      gains: {{master: 0, slave: 300}}
      force_limits: {{master: 3, slave: 3}}
      stale_timeout: 100ms
      prediction: {{enabled: {str(predict).lower()}, master: {delay}}}
connections:{links}
  - {{client: teleop, required: master, server: {chain_master}, provided: arm}}
  - {{client: teleop, required: slave, server: slave, provided: arm}}
record:
  columns: [master.measured_cp, slave.measured_cp]
"""


def run(saw_rt: pathlib.Path, work: pathlib.Path, hand: str, delay_ms: int, predict: bool):
    name = f"{hand}_{delay_ms}ms_{'pred' if predict else 'nopred'}"
    cfg = work / f"{name}.yaml"
    csv = work / f"{name}.csv"
    cfg.write_text(deployment(hand, delay_ms, predict))
    subprocess.run([str(saw_rt), str(cfg), "--duration", str(DURATION), "--record", str(csv)], check=True,
                   stdout=subprocess.DEVNULL)
    data = np.genfromtxt(csv, delimiter=",", names=True)
    t = data["time"]
    m = data["mastermeasured_cpx"]
    s = data["slavemeasured_cpx"]
    return t, m, s


def lag_seconds(t, master, slave):
    """Lag of slave behind master at the cross-correlation peak (positive: slave late)."""
    keep = t >= SETTLE
    a = master[keep] - master[keep].mean()
    b = slave[keep] - slave[keep].mean()
    dt = float(np.median(np.diff(t)))
    n = len(a)
    best, best_lag = -np.inf, 0
    for lag in range(-200, 201):  # ±200 samples; c(L) = Σ slave[k]·master[k − L]
        c = np.dot(b[lag:], a[: n - lag]) if lag >= 0 else np.dot(b[: n + lag], a[-lag:])
        if c > best:
            best, best_lag = c, lag
    return best_lag * dt


def rms(t, master, slave):
    keep = t >= SETTLE
    return float(np.sqrt(np.mean((slave[keep] - master[keep]) ** 2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--saw-rt", default=str(ROOT / "build/release/bin/saw-rt"))
    ap.add_argument("--out", default=str(ROOT / "docs"))
    args = ap.parse_args()
    saw_rt = pathlib.Path(args.saw_rt)
    out = pathlib.Path(args.out)
    (out / "img").mkdir(parents=True, exist_ok=True)
    work = ROOT / "build/experiments"
    work.mkdir(parents=True, exist_ok=True)

    rows = []
    for hand in HANDS:
        fig, axes = plt.subplots(len(DELAYS_MS), 2, figsize=(11, 2.3 * len(DELAYS_MS)), sharex=True, sharey=True)
        for i, delay in enumerate(DELAYS_MS):
            for j, predict in enumerate([False, True]):
                t, m, s = run(saw_rt, work, hand, delay, predict)
                lag = lag_seconds(t, m, s)
                err = rms(t, m, s)
                rows.append((hand, delay, predict, lag, err))
                ax = axes[i][j]
                base = m[0]
                ax.plot(t, (m - base) * 1e3, label="master", lw=1.2)
                ax.plot(t, (s - base) * 1e3, label="slave", lw=1.0, ls="--")
                ax.set_title(f"{hand}, delay {delay} ms, prediction {'on' if predict else 'off'}: "
                             f"lag {lag * 1e3:.0f} ms, RMS {err * 1e3:.2f} mm", fontsize=8)
                ax.set_xlim(SETTLE, SETTLE + 6)
                ax.grid(alpha=0.3)
                if j == 0:
                    ax.set_ylabel("x (mm)")
        axes[0][0].legend(loc="upper right", fontsize=7)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        fig.tight_layout()
        fig.savefig(out / "img" / f"fig7_{hand}.png", dpi=90)
        plt.close(fig)
        print(f"wrote {out / 'img' / f'fig7_{hand}.png'}", file=sys.stderr)

    lines = [
        "# Experiments: the paper's Fig. 7",
        "",
        "Master/slave position tracking of the simulated Omni-like devices, 1 kHz. The teleoperation",
        "task sits beside the slave; a delay task between the master and it injects a one-way delay",
        "on the master's positions (the network), with and without the Euler-prediction local model",
        "(paper eq. 7, the master's horizon = the delay). Forces reach the devices without added delay. Delaying",
        "the slave's own position inside its local loop as well (the paper's DelayTask delays both",
        "devices) makes a stiff loop around a light arm unstable here, so it is not what is shown.",
        "As in the paper (\"we fed the sinusoidal wave to the master device, and let the slave",
        "device follow\"), the master's force-feedback gain is 0 in these runs: with it, a delayed",
        "position in the master's own loop oscillates at 10 ms and more unless prediction is on (a",
        "bilateral law with delay needs passivity tools this paper did not have). The master is driven by the",
        "scripted hand through a 200 N/m virtual spring: a back-and-forth line (4 cm in 1 s) and a",
        "0.5 Hz sinusoid of 3 cm. Slave gain 300 N/m, force limits 3 N. Deterministic: saw-rt on the",
        "stepped clock, 12 s per run, the first 2 s ignored.",
        "",
        "Command: `tools/fig7.sh` (regenerates this file and `docs/img/fig7_*.png`).",
        "",
        "Lag is the shift (1 ms steps, within ±200 ms) that maximises the correlation of slave and",
        "master positions; for the back-and-forth line (a triangle wave) that peak is broad and the",
        "figure coarse: its RMS error is the better measure.",
        "",
        "| hand | delay (ms) | prediction | lag at the cross-correlation peak (ms) | RMS tracking error (mm) |",
        "|---|---|---|---|---|",
    ]
    for hand, delay, predict, lag, err in rows:
        lines.append(f"| {hand} | {delay} | {'on' if predict else 'off'} | {lag * 1e3:.0f} | {err * 1e3:.3f} |")
    by = {(h, d, p): (lag, err) for h, d, p, lag, err in rows}
    no_delay = max(by[(h, 0, False)][1] for h in HANDS)
    lag20 = by[("sinusoid", 20, True)][0]
    lag20_off = by[("sinusoid", 20, False)][0]
    base = by[("sinusoid", 0, False)][0]  # the slave's own tracking lag, with no delay at all
    added = lag20 - base
    lines += [
        "",
        "Goals:",
        f"- without delay the slave tracks the master within 1 mm RMS: worst {no_delay * 1e3:.3f} mm — "
        f"{'met' if no_delay <= 1e-3 else 'NOT met'};",
        f"- at 20 ms delay on the 0.5 Hz sinusoid, prediction cuts the lag to ≤ 20 % of the delay (4 ms). "
        f"Measured lag {lag20 * 1e3:.0f} ms with prediction, {lag20_off * 1e3:.0f} ms without. Of that, "
        f"{base * 1e3:.0f} ms is the slave's own tracking lag, there with no delay at all (the spring-damper "
        f"slave behind a 1 kHz loop); the lag the delay adds is {added * 1e3:.0f} ms with prediction, "
        f"{(lag20_off - base) * 1e3:.0f} ms without — "
        f"{'met' if abs(added) <= 0.004 else 'NOT met'} for the added lag, "
        f"{'met' if abs(lag20) <= 0.004 else 'not met'} for the total lag (lag resolution: 1 ms, one sample).",
        "",
        "![line](img/fig7_line.png)",
        "",
        "![sinusoid](img/fig7_sinusoid.png)",
        "",
    ]
    # The bilateral section (tools/experiments/bilateral.py) follows its marker: kept as it is.
    doc = out / "experiments.md"
    marker = "<!-- bilateral: generated by tools/bilateral.sh from here on -->"
    rest = doc.read_text().split(marker, 1) if doc.exists() else [""]
    tail = "\n" + marker + rest[1] if len(rest) == 2 else ""
    doc.write_text("\n".join(lines) + tail)
    print("\n".join(lines[11:]))


if __name__ == "__main__":
    main()
