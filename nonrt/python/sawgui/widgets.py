"""Widgets the views share: a live plot, a state badge, a command's outcome."""
import time

import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from .model import state_color

PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b"]


def clock(t) -> str:
    """A wall-clock time as HH:MM:SS.mmm (local)."""
    if t is None:
        return ""
    return time.strftime("%H:%M:%S", time.localtime(t)) + f".{int((t % 1) * 1000):03d}"


class Plot(pg.PlotWidget):
    """The last seconds of one topic's numbers (x: seconds before the newest sample)."""

    def __init__(self, title: str, units: str = "", parent=None):
        super().__init__(parent=parent, background="w")
        self.setTitle(title, color="k")
        self.setLabel("bottom", "time", units="s")
        if units:
            self.setLabel("left", "", units=units)
        self.showGrid(x=True, y=True, alpha=0.3)
        self.addLegend(offset=(5, 5))
        self.curves = {}
        self.setMinimumHeight(160)
        self.setMinimumWidth(120)  # a long title must not push the plot out of its cell

    def show_series(self, names, times, rows, scale: float = 1.0):
        if not times:
            return
        t_end = times[-1]
        xs = [t - t_end for t in times]
        for i, n in enumerate(names):
            if n not in self.curves:
                # One number (std_msgs "data"): the title says what it is, no legend.
                label = None if names == ["data"] else ".".join(n.split(".")[-2:]) if n.count(".") > 1 else n
                self.curves[n] = self.plot([], [], pen=pg.mkPen(PALETTE[len(self.curves) % len(PALETTE)], width=2),
                                           name=label)
            self.curves[n].setData(xs, [r[i] * scale for r in rows])


class StateBadge(QtWidgets.QLabel):
    """An operating state in a coloured box; FAULT is red and large."""

    def __init__(self, parent=None):
        super().__init__("—", parent)
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.setMinimumWidth(140)
        self.set_state("")

    def set_state(self, state: str):
        color = state_color(state)
        self.setText(state or "(no state yet)")
        self.setStyleSheet(f"QLabel {{ background: {color}; color: white; font-weight: bold; font-size: 18px;"
                           f" padding: 6px 14px; border-radius: 6px; }}")
        self.state = state


class Outcome(QtWidgets.QLabel):
    """What became of a command: refused by the form, delivered, or refused by the gateway (its
    reason, from the component's error topic)."""

    def __init__(self, parent=None):
        super().__init__("", parent)
        self.setWordWrap(True)
        self.command = None
        self.errors_seen = 0
        self.sent_at = 0.0
        self.refusal = None

    def refused(self, why: str):
        self._show(why, "#d01010")
        self.command = None

    def sending(self, command: str, errors_now: int):
        self.command, self.errors_seen, self.sent_at = command, errors_now, time.monotonic()
        self.refusal = None
        self._show(f"{command}: sending…", "#555")

    def delivered(self, ok: bool, text: str):
        # The gateway's refusal can arrive before word that the command left: it is kept.
        if self.refusal is None:
            self._show(f"{self.command or ''}: {text}", "#1f9d3a" if ok else "#d01010")

    def check_errors(self, live, component: str):
        """Shows the gateway's refusal of our command when one arrives."""
        if self.command is None:
            return
        self.errors_seen, new = live.errors_after(component, self.errors_seen)
        for _, text in new:
            if text.startswith(self.command):
                self._show("refused by the gateway: " + text, "#d01010")
                self.refusal = text

    def _show(self, text, color):
        self.setText(text)
        self.setStyleSheet(f"QLabel {{ color: {color}; font-weight: bold; }}")
