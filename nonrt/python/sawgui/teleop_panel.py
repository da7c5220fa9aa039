"""The teleoperation panel: enable/disable, clutch, a row per setting the teleoperation's law declares
(made from its description: name, unit, bounds; the value its read-back publishes; checked against
the bounds the component accepts), the tracking error and both arms' positions, state and last fault."""
import time

from PySide6 import QtWidgets

from sawdds import msgs, values

from . import model
from .widgets import PLOT_POINTS, Outcome, Plot, StateBadge, clock, newest


class TeleopPanel(QtWidgets.QWidget):
    def __init__(self, live, teleop: str, parent=None):
        super().__init__(parent)
        self.live, self.teleop = live, teleop
        self.master, self.slave = model.teleop_sides(live, teleop)
        for t in model.teleop_topics(live, teleop):
            live.watch(t)

        top = QtWidgets.QHBoxLayout()
        self.badge = StateBadge()
        top.addWidget(QtWidgets.QLabel(f"<b>{teleop}</b> ({self.master} → {self.slave})"))
        top.addWidget(self.badge)
        self.enable = QtWidgets.QPushButton("Enable")
        self.disable = QtWidgets.QPushButton("Disable")
        self.clutch = QtWidgets.QPushButton("Clutch (hold)")
        self.clutch.setToolTip("While held, the teleoperation pauses (the master moves alone); on release it "
                               "resumes from the new pose, as a clutch pedal does.")
        for b in (self.enable, self.disable, self.clutch):
            b.setMinimumHeight(34)
            top.addWidget(b)
        top.addStretch(1)
        self.enable.clicked.connect(lambda: self.state_command("enable"))
        self.disable.clicked.connect(lambda: self.state_command("disable"))
        self.clutch.pressed.connect(lambda: self.state_command("pause"))
        self.clutch.released.connect(lambda: self.state_command("resume"))

        # One row per setting the law declares (its description), made once it has arrived: the
        # panel knows no setting of its own, so another law shows its own rows.
        self.settings_box = QtWidgets.QGroupBox("settings")
        self.form = QtWidgets.QGridLayout(self.settings_box)
        self.rows = {}  # setting name -> SettingRow
        self.row_widgets, self.built = [], None  # the rows' widgets; what they were made from
        self.outcome = Outcome()
        self.refusal = QtWidgets.QLabel("")
        self.refusal.setWordWrap(True)
        self.filled = {}  # edit -> the text last filled from a read-back (not edited since)
        self.build_settings()

        self.fault = QtWidgets.QLabel("last fault: none")
        self.fault.setWordWrap(True)
        self.error_plot = Plot("tracking error |e_s|", "m")  # metres, as every plot (the axis says mm)
        self.slave_plot = Plot(f"{self.slave}.measured_cp position", "m")
        self.master_plot = Plot(f"{self.master}.measured_cp position", "m")
        plots = QtWidgets.QGridLayout()
        plots.addWidget(self.error_plot, 0, 0, 1, 2)
        plots.addWidget(self.master_plot, 1, 0)
        plots.addWidget(self.slave_plot, 1, 1)

        # The commands' writers now: the first click must not wait for one to be made and matched.
        e = model.endpoint(live, teleop, "state_command", kinds=("write", "void"))
        if e is not None and e.topic:
            live.prepare(e.topic)
        self.attached = None  # (gateway, served, since): the refusals shown are those since it serves
        self.badge.set_state(model.shown_state(live.components().get(teleop, {})))  # no empty first frame
        lay = QtWidgets.QVBoxLayout(self)
        lay.addLayout(top)
        lay.addWidget(self.settings_box)
        lay.addWidget(self.fault)
        lay.addLayout(plots, 1)

    def _topic(self, component, name):
        e = model.endpoint(self.live, component, name)
        return e.topic if e is not None else ""

    def _send(self, name, sample):
        e = model.endpoint(self.live, self.teleop, name, kinds=("write", "void"))
        if e is None or not e.topic:
            self.outcome.refused(f"{name}: the gateway does not map it to DDS "
                                 f"({e.saw_type if e else 'not in the manifest'}); it can be set in the deployment")
            return
        self.outcome.sending(name, self.live.error_count(self.teleop))
        self.live.send(e.topic, sample, tag=self.outcome.delivered)

    def state_command(self, command: str):
        self._send("state_command", msgs.StringStamped(string=command))

    def build_settings(self):
        """The rows of the declared settings, once the description is there; made again when what
        it declares or how the gateway serves it changes (saw-rt restarted with another law)."""
        declared = model.declared_settings(self.live, self.teleop)
        shape = [(d.name, d.unit, d.bounds, d.read and d.read.topic, d.write and d.write.topic,
                  model.limits(d.write)) for d in declared]
        if not declared or shape == self.built:
            return
        for w in self.row_widgets:
            self.form.removeWidget(w)
            w.deleteLater()
        for w in (self.outcome, self.refusal):
            self.form.removeWidget(w)
        self.rows, self.row_widgets, self.filled, self.built = {}, [], {}, shape
        for r, setting in enumerate(declared):
            row = SettingRow(setting, self.live)
            self.rows[setting.name] = row
            widgets = [QtWidgets.QLabel(setting.label()), *row.edits.values(),
                       row.note if row.button is None else row.button]
            self.form.addWidget(widgets[0], r, 0)
            for j, edit in enumerate(row.edits.values()):
                self.form.addWidget(edit, r, 1 + j)
            self.form.addWidget(widgets[-1], r, 4)
            self.row_widgets += widgets
            if row.button is not None:
                row.button.clicked.connect(lambda _=False, n=setting.name: self.send_setting(n))
                self.live.prepare(setting.write.topic)
            if setting.read is not None:
                self.live.watch(setting.read.topic)
        self.form.addWidget(self.outcome, len(declared), 0, 1, 5)
        self.form.addWidget(self.refusal, len(declared) + 1, 0, 1, 5)

    def send_setting(self, name):
        """set_<name> from its row, checked against the bounds the registry carries for it (the
        component's own), else those it declares."""
        row = self.rows[name]
        try:
            sample = values.build(row.setting.cls, {f: e.text() for f, e in row.edits.items()}, row.limits)
        except values.Invalid as e:
            self.outcome.refused(f"set_{name}: {e}")
            return
        self._send("set_" + name, sample)

    def refresh(self):
        comp = self.live.components().get(self.teleop, {})
        state = model.shown_state(comp)
        if state != self.badge.state:
            self.badge.set_state(state)
        attached = (comp.get("gateway"), comp.get("gone_at") is None)
        if attached != (self.attached or (None, None))[:2]:
            # Served again (a restart) or gone: what was said to the old gateway no longer holds.
            if attached[1] and self.attached is not None:
                self.outcome.clear_stale()
                self.refusal.setText("")
            self.attached = attached + (time.time(),)
        if state.startswith("FAULT") or comp.get("fault_reason"):
            self.fault.setText(f"last fault at {clock(comp.get('fault_time'))}: {comp.get('fault_reason')}")
            self.fault.setStyleSheet("QLabel { color: #d01010; font-weight: bold; font-size: 14px; }")
        elif state == "GONE":
            self.fault.setText(f"the gateway serving {self.teleop} left at {clock(comp.get('gone_at'))}")
        drawn = [self.live.series(self._topic(c, n), PLOT_POINTS) for c, n in
                 ((self.teleop, "tracking_error"), (self.slave, "measured_cp"), (self.master, "measured_cp"))]
        t_end = newest(*drawn)  # one time axis for the three plots
        for plot, series in zip((self.error_plot, self.slave_plot, self.master_plot), drawn):
            plot.show_series(*series, t_end=t_end)
        self.outcome.check_errors(self.live, self.teleop)
        since = self.attached[2] if self.attached else 0.0
        refusals = [(t, text) for t, text in self.live.errors(self.teleop) if " rejected: " in text and t >= since]
        if refusals:  # whoever sent it (this window or another peer), the gateway's last refusal
            t, text = refusals[-1]
            self.refusal.setText(f"last refusal by the gateway, at {clock(t)}: {text}")
            self.refusal.setStyleSheet("QLabel { color: #d01010; }")
        self.fill_settings()

    def fill_settings(self):
        """Each setting's fields from the value the component publishes, unless edited since."""
        self.build_settings()
        for row in self.rows.values():
            if row.setting.read is None:
                continue
            sample, _ = self.live.latest(row.setting.read.topic)
            if sample is None:
                continue
            texts = model.form_texts(sample, row.setting.fields)
            for field, e in row.edits.items():
                text = texts.get(field)
                if text is not None and e.text() == self.filled.get(e, "") and e.text() != text:
                    e.setText(text)
                    self.filled[e] = text


