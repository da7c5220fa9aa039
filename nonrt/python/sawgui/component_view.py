"""A component's view, generated from its manifest entries: read commands as live values and
plots, events as a log, write/void commands as forms, qualified reads as a query box."""
from PySide6 import QtWidgets

from sawdds import msgs, values

from . import model
from .widgets import PLOT_POINTS, Outcome, Plot, clock, newest, units_of


class CommandForm(QtWidgets.QGroupBox):
    """A form for one write or void command: a field per number of its message."""

    def __init__(self, view, endpoint):
        super().__init__(f"{endpoint.name}  ({endpoint.saw_type or 'void'})")
        self.view, self.endpoint = view, endpoint
        self.cls = msgs.BY_DDS_NAME.get(endpoint.dds_type)
        form = QtWidgets.QFormLayout(self)
        self.fields = {}
        if self.cls is None or not endpoint.topic:
            form.addRow(QtWidgets.QLabel(f"not mapped to DDS by the gateway ({endpoint.saw_type} has no DDS type)"))
            return
        self.limits = model.limits(endpoint)
        if self.limits:
            form.addRow(QtWidgets.QLabel(f"within [{self.limits[0]:g}, {self.limits[1]:g}], as the component declares"))
        # A field starts from the component's current value when it publishes one (read_back), else
        # empty: a made-up default (0) can be outside the bounds, or a harmful value within them.
        self.source = model.read_back(view.live, view.component, endpoint)
        self.filled = {}  # field -> the text last filled from the read-back (not edited since)
        for name, kind in values.form_fields(self.cls):
            if endpoint.saw_type == "saw::StateCommand":
                w = QtWidgets.QComboBox()
                w.addItems(values.STATE_COMMANDS)
            else:
                w = QtWidgets.QLineEdit("")
                w.setMinimumWidth(90)
                if kind in (int, float, list):
                    w.setPlaceholderText(model.placeholder(self.limits))
            self.fields[name] = w
            form.addRow(name, w)
        if self.source is not None:
            form.addRow(QtWidgets.QLabel(f"starts from {self.source.name}, the current value"))
        self.button = QtWidgets.QPushButton("Send")
        self.button.clicked.connect(self.submit)
        self.outcome = Outcome()
        form.addRow(self.button, self.outcome)

    def fill(self, live):
        """Puts the read-back's newest value in the fields the person has not edited."""
        if self.source is None:
            return
        sample, _ = live.latest(self.source.topic)
        if sample is None:
            return
        for name, text in model.form_texts(sample, values.form_fields(self.cls)).items():
            w = self.fields.get(name)
            if isinstance(w, QtWidgets.QLineEdit) and w.text() == self.filled.get(name, "") and text != w.text():
                w.setText(text)
                self.filled[name] = text

    def submit(self):
        raw = {n: (w.currentText() if isinstance(w, QtWidgets.QComboBox) else w.text()) for n, w in self.fields.items()}
        try:
            check = "state" if self.endpoint.saw_type == "saw::StateCommand" else self.limits
            sample = values.build(self.cls, raw, check)
        except values.Invalid as e:
            self.outcome.refused(str(e))
            return
        self.view.send(self.endpoint, sample, self.outcome)


class QueryBox(QtWidgets.QGroupBox):
    """A qualified read: the qualifier typed in, the reply shown."""

    def __init__(self, view, endpoint):
        super().__init__(f"{endpoint.name}  ({endpoint.saw_type} → {endpoint.result_type})")
        self.view, self.endpoint = view, endpoint
        lay = QtWidgets.QHBoxLayout(self)
        self.arg = QtWidgets.QLineEdit()
        self.arg.setPlaceholderText(endpoint.saw_type)
        self.button = QtWidgets.QPushButton("Ask")
        self.result = QtWidgets.QLabel("")
        lay.addWidget(self.arg)
        lay.addWidget(self.button)
        lay.addWidget(self.result, 1)
        self.button.clicked.connect(self.ask)

    def ask(self):
        try:
            data = values.pack(self.endpoint.saw_type, self.arg.text())
        except values.Invalid as e:
            self.result.setText(str(e))
            return
        self.result.setText("asking…")
        self.view.live.query(self.endpoint.topic, data, tag=lambda ok, text: self.result.setText(
            text if ok else "failed: " + text))


