"""What the window shows around a FAULT and a restart of saw-rt, as an operator sees it: the FAULT
banner whichever tab is open (and the status bar says it), a tab that shows its state the moment
it is opened (never "(no state yet)"), the system tree after saw-rt is started again (its
components under the new gateway, none left under the dead one), and the lines that were true
only while the gateway was gone ("no live gateway", an old refusal) cleared once it is back, on
the panel and in a component's forms."""
from PySide6 import QtCore

from conftest import figure
from sawdds import Client, msgs

LONG = 20_000  # ms: bounds for what depends on the machine (process start, discovery)


def test_fault_on_every_tab_and_the_tree_and_messages_after_a_restart(qtbot, deployment, window):
    d, w, live = deployment, window, window.live
    qtbot.waitUntil(lambda: w.teleop is not None and w.system.state_of(d.teleop) == "ENABLED", timeout=LONG)
    panel = w.teleop
    # A tab opened shows its state at once: no empty first frame.
    w.tabs.setCurrentWidget(w.tasks)
    w.tabs.setCurrentWidget(panel)
    assert panel.badge.state == "ENABLED", panel.badge.text()
    # A refusal by the gateway (another peer's gain out of range), shown on the panel.
    Client(d.domain).send(f"rt/{d.teleop}/set_gains", msgs.MasterSlave(master=20000, slave=300))
    qtbot.waitUntil(lambda: "set_gains rejected" in panel.refusal.text(), timeout=LONG)
    old_gateway = live.components()[d.teleop]["gateway"]

    d.kill_rt()  # (the Teleoperation tab open)
    qtbot.waitUntil(lambda: w.system.banner.isVisible() and "FAULT" in w.system.banner.text(), timeout=LONG)
    # The banner is above the tabs: seen, with the component and why, whichever tab is open.
    for i in range(w.tabs.count()):
        w.tabs.setCurrentIndex(i)
        qtbot.wait(60)
        assert w.system.banner.isVisible(), w.tabs.tabText(i)
        assert d.teleop in w.system.banner.text() and "FAULT" in w.system.banner.text()
        assert not w.tabs.isAncestorOf(w.system.banner)
    assert "in FAULT" in w.status.text(), w.status.text()
    w.tabs.setCurrentWidget(panel)
    qtbot.mouseClick(panel.enable, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: "no live gateway" in panel.outcome.text(), timeout=LONG)
    qtbot.waitUntil(lambda: panel.badge.state == "FAULT (gone)", timeout=LONG)
    w.tabs.setCurrentWidget(w.components)
    w.picker.setCurrentText(d.slave)
    form = w.views[d.slave].forms["state_command"]
    qtbot.mouseClick(form.button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: "no live gateway" in form.outcome.text(), timeout=LONG)

    d.restart_rt()
    w.tabs.setCurrentWidget(w.system)
    qtbot.waitUntil(lambda: live.components()[d.teleop]["gateway"] != old_gateway
                    and w.system.state_of(d.teleop) == "ENABLED", timeout=LONG)
    qtbot.waitUntil(lambda: all(w.system.parent_of(c) == live.components()[c]["gateway"]
                                for c in (d.master, d.slave, d.teleop)), timeout=LONG)
    dead = w.system._items[("g", old_gateway)]
    assert dead.childCount() == 0, [dead.child(i).text(0) for i in range(dead.childCount())]
    assert dead.text(3) == "GONE"
    # Back: the FAULT is over (the banner goes), and what was said to the gone gateway is cleared.
    qtbot.waitUntil(lambda: not w.system.banner.isVisible(), timeout=LONG)
    w.tabs.setCurrentWidget(panel)
    assert panel.badge.state == "ENABLED"
    qtbot.waitUntil(lambda: "no live gateway" not in panel.outcome.text(), timeout=LONG)
    assert panel.refusal.text() == "", panel.refusal.text()
    w.tabs.setCurrentWidget(w.components)
    qtbot.waitUntil(lambda: form.outcome.text() == "", timeout=LONG)
    w.tabs.setCurrentWidget(panel)
    # and a command goes through again.
    qtbot.mouseClick(panel.disable, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: panel.badge.state == "DISABLED", timeout=LONG)
    figure(f"after a restart of saw-rt the tree lists {d.teleop} under {w.system.parent_of(d.teleop)} "
           f"(the dead {old_gateway} has none); the panel's stale lines cleared")
