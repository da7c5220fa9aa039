"""sawgui: a desktop GUI for sawrt over DDS (PySide6 + pyqtgraph over sawdds)."""
__version__ = "0.1.0"