class ComponentView(QtWidgets.QWidget):
    def __init__(self, live, component: str, parent=None):
        super().__init__(parent)
        self.live, self.component = live, component
        eps = live.endpoints(component)
        self.reads = [e for e in eps if e.kind == "read"]
        self.events = [e for e in eps if e.kind in ("write_event", "void_event") and e.topic]
        for t in model.component_topics(live, component):
            live.watch(t)

        split = QtWidgets.QSplitter()
        left = QtWidgets.QWidget()
        ll = QtWidgets.QVBoxLayout(left)
        self.table = QtWidgets.QTableWidget(len(self.reads), 4)
        self.table.setHorizontalHeaderLabels(["read", "value", "samples", "statistics (samples received)"])
        self.table.verticalHeader().hide()
        # Name and count as wide as they need; value and statistics share the rest (elided, never
        # pushed out of sight behind a scroll bar).
        header = self.table.horizontalHeader()
        for j, mode in enumerate((QtWidgets.QHeaderView.ResizeMode.ResizeToContents,
                                  QtWidgets.QHeaderView.ResizeMode.Stretch,
                                  QtWidgets.QHeaderView.ResizeMode.ResizeToContents,
                                  QtWidgets.QHeaderView.ResizeMode.Stretch)):
            header.setSectionResizeMode(j, mode)
        self.table.setWordWrap(False)
        for i, e in enumerate(self.reads):
            self.table.setItem(i, 0, QtWidgets.QTableWidgetItem(e.name))
            for j in (1, 2, 3):
                self.table.setItem(i, j, QtWidgets.QTableWidgetItem("" if e.topic else "(not mapped)"))
        self.table.itemSelectionChanged.connect(self._select)
        ll.addWidget(self.table, 2)
        # Position, velocity and force when the component has them; a row selected replaces the first.
        self.plotted = self._default_plots()
        self.plots = [Plot("") for _ in self.plotted or [None]]
        row = QtWidgets.QHBoxLayout()
        for p in self.plots:
            row.addWidget(p)
        ll.addLayout(row, 3)
        self.plot = self.plots[0]
        ll.addWidget(QtWidgets.QLabel("events and refusals"))
        self.log = QtWidgets.QPlainTextEdit()
        self.log.setReadOnly(True)
        self.log.setMaximumBlockCount(2000)
        ll.addWidget(self.log, 1)
        split.addWidget(left)

        right = QtWidgets.QScrollArea()
        right.setWidgetResizable(True)
        inner = QtWidgets.QWidget()
        rl = QtWidgets.QVBoxLayout(inner)
        self.forms = {e.name: CommandForm(self, e) for e in eps if e.kind in ("write", "void")}
        for f in self.forms.values():
            rl.addWidget(f)
        self.queries = {e.name: QueryBox(self, e) for e in eps if e.kind == "qualified_read"}
        for q in self.queries.values():
            rl.addWidget(q)
        rl.addStretch(1)
        right.setWidget(inner)
        split.addWidget(right)
        split.setSizes([860, 340])
        lay = QtWidgets.QVBoxLayout(self)
        lay.addWidget(split)
        self._logged = {}
        self.served = None  # (gateway, alive): a failure said to a gateway since gone is cleared on its return

    def _default_plots(self) -> list:
        numeric = [e for e in self.reads if e.topic and e.dds_type not in (
            "crtk_msgs::msg::dds_::OperatingState_", "crtk_msgs::msg::dds_::StringStamped_")]
        picks = [next((e for e in numeric if e.name == n), None) for n in ("measured_cp", "measured_cv")]
        picks.append(next((e for e in numeric if "force" in e.name), None))
        picks = [e for e in picks if e is not None]
        return picks or numeric[:1]

    def send(self, endpoint, sample, outcome):
        outcome.sending(endpoint.name, self.live.error_count(self.component))
        self.live.send(endpoint.topic, sample, tag=outcome.delivered)

    def _select(self):
        rows = {i.row() for i in self.table.selectedItems()}
        if rows and self.reads[min(rows)].topic:
            self.plotted[0:1] = [self.reads[min(rows)]]
            self.plot.clear()
            self.plot.curves = {}

    def refresh(self):
        for i, e in enumerate(self.reads):
            if not e.topic:
                continue
            sample, _ = self.live.latest(e.topic)
            if sample is not None:
                self.table.item(i, 1).setText(values.text(sample)[:90])
            self.table.item(i, 2).setText(str(self.live.count(e.topic)))
            st = self.live.statistics(e.topic)
            self.table.item(i, 3).setText("; ".join(f"{k.split('.')[-1]} mean {v[3]:.4g} [{v[1]:.4g}, {v[2]:.4g}]"
                                                    for k, v in list(st.items())[:3]))
        drawn = [self.live.series(e.topic, PLOT_POINTS) for e in self.plotted]
        t_end = newest(*drawn)  # one time axis for the view's plots
        for plot, e, series in zip(self.plots, self.plotted, drawn):
            if plot.units != units_of(e):
                plot.set_units(units_of(e))
            plot.setTitle(e.name, color="k")
            plot.show_series(*series, t_end=t_end)
        lines = []
        for e in self.events:
            total, entries = self.live.log(e.topic, self._logged.get(e.topic, 0))
            lines += [(t, f"{clock(t)}  {e.name}: {text}") for t, text in entries]
            self._logged[e.topic] = total
        total, errors = self.live.errors_after(self.component, self._logged.get("error", 0))
        lines += [(t, f"{clock(t)}  error: {text}") for t, text in errors]
        self._logged["error"] = total
        for _, line in sorted(lines):
            self.log.appendPlainText(line)
        comp = self.live.components().get(self.component, {})
        served = (comp.get("gateway"), comp.get("gone_at") is None)
        back = self.served is not None and served != self.served and served[1]
        self.served = served
        for f in self.forms.values():
            if hasattr(f, "outcome"):
                if back:
                    f.outcome.clear_stale()
                f.outcome.check_errors(self.live, self.component)
                f.fill(self.live)
