"""The platform's end of a processor's pipe, read without blocking: whole messages, in order, then the end."""

from __future__ import annotations

import multiprocessing
import threading
from multiprocessing.connection import wait

import numpy as np

from uav_tui.hosting.codec import TO_CHILD, decode_from_child
from uav_tui.hosting.pipe import Inbox, send_message, send_to_child
from uav_tui.hosting.wire import Forget, FromChild, Reply, Save


def read_all(inbox: Inbox, count: int) -> list[FromChild]:
    messages: list[FromChild] = []
    while len(messages) < count:
        assert wait([inbox], timeout=10), "no data within 10 s"
        messages += [decode_from_child(data, buffers) for data, buffers in inbox.read()]
    return messages


def test_messages_split_over_reads_or_sharing_one_come_out_whole_and_in_order() -> None:
    ours, theirs = multiprocessing.Pipe()
    inbox = Inbox(ours)
    assert inbox.read() == []  # nothing sent yet: an empty answer, not a wait
    image = np.arange(720 * 1280 * 3, dtype=np.uint32).astype(np.uint8).reshape(720, 1280, 3)  # 2.7 MB
    small = np.full((10, 10), 7, np.uint8)
    saves = (Save(image, {"n": 1}), Save(small, {"n": 2, "mask": small}))
    sent = [Reply(1, True, 5, (), None, ()), Reply(2, True, 6, ("slot",), "ok", saves),
            Reply(3, True, 7, (), None, (Save(None, {"raw": b"bytes stay in band"}),))]
    sender = threading.Thread(target=lambda: [send_message(theirs, m) for m in sent])
    sender.start()
    got = read_all(inbox, 3)
    sender.join()
    assert got[0] == sent[0] and got[2] == sent[2]
    assert isinstance(got[1], Reply)
    (image_back, extra), (small_back, small_extra) = ((s.image, s.extra) for s in got[1].saves)
    assert extra == {"n": 1} and np.array_equal(image_back, image) and np.array_equal(small_back, small)
    assert np.array_equal(small_extra["mask"], small)  # an array in ``extra`` travels like the image
    image_back[0, 0] = 1  # arrays arrive writable, in buffers of their own
    send_to_child(ours, Forget(("a",)))  # the platform's own sends still go out (the socket itself stays blocking)
    assert TO_CHILD.decode(theirs.recv_bytes()) == Forget(("a",))
    theirs.close()
    assert wait([inbox], timeout=10)
    assert inbox.read() is None  # the child's end is gone
    inbox.close()
    assert inbox.closed
    ours.close()
