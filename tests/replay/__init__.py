"""Replaying a recorded flight through a processor."""
