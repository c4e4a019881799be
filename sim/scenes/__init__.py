"""The scene library: importing this package registers every scene in it."""

from sim.scenes import table  # noqa: F401
