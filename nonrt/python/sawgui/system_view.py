"""The system view: every gateway and component the registry lists, their interfaces and
operating states, live; FAULT in red with its reason and time; what vanished shown as gone."""
from PySide6 import QtCore, QtGui, QtWidgets

from .model import shown_state, state_color
from .widgets import clock

COLUMNS = ["name", "host", "interfaces", "state", "since", "reason"]


def banner_lines(gws, comps):
    """(FAULT lines, gone lines): each component in FAULT (still said once its gateway has gone: the
    last word it had), and each gone with its gateway without one."""
    faults, gone = [], []
    for g, gw in sorted(gws.items()):
        for c in gw["components"]:
            comp = comps.get(c)
            if comp is None or comp["gateway"] != g:
                continue
            if comp["gone_at"] and comp["state"] != "FAULT":
                gone.append(f"{c}: gone with its gateway at {clock(comp['gone_at'])} "
                            f"(last state {comp['state'] or 'unknown'})")
            if comp["state"] == "FAULT":
                why = comp["fault_reason"].removeprefix("FAULT: ")
                faults.append(f"{c}: FAULT at {clock(comp['fault_time'])}: {why}"
                              + (f" (gateway gone at {clock(comp['gone_at'])})" if comp["gone_at"] else ""))
    return faults, gone


def set_banner(banner, faults, gone):
    """A FAULT in red (a component gone without one in dark grey), above everything; hidden when none."""
    banner.setVisible(bool(faults or gone))
    if faults or gone:
        banner.setText("\n".join(faults + gone))
        banner.setStyleSheet(f"QLabel {{ background: {'#d01010' if faults else '#404040'}; color: white;"
                             " font-size: 16px; font-weight: bold; padding: 8px; }")


class SystemView(QtWidgets.QWidget):
    def __init__(self, live, parent=None):
        super().__init__(parent)
        self.live = live
        # The FAULT banner: the window shows it above every tab (MainWindow puts it there).
        self.banner = QtWidgets.QLabel("")
        self.banner.setWordWrap(True)
        self.banner.hide()
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setHeaderLabels(COLUMNS)
        self.tree.setRootIsDecorated(True)
        self.tree.setAlternatingRowColors(False)
        self.empty = QtWidgets.QLabel("Looking for gateways on the DDS domain…")
        lay = QtWidgets.QVBoxLayout(self)
        lay.addWidget(self.empty)
        lay.addWidget(self.tree)
        self._items = {}
        self.faults, self.gone = [], []  # the banner's lines, for the window's own banner

    def _item(self, key, parent):
        it = self._items.get(key)
        if it is None:
            it = QtWidgets.QTreeWidgetItem()
            (parent.addChild if isinstance(parent, QtWidgets.QTreeWidgetItem) else self.tree.addTopLevelItem)(it)
            it.setExpanded(True)
            self._items[key] = it
            if isinstance(parent, QtWidgets.QTreeWidgetItem):
                parent.setExpanded(True)
        return it

    def refresh(self):
        gws, comps = self.live.gateways(), self.live.components()
        self.empty.setVisible(not gws)
        shown = set()
        for g, gw in sorted(gws.items()):
            gi = self._item(("g", g), None)
            state = "GONE" if not gw["alive"] else gw["state"]
            self._fill(gi, [g, f"{gw['host']} (pid {gw['pid']})", "gateway", state,
                            clock(gw["gone_at"]) if gw["gone_at"] else "", "left the DDS domain" if not gw["alive"]
                            else ""], state)
            for c in gw["components"]:
                comp = comps.get(c)
                if comp is None or comp["gateway"] != g:
                    continue
                ci = self._item(("c", g, c), gi)
                shown.add(("c", g, c))
                st = shown_state(comp)
                since = clock(comp["gone_at"]) if comp["gone_at"] else clock(comp["fault_time"] if st == "FAULT"
                                                                            else comp["state_time"])
                reason = comp["fault_reason"].removeprefix("FAULT: ") if comp["state"] == "FAULT" else ""
                if comp["gone_at"]:
                    reason = "gone with its gateway" + (f", after FAULT: {reason}" if reason else "")
                self._fill(ci, [c, comp["host"], ", ".join(comp["interfaces"]), st, since, reason], st)
        # A component served by another gateway now (saw-rt restarted) leaves the old one's branch.
        for key in [k for k in self._items if k[0] == "c" and k not in shown]:
            it = self._items.pop(key)
            (it.parent() or self.tree.invisibleRootItem()).removeChild(it)
        for i in range(len(COLUMNS) - 1):
            self.tree.resizeColumnToContents(i)
        # FAULT in red; a component gone without a FAULT (its gateway vanished) in dark grey: both said
        # above everything, neither shown as its last state frozen.
        self.refresh_banner(gws, comps)

    def refresh_banner(self, gws=None, comps=None):
        """The FAULT banner alone (cheap: the window calls it at every tick, whichever tab is open)."""
        gws = self.live.gateways() if gws is None else gws
        comps = self.live.components() if comps is None else comps
        self.faults, self.gone = banner_lines(gws, comps)
        set_banner(self.banner, self.faults, self.gone)

    def _fill(self, item, texts, state):
        for i, t in enumerate(texts):
            item.setText(i, t)
        color = state_color(state)
        fault, gone = state.startswith("FAULT"), state.endswith("GONE") or state.endswith("(gone)")
        bg = QtGui.QColor("#ffd6d6") if fault else (QtGui.QColor("#e4e4e4") if gone else None)
        for i in range(len(COLUMNS)):
            item.setBackground(i, QtGui.QBrush(bg) if bg else QtGui.QBrush())
            f = item.font(i)
            f.setBold(fault)
            f.setItalic(gone)
            item.setFont(i, f)
        if color:
            item.setForeground(3, QtGui.QBrush(QtGui.QColor(color)))
        item.setData(0, QtCore.Qt.ItemDataRole.UserRole, state)

    def state_of(self, name: str) -> str:
        """What the view shows as `name`'s state (for tests): under the gateway serving it now."""
        comp = self.live.components().get(name)
        it = (self._items.get(("c", comp["gateway"], name)) if comp else None) or self._items.get(("g", name))
        return it.text(3) if it else ""

    def parent_of(self, name: str) -> str:
        """The gateway under which the tree shows component `name` ("" if it does not)."""
        items = [k for k in self._items if k[0] == "c" and k[2] == name]
        return items[0][1] if len(items) == 1 else ("" if not items else "several")
