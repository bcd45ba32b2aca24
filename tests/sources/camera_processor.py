"""Test processor: saves, every frame, what ``tmMgr.camera()`` says (and a pixel -> ray -> pixel round trip)."""


class CameraSeen:
    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        camera = self.tmMgr.camera()
        if camera is None:
            self.tmMgr.save(frame, camera="none")
            return
        u, v = camera.ray_to_pixel(camera.pixel_to_ray(10.0, 20.0))
        self.tmMgr.save(frame, camera=camera.origin, fx=camera.fx, width=camera.width, tilt=camera.mount.tilt_deg,
                        round_trip_px=abs(u - 10.0) + abs(v - 20.0))


class CameraSeenCrashingOnce(CameraSeen):
    """As CameraSeen, but its process dies at its 5th frame the first time (``flag`` is the file that says so)."""

    def __init__(self, flag):
        super().__init__()
        self.flag, self.frames = flag, 0

    def photo_processing(self, frame):
        import os
        from pathlib import Path

        self.frames += 1
        if self.frames == 5 and not Path(self.flag).exists():
            Path(self.flag).touch()
            os._exit(3)
        super().photo_processing(frame)
