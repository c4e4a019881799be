"""Robots shared by the scenes: the chapter-5 mobile base (``sim.robots.mobile``)."""
