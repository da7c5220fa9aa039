"""The teleoperation panel is made from what the teleoperation says of itself (its description,
saw_msgs/ComponentDescription): found by its kind, its master and slave by the roles it declares
(the arms here are named "right" and "left", the master first in neither name nor order), one row
per setting its law declares with the law's units and bounds, each showing the value the system
publishes. A law with other settings (position-position) shows its own rows; a setting another
client changes appears in the panel; a value outside a setting's bounds is refused by its row."""
from PySide6 import QtCore

from sawdds import Client, msgs
from sawgui import model

LONG = 20_000  # ms: bounds for what depends on the machine (process start, discovery)


def test_the_panel_is_the_laws_declared_settings(qtbot, position_position_deployment, window):
    d, w, live = position_position_deployment, window, window.live
    qtbot.waitUntil(lambda: w.teleop is not None, timeout=LONG)
    # Found by what it says it is; its sides by the roles it declares.
    assert model.teleop_components(live) == [d.teleop]
    description = live.description(d.teleop)
    assert (description.kind, description.variant) == ("teleoperation", "position_position")
    assert list(description.roles) == ["master", "slave"]
    panel = w.teleop
    assert (panel.master, panel.slave) == (d.master, d.slave) == ("right_" + d.tag, "left_" + d.tag)
    # Not a component that merely has a teleoperation's command names.
    assert d.master not in model.teleop_components(live)

    w.tabs.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: bool(panel.rows), timeout=LONG)
    assert list(panel.rows) == ["scale", "stiffness", "damping", "force_limit"], list(panel.rows)
    assert "gains" not in panel.rows and "force_limits" not in panel.rows
    labels = {n: r.setting.label() for n, r in panel.rows.items()}
    assert labels["stiffness"] == "stiffness (N/m)  [0, 10000]", labels
    assert labels["damping"] == "damping (N·s/m)  [0, 100]", labels
    assert labels["force_limit"] == "force_limit (N)  [0, 100]", labels
    # Each row starts from the value the teleoperation publishes (the deployment's).
    edits = {n: r.edit() for n, r in panel.rows.items()}
    qtbot.waitUntil(lambda: all(e.text() for e in edits.values()), timeout=LONG)
    assert {n: float(e.text()) for n, e in edits.items()} == \
        {"scale": 1, "stiffness": 250, "damping": 5, "force_limit": 2.5}
    assert edits["damping"].placeholderText() == "within [0, 100]"

    # A setting another client changes is what the panel then shows.
    other = Client(d.domain)
    other.send(f"rt/{d.teleop}/set_stiffness", msgs.Float64(data=400.0))
    qtbot.waitUntil(lambda: edits["stiffness"].text() == "400", timeout=LONG)

    # The row sends its own command, checked against the bounds the law declares.
    edits["damping"].setText("500")
    qtbot.mouseClick(panel.rows["damping"].button, QtCore.Qt.MouseButton.LeftButton)
    assert "500 is outside [0, 100]" in panel.outcome.text(), panel.outcome.text()
    edits["damping"].setText("7")
    qtbot.mouseClick(panel.rows["damping"].button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: "set_damping: delivered" in panel.outcome.text(), timeout=LONG)
    damping = model.endpoint(live, d.teleop, "damping", kinds=("read",)).topic
    qtbot.waitUntil(lambda: live.latest(damping)[0] is not None and live.latest(damping)[0].data == 7.0,
                    timeout=LONG)


def test_the_collaborative_laws_prediction_and_offset_limits_are_set_and_read_back(qtbot, deployment, window):
    """The collaborative law's offset_limits and prediction are settings like its gains: a row
    each with the declared unit and bounds, filled from the read-back, set from the panel (seen by
    an independent DDS reader), a value outside the bounds refused by the row, one outside the
    type's own range (an offset velocity above 10 m/s) by the gateway."""
    d, w, live = deployment, window, window.live
    other = Client(d.domain)  # the independent reader: not the window's
    qtbot.waitUntil(lambda: w.teleop is not None, timeout=LONG)
    panel = w.teleop
    w.tabs.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: "prediction" in panel.rows and "offset_limits" in panel.rows, timeout=LONG)
    prediction, limits = panel.rows["prediction"], panel.rows["offset_limits"]
    assert prediction.button is not None and limits.button is not None, \
        (prediction.note and prediction.note.text(), limits.note and limits.note.text())
    assert list(prediction.edits) == ["enabled", "master_horizon", "slave_horizon"], list(prediction.edits)
    assert list(limits.edits) == ["velocity", "acceleration", "jerk"], list(limits.edits)
    assert prediction.setting.label() == "prediction (s)  [0, 1]", prediction.setting.label()
    assert limits.setting.label() == "offset_limits (m/s, m/s², m/s³)  [1e-06, 100000]", limits.setting.label()
    # Filled from the read-back: the law's defaults (the deployment sets neither).
    qtbot.waitUntil(lambda: all(e.text() for e in [*prediction.edits.values(), *limits.edits.values()]),
                    timeout=LONG)
    assert {f: e.text() for f, e in prediction.edits.items()} == \
        {"enabled": "false", "master_horizon": "0", "slave_horizon": "0"}
    assert {f: e.text() for f, e in limits.edits.items()} == \
        {"velocity": "0.05", "acceleration": "0.5", "jerk": "10"}

    seen = {}

    def read_back(name):
        """The newest sample of `name`'s read-back at the independent reader."""
        if name not in seen:
            seen[name] = [other.reader(f"rt/{d.teleop}/{name}"), None]
        for s in seen[name][0].take(N=16):
            seen[name][1] = s
        return seen[name][1]

    # Set from the panel: the independent reader sees the value in force.
    prediction.edits["enabled"].setText("true")
    prediction.edits["master_horizon"].setText("0.02")
    prediction.edits["slave_horizon"].setText("0.01")
    qtbot.mouseClick(prediction.button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: "set_prediction: delivered" in panel.outcome.text(), timeout=LONG)
    qtbot.waitUntil(lambda: (lambda s: s is not None and (s.enabled, s.master_horizon, s.slave_horizon)
                             == (True, 0.02, 0.01))(read_back("prediction")), timeout=LONG)

    # Outside the declared bounds: refused by the row, nothing sent.
    limits.edits["jerk"].setText("1e6")
    qtbot.mouseClick(limits.button, QtCore.Qt.MouseButton.LeftButton)
    assert "1e+06 is outside [1e-06, 100000]" in panel.outcome.text(), panel.outcome.text()
    # Within them but above the velocity's own limit (10 m/s): refused by the gateway, with the
    # reason shown, and the value in force unchanged.
    limits.edits["jerk"].setText("10")
    limits.edits["velocity"].setText("50")
    qtbot.mouseClick(limits.button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: "refused by the gateway: set_offset_limits rejected" in panel.outcome.text(),
                    timeout=LONG)
    # A valid one is set, and read back (the refused one never was in force).
    limits.edits["velocity"].setText("0.1")
    limits.edits["acceleration"].setText("1")
    limits.edits["jerk"].setText("20")
    qtbot.mouseClick(limits.button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: (lambda s: s is not None and (s.velocity, s.acceleration, s.jerk)
                             == (0.1, 1.0, 20.0))(read_back("offset_limits")), timeout=LONG)
    assert read_back("offset_limits").velocity != 50
