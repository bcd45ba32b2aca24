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
