"""The camera side of the core: the source frames come from now, its camera model, and the ``sim:`` camera's
pose fed from the vehicle's telemetry.

- :mod:`~uav_tui.camera.active`: ``ActiveCamera``, which opens a source by URI, picks its model and switches.
- :mod:`~uav_tui.camera.pose_feed`: the ``sim:`` camera's pose, copied from the flight controller's telemetry.
"""
