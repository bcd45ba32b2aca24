"""What a run writes while it flies: frames, video, telemetry, events, a full disk, a crash."""
