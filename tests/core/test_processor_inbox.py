"""The platform's end of a processor's pipe, read without blocking: whole messages, in order, then the end."""

from __future__ import annotations

import multiprocessing
import pickle
import threading
from multiprocessing.connection import wait

from uav_tui.processor_process import Inbox


def read_all(inbox: Inbox, count: int) -> list[object]:
    messages: list[object] = []
    while len(messages) < count:
        assert wait([inbox], timeout=10), "no data within 10 s"
        messages += [pickle.loads(data) for data in inbox.read()]
    return messages


def test_messages_split_over_reads_or_sharing_one_come_out_whole_and_in_order() -> None:
    ours, theirs = multiprocessing.Pipe()
    inbox = Inbox(ours)
    assert inbox.read() == []  # nothing sent yet: an empty answer, not a wait
    big = bytes(range(256)) * 4000  # 1 MB: more than one read's worth
    sender = threading.Thread(target=lambda: [theirs.send(m) for m in (("claimed", 1, None), ("big", big), ("x",))])
    sender.start()
    assert read_all(inbox, 3) == [("claimed", 1, None), ("big", big), ("x",)]
    sender.join()
    ours.send(("call", 7))  # the platform's own sends still go out (the socket itself stays blocking)
    assert theirs.recv() == ("call", 7)
    theirs.close()
    assert wait([inbox], timeout=10)
    assert inbox.read() is None  # the child's end is gone
    inbox.close()
    assert inbox.closed
    ours.close()
