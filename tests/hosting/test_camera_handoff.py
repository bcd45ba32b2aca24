"""The camera model reaches the processor's process before the first frame of its source, however late its pipe is read.

The model goes over the pipe and frames through the shared-memory mailbox, so a child can claim a frame before it has
read the message sent ahead of it. Here the pipe is made late (its camera messages delivered 0.5 s after they are
sent, the narrowest point that reorders the two channels) and the processor raises on a frame without a model.
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np

from sources.buffer import FrameBuffer
from tests.hosting.hosts import collect
from uav_tui.events import EventLog
from uav_tui.hosting.child_process import ChildProcess
from uav_tui.hosting.host import ProcessedFrame
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.hosting.wire import Camera, ToChild
from uav_values.camera import CameraModel

CAMERA_OR_ERROR = '''
class CameraOrError:
    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        camera = self.tmMgr.camera()
        if camera is None:
            raise RuntimeError("a frame before its camera model")
        return camera.width
'''


async def test_a_frame_offered_before_its_camera_message_is_read_waits_for_it(tmp_path: Path) -> None:
    (tmp_path / "camera_or_error.py").write_text(CAMERA_OR_ERROR)
    results: list[ProcessedFrame] = []
    worker = await SubprocessHost.start(f"{tmp_path}/camera_or_error.py:CameraOrError", {}, results.append,
                                        events=EventLog(), on_fault=print)
    send, late = worker._link.send, []

    def late_camera(child: ChildProcess, message: ToChild) -> bool:
        if not isinstance(message, Camera):
            return send(child, message)
        late.append(threading.Timer(0.5, send, (child, message)))
        late[-1].start()
        return True

    worker._link.send = late_camera  # type: ignore[method-assign]
    buffer = FrameBuffer()
    try:
        worker.attach(buffer, CameraModel.from_hfov(32, 24, 90.0))
        buffer.put(np.zeros((24, 32, 3), np.uint8))
        await collect(worker, results, 1)
    finally:
        worker.close()
        for timer in late:
            timer.join()
    assert len(late) == 1
    assert [result.outcome.error for result in results] == [None]
