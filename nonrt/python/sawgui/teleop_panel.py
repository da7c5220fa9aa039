"""The teleoperation panel: enable/disable, clutch, scale, gains and force limits (checked against
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

        settings = QtWidgets.QGroupBox("settings")
        form = QtWidgets.QGridLayout(settings)
        # Empty until the component publishes the setting's current value (model.read_back): a
        # hard-coded default would show a setting the system may not have.
        self.scale = QtWidgets.QLineEdit("")
        self.gain_m, self.gain_s = QtWidgets.QLineEdit(""), QtWidgets.QLineEdit("")
        self.lim_m, self.lim_s = QtWidgets.QLineEdit(""), QtWidgets.QLineEdit("")
        self.apply_scale = QtWidgets.QPushButton("Apply scale")
        self.apply_gains = QtWidgets.QPushButton("Apply gains")
        self.apply_limits = QtWidgets.QPushButton("Apply force limits")
        rows = [("scale (slave/master)", "set_scale", [self.scale], self.apply_scale),
                ("gains master, slave (N/m)", "set_gains", [self.gain_m, self.gain_s], self.apply_gains),
                ("force limits master, slave (N)", "set_force_limits", [self.lim_m, self.lim_s], self.apply_limits)]
        for r, (label, command, edits, button) in enumerate(rows):
            lim = model.limits(model.endpoint(live, teleop, command, kinds=("write",)))
            bounds = f"  [{lim[0]:g}, {lim[1]:g}]" if lim else ""
            form.addWidget(QtWidgets.QLabel(label + bounds), r, 0)
            for j, e in enumerate(edits):
                e.setPlaceholderText(model.placeholder(lim))
                if lim:
                    e.setToolTip(f"within [{lim[0]:g}, {lim[1]:g}], as the component declares")
                form.addWidget(e, r, 1 + j)
            form.addWidget(button, r, 3)
        self.outcome = Outcome()
        form.addWidget(self.outcome, len(rows), 0, 1, 4)
        self.refusal = QtWidgets.QLabel("")
        self.refusal.setWordWrap(True)
        form.addWidget(self.refusal, len(rows) + 1, 0, 1, 4)
        self.settings = {command: (edits, model.read_back(live, teleop, model.endpoint(live, teleop, command,
                                                                                    kinds=("write",))))
                         for _, command, edits, _ in rows}
        self.filled = {}  # edit -> the text last filled from a read-back (not edited since)
        self.apply_scale.clicked.connect(self.send_scale)
        self.apply_gains.clicked.connect(lambda: self.send_pair("set_gains", [self.gain_m, self.gain_s]))
        self.apply_limits.clicked.connect(lambda: self.send_pair("set_force_limits", [self.lim_m, self.lim_s]))

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
        for name in ("state_command", "set_scale", "set_gains", "set_force_limits"):
            e = model.endpoint(live, teleop, name, kinds=("write", "void"))
            if e is not None and e.topic:
                live.prepare(e.topic)
        for _, source in self.settings.values():
            if source is not None:
                live.watch(source.topic)
        self.attached = None  # (gateway, served, since): the refusals shown are those since it serves
        self.badge.set_state(model.shown_state(live.components().get(teleop, {})))  # no empty first frame
        lay = QtWidgets.QVBoxLayout(self)
        lay.addLayout(top)
        lay.addWidget(settings)
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

    def _limits(self, name):
        return model.limits(model.endpoint(self.live, self.teleop, name, kinds=("write",)))

    def send_scale(self):
        try:
            s = values.parse_number("scale", self.scale.text(), float, self._limits("set_scale"))
        except values.Invalid as e:
            self.outcome.refused(str(e))
            return
        self._send("set_scale", msgs.Float64(data=s))

    def send_pair(self, name, edits):
        """A (master, slave) setting, checked against the bounds the registry carries for it."""
        try:
            vals = [values.parse_number(f"{name} {side}", e.text(), float, self._limits(name))
                    for side, e in zip(("master", "slave"), edits)]
        except values.Invalid as e:
            self.outcome.refused(str(e))
            return
        self._send(name, msgs.MasterSlave(master=vals[0], slave=vals[1]))

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
        for command, (edits, source) in self.settings.items():
            if source is None:
                continue
            sample, _ = self.live.latest(source.topic)
            if sample is None:
                continue
            texts = [f"{sample.data:.6g}"] if isinstance(sample, msgs.Float64) else \
                [f"{sample.master:.6g}", f"{sample.slave:.6g}"] if isinstance(sample, msgs.MasterSlave) else []
            for e, text in zip(edits, texts):
                if e.text() == self.filled.get(e, "") and e.text() != text:
                    e.setText(text)
                    self.filled[e] = text
