"""Traffic: highway-env stepped headless, converted once to simrig's world frame (see :mod:`.traffic`)."""

from .traffic import TrafficWorld
from .vehicles import CLASS_SPECS, VEHICLE_TYPES

__all__ = ["CLASS_SPECS", "VEHICLE_TYPES", "TrafficWorld"]
