"""Widgets the views share: a live plot, a state badge, a command's outcome."""
import time

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from .model import state_color

# Points a curve draws of its 10 s (about one per pixel of a plot's width): drawing lines is what a
# redraw costs most once the text is cached.
PLOT_POINTS = 600
PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b"]


def clock(t) -> str:
    """A wall-clock time as HH:MM:SS.mmm (local)."""
    if t is None:
        return ""
    return time.strftime("%H:%M:%S", time.localtime(t)) + f".{int((t % 1) * 1000):03d}"


# The unit of a topic's numbers, by the message type the gateway maps it to (SI, as the RT side
# has them; the axis adds a prefix, mm or µs, the same way on every plot).
UNITS = {"geometry_msgs::msg::dds_::PoseStamped_": "m", "geometry_msgs::msg::dds_::TwistStamped_": "m/s",
         "geometry_msgs::msg::dds_::WrenchStamped_": "N", "saw_msgs::msg::dds_::TaskStatistics_": "ns"}
UNITS_BY_NAME = {"tracking_error": "m", "force": "N", "measured_js": "rad", "measured_cv": "m/s"}


def units_of(endpoint) -> str:
    """The unit of an endpoint's numbers for a plot's axis ("" when the registry does not tell)."""
    if endpoint is None:
        return ""
    if endpoint.dds_type in UNITS:
        return UNITS[endpoint.dds_type]
    return next((u for k, u in UNITS_BY_NAME.items() if k in endpoint.name), "")


def newest(*series) -> float:
    """The newest sample time among (names, times, rows) series: the end of a view's common time axis."""
    ends = [s[1][-1] for s in series if len(s[1])]
    return max(ends) if ends else 0.0


class Plot(pg.PlotWidget):
    """The last seconds of one topic's numbers (x: seconds before the view's newest sample, the same
    for every plot of a view); a NaN row in the series (samples stopped) is drawn as a gap."""

    def __init__(self, title: str, units: str = "", parent=None):
        super().__init__(parent=parent, background="w")
        self.setTitle(title, color="k")
        self.setLabel("bottom", "time", units="s")
        self.set_units(units)
        self.showGrid(x=True, y=True, alpha=0.3)
        # An opaque legend with dark text: readable over the curves it names.
        self.addLegend(offset=(5, 5), brush=pg.mkBrush(255, 255, 255, 230), pen=pg.mkPen("#888"),
                       labelTextColor="k")
        self.curves = {}
        self.setMinimumHeight(160)
        self.setMinimumWidth(120)  # a long title must not push the plot out of its cell
        self.setXRange(-10, 0, padding=0)
        self.getViewBox().disableAutoRange()
        # An axis, its labels and the title are drawn once into a pixmap and then only copied, until
        # they change: redrawn text is most of what a redraw costs (measured: tools/gui_perf.py).
        for name in ("left", "bottom"):
            self.getAxis(name).setCacheMode(QtWidgets.QGraphicsItem.CacheMode.DeviceCoordinateCache)
        self.getPlotItem().titleLabel.setCacheMode(QtWidgets.QGraphicsItem.CacheMode.DeviceCoordinateCache)

    def set_units(self, units: str):
        self.units = units
        self.setLabel("left", "value" if units else "value (no unit declared)", units=units or None)

    def show_series(self, names, times, rows, scale: float = 1.0, t_end=None):
        if not len(times):
            return
        t_end = times[-1] if t_end is None else t_end
        xs = np.asarray(times) - t_end
        rows = np.asarray(rows)
        for i, n in enumerate(names):
            if n not in self.curves:
                # One number (std_msgs "data"): the title says what it is, no legend.
                label = None if names == ["data"] else ".".join(n.split(".")[-2:]) if n.count(".") > 1 else n
                self.curves[n] = self.plot([], [], pen=pg.mkPen(PALETTE[len(self.curves) % len(PALETTE)], width=1),
                                           name=label, connect="finite")
            self.curves[n].setData(xs, rows[:, i] * scale, connect="finite")
        legend = self.getPlotItem().legend
        if legend is not None and legend.isVisible() != bool(legend.items):
            legend.setVisible(bool(legend.items))  # (no empty box over a single, titled curve)
        self._fit_y(rows * scale)

    def _fit_y(self, ys):
        """Moves the y range only when the curves leave it or fill less than a third of it: the
        axis (its text, the costly part of a redraw) is redrawn then, not at every frame."""
        finite = ys[np.isfinite(ys)]
        if not finite.size:
            return
        lo, hi = float(finite.min()), float(finite.max())
        (vlo, vhi) = self.getViewBox().viewRange()[1]
        span = max(hi - lo, abs(hi) * 1e-3, 1e-9)
        if lo < vlo or hi > vhi or span < (vhi - vlo) / 3:
            self.setYRange(lo - 0.15 * span, hi + 0.15 * span, padding=0)


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
        self.failed = False

    def refused(self, why: str):
        self._show(why, "#d01010")
        self.command = None

    def clear_stale(self):
        """Forgets a failure said before the gateway came back (no live gateway, a refusal)."""
        if self.failed:
            self._show("", "#555")
            self.command, self.refusal = None, None

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
        self.failed = color == "#d01010"
        self.setText(text)
        self.setStyleSheet(f"QLabel {{ color: {color}; font-weight: bold; }}")
