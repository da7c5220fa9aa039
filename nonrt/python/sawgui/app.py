"""The main window: system view, teleoperation, components and task health in tabs, refreshed
from sawdds.Live (whose threads do every DDS read and write) by a Qt timer."""
import collections
import os
import time

from PySide6 import QtCore, QtWidgets

from . import model
from .component_view import ComponentView
from .system_view import SystemView
from .task_health import TaskHealth
from .teleop_panel import TeleopPanel

# 25 redraws a second: a 50 ms timer would make 20/s only when no tick is ever late.
REFRESH_MS = 40


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, live, domain: int, interface: str):
        super().__init__()
        self.live = live
        self.setWindowTitle(f"sawgui — DDS domain {domain} on {interface}")
        self.resize(1200, 820)
        self.tabs = QtWidgets.QTabWidget()
        self.system = SystemView(live)
        # A FAULT (or a component gone) is said above the tabs: seen whichever tab is open.
        central = QtWidgets.QWidget()
        cl = QtWidgets.QVBoxLayout(central)
        cl.setContentsMargins(4, 4, 4, 4)
        cl.addWidget(self.system.banner)
        cl.addWidget(self.tabs, 1)
        self.setCentralWidget(central)
        self.tabs.addTab(self.system, "System")
        self.teleop = None  # made when the registry shows a teleoperation
        self.components = QtWidgets.QWidget()
        cl = QtWidgets.QVBoxLayout(self.components)
        self.picker = QtWidgets.QComboBox()
        self.stack = QtWidgets.QStackedWidget()
        cl.addWidget(self.picker)
        cl.addWidget(self.stack, 1)
        self.views = {}
        self.picker.currentTextChanged.connect(self.show_component)
        self.tabs.addTab(self.components, "Components")
        self.tasks = TaskHealth(live)
        self.tabs.addTab(self.tasks, "Task health")
        self.status = QtWidgets.QLabel("")
        self.statusBar().addWidget(self.status, 1)
        self.recording = None
        tb = self.addToolBar("tools")
        self.record_action = tb.addAction("Record (MCAP + CSV)", lambda: self.toggle_recording())
        tb.addAction("Save plots as PNG", self.save_plots)
        self.refreshed = collections.deque(maxlen=2000)  # monotonic times of the redraws (tools/gui_perf.py)
        self.tabs.currentChanged.connect(lambda _: self.refresh())  # a tab shows its state at once
        self.timer = QtCore.QTimer(self)
        self.timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self.timer.timeout.connect(self.refresh)
        self.timer.start(REFRESH_MS)

    def show_component(self, name: str):
        if not name:
            return
        if name not in self.views:
            self.views[name] = ComponentView(self.live, name)
            self.stack.addWidget(self.views[name])
        self.stack.setCurrentWidget(self.views[name])

    def refresh(self):
        if getattr(self, "_refreshing", False):  # (a tab inserted or switched from within)
            return
        self._refreshing = True
        try:
            self._refresh()
        finally:
            self._refreshing = False

    def _refresh(self):
        for tag, ok, text in self.live.results():
            if callable(tag):
                tag(ok, text)
        comps = self.live.components()
        names = sorted(comps)
        if names != [self.picker.itemText(i) for i in range(self.picker.count())]:
            current = self.picker.currentText()
            self.picker.blockSignals(True)
            self.picker.clear()
            self.picker.addItems(names)
            self.picker.blockSignals(False)
            self.picker.setCurrentText(current if current in names else names[0])
            self.show_component(self.picker.currentText())
        if self.teleop is None:
            t = model.teleop_components(self.live)
            if t:
                self.teleop = TeleopPanel(self.live, t[0])
                self.tabs.insertTab(1, self.teleop, "Teleoperation")
        current = self.tabs.currentWidget()
        # The FAULT banner, above every tab, at every tick; the system tree while it is shown.
        if current is self.system:
            self.system.refresh()
        else:
            self.system.refresh_banner()
        if current is self.components and self.stack.currentWidget() is not None:
            self.stack.currentWidget().refresh()
        elif current is not self.system and hasattr(current, "refresh"):
            current.refresh()
        gws = self.live.gateways()
        faults = len(self.system.faults)
        rec = self.live.recording() if self.recording else None
        self.status.setText(f"{sum(g['alive'] for g in gws.values())} gateway(s) alive, {len(comps)} component(s)"
                            + (f", {faults} in FAULT" if faults else "")
                            + (f"; recording to {self.recording}" + ("" if rec and rec["ready"] else " (starting…)")
                               if self.recording else ""))
        self.status.setStyleSheet("QLabel { color: #d01010; font-weight: bold; }" if faults else "")
        if rec and rec["error"]:
            self.statusBar().showMessage(f"recording failed: {rec['error']}", 15000)
        self.refreshed.append(time.monotonic())

    def choose_topics(self) -> list:
        """Asks which of the topics the window reads to record (all checked to begin with)."""
        dialog = QtWidgets.QDialog(self)
        dialog.setWindowTitle("Record which topics?")
        lay = QtWidgets.QVBoxLayout(dialog)
        listing = QtWidgets.QListWidget()
        for t in self.live.watched():
            item = QtWidgets.QListWidgetItem(t)
            item.setFlags(item.flags() | QtCore.Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(QtCore.Qt.CheckState.Checked)
            listing.addItem(item)
        lay.addWidget(listing)
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Ok
                                             | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(dialog.accept)
        buttons.rejected.connect(dialog.reject)
        lay.addWidget(buttons)
        if dialog.exec() != QtWidgets.QDialog.DialogCode.Accepted:
            return []
        return [listing.item(i).text() for i in range(listing.count())
                if listing.item(i).checkState() == QtCore.Qt.CheckState.Checked]

    def toggle_recording(self, directory: str = "", topics=None):
        """Starts recording `topics` (by default those chosen in a dialog, among what the window reads)
        to <directory>/recording.mcap (ROS 2 types) and a CSV file per topic, by a recorder process
        of its own (every sample, counting what it missed); or stops it and returns the recorder's
        summary (its files and, per topic, the samples and what was missed)."""
        if self.recording:
            summary = self.live.stop_recording() or {"files": [], "topics": {}}
            n = sum(t["samples"] for t in summary["topics"].values())
            missed = sum(t["missed"] for t in summary["topics"].values())
            if "error" in summary:
                text = f"recording failed: {summary['error']}"
            else:
                text = (f"recorded {n} samples in {len(summary['files'])} file(s) in {self.recording}; "
                        + (f"MISSED {missed} sample(s) (see the recorder's summary)" if missed else "none missed"))
            self.statusBar().showMessage(text, 15000)
            self.recording = None
            self.record_action.setText("Record (MCAP + CSV)")
            return summary
        topics = self.choose_topics() if topics is None else topics
        if not topics:
            return None
        directory = directory or QtWidgets.QFileDialog.getExistingDirectory(self, "Record into")
        if not directory:
            return None
        self.live.record(topics, directory)
        self.recording = directory
        self.record_action.setText("Stop recording")
        return None

    def save_plots(self, path: str = ""):
        """Saves the open tab (its plots) as a PNG."""
        if not path:
            path, _ = QtWidgets.QFileDialog.getSaveFileName(
                self, "Save as PNG", os.path.join(os.getcwd(), f"sawgui-{time.strftime('%H%M%S')}.png"), "PNG (*.png)")
        if path:
            self.tabs.currentWidget().grab().save(path, "PNG")
        return path
