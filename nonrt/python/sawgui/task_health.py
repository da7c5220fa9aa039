"""Task health: each periodic task's cycles, overruns and wake-up latencies (its
period_statistics read), live, where the gateway maps it."""
import pyqtgraph as pg
from PySide6 import QtWidgets

from sawdds import values

from . import model


class TaskHealth(QtWidgets.QWidget):
    def __init__(self, live, parent=None):
        super().__init__(parent)
        self.live = live
        self.note = QtWidgets.QLabel("")
        self.note.setWordWrap(True)
        self.table = QtWidgets.QTableWidget(0, 3)
        self.table.setHorizontalHeaderLabels(["task", "samples", "statistics"])
        self.hist = pg.PlotWidget(background="w", title="wake-up latency histogram")
        lay = QtWidgets.QVBoxLayout(self)
        lay.addWidget(self.note)
        lay.addWidget(self.table, 1)
        lay.addWidget(self.hist, 1)

    def refresh(self):
        for t in model.task_topics(self.live):
            self.live.watch(t)
        tasks = [(c, e) for c in self.live.components() for e in self.live.endpoints(c)
                 if e.name == "period_statistics"]
        unmapped = [c for c, e in tasks if not e.topic]
        mapped = [(c, e) for c, e in tasks if e.topic]
        if not tasks:
            self.note.setText("No gateway publishes a task's period_statistics: it needs the component's `task` "
                              "interface exported to the gateway and a DDS type for the statistics, which the "
                              "gateway does not map yet. saw-rt prints each task's cycles, overruns and wake-up "
                              "latencies when it stops.")
        elif unmapped:
            self.note.setText("period_statistics of " + ", ".join(unmapped) + " is listed by the gateway but not "
                              "mapped to a DDS type, so it cannot be shown here.")
        else:
            self.note.setText("")
        self.table.setRowCount(len(mapped))
        for i, (c, e) in enumerate(mapped):
            sample, _ = self.live.latest(e.topic)
            nums = {} if sample is None else values.numbers(sample)
            for j, text in enumerate([c, str(self.live.count(e.topic)),
                                      ", ".join(f"{k} {v:.4g}" for k, v in nums.items() if "[" not in k)]):
                self.table.setItem(i, j, QtWidgets.QTableWidgetItem(text))
            bins = [v for k, v in nums.items() if "[" in k]
            if bins and i == 0:
                self.hist.clear()
                self.hist.addItem(pg.BarGraphItem(x=list(range(len(bins))), height=bins, width=0.8, brush="#1f77b4"))
