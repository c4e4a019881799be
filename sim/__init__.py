"""Simulation: SAPIEN physics, the simulated hand, the range camera, scenes, exploration.

Imports ``features`` only (a robot perceives what it did).
"""

import warnings as _warnings

# SAPIEN looks for a Vulkan loader on import; these machines have none and need none
# (CPU physics, ray-cast camera). The warning would reach every worker's stderr.
_warnings.filterwarnings("ignore", message="Failed to find system libvulkan")
