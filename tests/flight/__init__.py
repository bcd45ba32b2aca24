"""The vehicle side of the core: commands, telemetry, the link, the autonomy gate, geo-location."""
