"""The vehicle side of the core: telemetry, the link, commands, the autonomy gate, the autopilot's
clock, and where the target is on the ground."""