class SettingRow:
    """The widgets of one declared setting: a field per number of its message (form_fields), an
    Apply button when it is a command the gateway maps, else a note saying why not."""

    def __init__(self, setting, live):
        self.setting = setting
        self.limits = model.limits(setting.write) or setting.finite_bounds
        self.edits = {}
        for field, kind in setting.fields:
            e = QtWidgets.QLineEdit("")
            e.setObjectName(f"{setting.name}.{field}")
            if kind is bool:
                e.setPlaceholderText("true or false")
            else:
                e.setPlaceholderText(model.placeholder(self.limits))
            tip = f"{setting.name}.{field}"
            if self.limits:
                tip += f": within [{self.limits[0]:g}, {self.limits[1]:g}], as the component declares"
            e.setToolTip(tip)
            self.edits[field] = e
        self.button, self.note = None, None
        if setting.command and setting.write is not None:
            self.button = QtWidgets.QPushButton(f"Apply {setting.name}")
        else:
            for e in self.edits.values():
                e.setReadOnly(True)
            why = ("fixed by the deployment" if not setting.command else
                   "not mapped to DDS: set it in the deployment")
            if not self.edits:
                why = "not mapped to DDS (" + ("set it in the deployment" if setting.command else "fixed by the deployment") + ")"
            self.note = QtWidgets.QLabel(why)
            self.note.setStyleSheet("QLabel { color: #707070; }")

    def edit(self, field=None):
        """The field `field` (default: the only or first one)."""
        return self.edits[field] if field is not None else next(iter(self.edits.values()))
