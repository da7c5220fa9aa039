"""sawdds: a Python client for sawrt over DDS (Cyclone DDS), independent of the C++ code."""
from .client import Client, LOOPBACK_URI  # noqa: F401
