"""Replaying recorded runs: the autonomy gate of a replay and ``uav-tui replay``."""
