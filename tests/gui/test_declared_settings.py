"""The teleoperation panel is made from what the teleoperation says of itself (its description,
saw_msgs/ComponentDescription): found by its kind, its master and slave by the roles it declares
(the arms here are named "right" and "left", the master first in neither name nor order), one row
per setting its law declares with the law's units and bounds, each showing the value the system
publishes. A law with other settings (position-position) shows its own rows; a setting another
client changes appears in the panel; a value outside a setting's bounds is refused by its row."""
from PySide6 import QtCore

from sawdds import Client, msgs
from sawdds.live import Live
from sawgui import model
from sawgui.app import MainWindow

LONG = 20_000  # ms: bounds for what depends on the machine (process start, discovery)


def test_the_panel_is_the_laws_declared_settings(qtbot, position_position_deployment):
    d = position_position_deployment
    live = Live(d.domain)
    w = MainWindow(live, d.domain, "lo")
    qtbot.addWidget(w)
    w.resize(1200, 820)
    w.show()
    try:
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
    finally:
        w.timer.stop()
        live.close()
