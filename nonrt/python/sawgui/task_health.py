"""Task health: each periodic task's cycles, overruns and wake-up latencies (its
period_statistics read, which the gateway publishes with the component's interface), live."""
import pyqtgraph as pg
from PySide6 import QtGui, QtWidgets

from . import model

COLUMNS = ["task", "period (ms)", "cycles", "overruns", "missed", "wake-up now (µs)", "wake-up max (µs)",
           "compute mean (µs)", "compute max (µs)"]
BIN_US = 5.0  # histogram bin width


def histogram(latencies_us, bin_us: float = BIN_US):
    """(left edges, counts) of wake-up latencies in µs, in bins of `bin_us`; empty if none."""
    if not latencies_us:
        return [], []
    top = int(max(latencies_us) // bin_us) + 1
    counts = [0] * top
    for x in latencies_us:
        counts[min(int(max(x, 0.0) // bin_us), top - 1)] += 1
    return [i * bin_us for i in range(top)], counts


class TaskHealth(QtWidgets.QWidget):
    def __init__(self, live, parent=None):
        super().__init__(parent)
        self.live = live
        self.note = QtWidgets.QLabel("")
        self.note.setWordWrap(True)
        self.table = QtWidgets.QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeToContents)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        self.hist = pg.PlotWidget(background="w")
        self.hist.setLabel("bottom", "wake-up latency (µs)")
        self.hist.setLabel("left", "cycles")
        lay = QtWidgets.QVBoxLayout(self)
        lay.addWidget(self.note)
        lay.addWidget(self.table, 1)
        lay.addWidget(self.hist, 1)
        self.rows = []  # (component, topic) in table order

    def refresh(self):
        for t in model.task_topics(self.live):
            self.live.watch(t)
        self.rows = [(c, e.topic) for c in sorted(self.live.components()) for e in self.live.endpoints(c)
                     if e.name == "period_statistics" and e.kind == "read" and e.topic]
        if not self.rows:
            self.note.setText("No gateway publishes a task's period_statistics yet (a component exported by an RT "
                              "process carries its task's; this view fills when one is there).")
        else:
            self.note.setText("Cycles, overruns and maxima are the task's own, since it started; the histogram "
                              "counts the wake-up latencies of the samples received in the last 10 s.")
        self.table.setRowCount(len(self.rows))
        for i, (component, topic) in enumerate(self.rows):
            sample, _ = self.live.latest(topic)
            cells = [component] + ([""] * (len(COLUMNS) - 1) if sample is None else [
                f"{sample.period / 1e6:.3g}", str(sample.cycles), str(sample.overruns), str(sample.missed_periods),
                f"{sample.last_wakeup_latency / 1e3:.1f}", f"{sample.max_wakeup_latency / 1e3:.1f}",
                f"{sample.mean_compute / 1e3:.1f}", f"{sample.max_compute / 1e3:.1f}"])
            for j, text in enumerate(cells):
                item = QtWidgets.QTableWidgetItem(text)
                if j == 3 and sample is not None and sample.overruns > 0:
                    item.setForeground(QtGui.QBrush(QtGui.QColor("#c62828")))
                self.table.setItem(i, j, item)
        self.draw_histogram()

    def draw_histogram(self):
        """The selected task's (or the first's) wake-up latencies over the window."""
        if not self.rows:
            self.hist.clear()
            return
        selected = self.table.currentRow()
        component, topic = self.rows[selected if 0 <= selected < len(self.rows) else 0]
        names, _, rows = self.live.series(topic, max_points=10**6)
        if "last_wakeup_latency" not in names:
            return
        k = names.index("last_wakeup_latency")
        edges, counts = histogram([r[k] / 1e3 for r in rows if r[k] == r[k]])  # (not the NaN of a gap)
        self.hist.clear()
        self.hist.setTitle(f"{component}: wake-up latency, {sum(counts)} samples")
        if counts:
            self.hist.addItem(pg.BarGraphItem(x0=edges, width=BIN_US * 0.9, height=counts, brush="#1f77b4"))
