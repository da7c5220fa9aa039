"""The ROS 2 / CRTK messages sawrt's gateway uses, for Cyclone DDS: made at import from the IDL
files (nonrt/msgs/idl, in the package as ``sawdds/idl``), the one source the gateway's C++ types
are generated from too, and from those of the directories in ``$SAWDDS_IDL_PATH`` (colon-separated:
a lab's own message types, ``<dir>/<pkg>/msg/<Type>.idl``, as its mapping module maps them). Each type is a module attribute by its short name (``msgs.PoseStamped``);
type names are the ROS 2 DDS names (``pkg::msg::dds_::Type_``); all are @final and travel as
XCDR1, the representation Fast DDS 2.9 and ROS 2 use.
"""
import os
from pathlib import Path

from . import idl

BY_IDL_NAME = idl.load(Path(__file__).resolve().parent / "idl",
                       *[p for p in os.environ.get("SAWDDS_IDL_PATH", "").split(":") if p])
# Every type by its DDS name, as a gateway's registry names the type of a topic.
BY_DDS_NAME = {cls.__idl_typename__: cls for cls in BY_IDL_NAME.values()}


def _short_names():
    names = {}
    for full, cls in BY_IDL_NAME.items():
        short = full.split("::")[-1]
        if short in names:
            raise idl.IdlError(f"{full} and {names[short]}: two types named {short}; sawdds.msgs names types by "
                               "their last name only")
        names[short] = full
    return {short: BY_IDL_NAME[full] for short, full in names.items()}


globals().update(_short_names())
