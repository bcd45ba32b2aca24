"""The flight controller over MAVSDK: :class:`controllers.mavsdk.controller.MavsdkController` and the modules it
drives the autopilot with (its link, telemetry, pose, velocity control, landing, gimbal, calls and errors).

Every module here imports the third-party ``mavsdk`` by its absolute name, so this package does not shadow it.
"""
