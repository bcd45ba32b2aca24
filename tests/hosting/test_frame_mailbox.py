"""The frame mailbox: the newest offer wins, the platform learns whether the one it replaced was taken.

The processor's side runs in a real second process (spawned, attaching by the address as the child does).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time
from multiprocessing.connection import wait

import pytest

from uav_tui.hosting.frame_mailbox import _WATCH, _WATCH_AT, FrameMailbox, MailboxGone, Offer


def offer(gen: int, seq: int | None = None, telemetry: bytes = b"", heartbeat_age_s: float | None = None) -> Offer:
    return Offer(gen, f"slot{gen}", (480, 640, 3), seq or gen, 10 * gen, 20 * gen, telemetry, heartbeat_age_s)


@pytest.fixture
def mailbox() -> FrameMailbox:
    box = FrameMailbox.create()
    yield box
    box.close()


def claim_in_another_process(box: FrameMailbox) -> str:
    """Claim once from a fresh interpreter attached by address; what it got, as text."""
    code = textwrap.dedent(f"""
        from uav_tui.hosting.frame_mailbox import FrameMailbox
        box = FrameMailbox.attach("{box.address}")
        got = box.claim()
        print(None if got is None else
              (got.gen, got.slot, got.shape, got.seq, got.t_mono_ns, got.telemetry, got.heartbeat_age_s))
        box.close()
    """)
    return subprocess.run([sys.executable, "-c", code], pass_fds=box.fds, capture_output=True,
                          text=True, check=True, timeout=60).stdout.strip()


def test_the_newest_offer_is_claimed_and_the_replaced_one_reported_untaken(mailbox: FrameMailbox) -> None:
    assert mailbox.offer(offer(1)) == (0, False)  # nothing was on offer
    assert mailbox.offer(offer(2, telemetry=b"tm", heartbeat_age_s=0.25)) == (1, False)  # 1 replaced, not taken
    assert claim_in_another_process(mailbox) == "(2, 'slot2', (480, 640, 3), 2, 20, b'tm', 0.25)"
    assert claim_in_another_process(mailbox) == "None"  # taken already: a claim gets each offer once
    assert mailbox.offer(offer(3)) == (2, True)  # the platform learns 2 went to the processor
    assert claim_in_another_process(mailbox) == "(3, 'slot3', (480, 640, 3), 3, 30, b'', None)"  # no heartbeat


def test_an_offer_wakes_a_waiting_processor_and_clear_wake_rearms_it(mailbox: FrameMailbox) -> None:
    mailbox.clear_wake()
    assert wait([mailbox], timeout=0) == []
    mailbox.offer(offer(1))
    assert wait([mailbox], timeout=0) == [mailbox]
    mailbox.clear_wake()
    assert wait([mailbox], timeout=0) == []


def test_a_two_axis_frame_keeps_its_shape(mailbox: FrameMailbox) -> None:
    mailbox.offer(Offer(1, "grey", (120, 160), 1, 0, 0, b""))
    assert mailbox.claim().shape == (120, 160)


def test_a_lock_never_released_and_a_closed_mailbox_are_errors_not_hangs(mailbox: FrameMailbox) -> None:
    os.eventfd_read(mailbox.lock_fd)  # as if the processor died inside claim(), holding the lock
    with pytest.raises(MailboxGone, match="died holding it"):
        mailbox.offer(offer(1))
    os.eventfd_write(mailbox.lock_fd, 1)
    mailbox.close()
    with pytest.raises(MailboxGone, match="closed"):
        mailbox.offer(offer(2))
    mailbox.close()  # idempotent


def test_an_offer_that_does_not_fit_is_refused(mailbox: FrameMailbox) -> None:
    with pytest.raises(ValueError, match="telemetry 65536 bytes"):
        mailbox.offer(offer(1, telemetry=bytes(64 * 1024)))
    with pytest.raises(ValueError, match="slot name 65 bytes"):
        mailbox.offer(Offer(1, "s" * 65, (2, 2, 3), 1, 0, 0, b""))


def test_the_last_claim_and_its_time_are_read_without_waiting(mailbox: FrameMailbox) -> None:
    assert mailbox.last_claim() == (0, 0)  # nothing claimed yet
    mailbox.offer(offer(1))
    before = time.monotonic_ns()
    claim_in_another_process(mailbox)
    gen, claimed_ns = mailbox.last_claim()
    assert gen == 1 and before <= claimed_ns <= time.monotonic_ns()  # one clock for both processes
    os.eventfd_read(mailbox.lock_fd)  # the processor is claiming at this instant
    assert mailbox.last_claim() is None  # no wait: the watchdog asks again later
    os.eventfd_write(mailbox.lock_fd, 1)
    mailbox.close()
    assert mailbox.last_claim() is None


def test_the_platform_waits_for_a_claim_and_only_then_is_it_signalled(mailbox: FrameMailbox) -> None:
    mailbox.offer(offer(1))
    claim_in_another_process(mailbox)
    assert wait([mailbox.claimed_fd], timeout=0) == []  # nobody waited: the claim signalled nothing
    assert mailbox.wait_claimed(1, timeout_s=0)  # claimed already: no wait
    mailbox.offer(offer(2))
    started = time.monotonic()
    assert not mailbox.wait_claimed(2, timeout_s=0.2)  # not claimed: times out
    assert time.monotonic() - started >= 0.2
    claim_in_another_process(mailbox)  # the platform now waits for gen 2: this claim signals
    assert wait([mailbox.claimed_fd], timeout=0) == [mailbox.claimed_fd]
    assert mailbox.wait_claimed(2, timeout_s=5)
    os.eventfd_read(mailbox.claimed_fd)
    mailbox.offer(offer(3))
    claim_in_another_process(mailbox)  # the watch for gen 2 was used up: nobody waits, nothing is signalled
    assert wait([mailbox.claimed_fd], timeout=0) == []


def test_closing_wakes_a_thread_waiting_for_a_claim_before_its_descriptors_go(mailbox: FrameMailbox) -> None:
    mailbox.offer(offer(1))
    outcome: list[BaseException | bool] = []

    def wait_for_the_claim() -> None:
        try:
            outcome.append(mailbox.wait_claimed(1, timeout_s=30))
        except BaseException as exc:  # noqa: BLE001 - what it raised is the result
            outcome.append(exc)

    waiter = threading.Thread(target=wait_for_the_claim)
    waiter.start()
    while not _WATCH.unpack_from(mailbox._shm.buf, _WATCH_AT)[0]:  # it waits once it posted the gen it watches
        time.sleep(0.001)
    descriptors = mailbox.fds
    mailbox.close()  # the process worker closes a dead child's mailbox while the capture thread waits
    waiter.join(timeout=10)
    assert not waiter.is_alive()  # woken, not left waiting out its timeout on a closed descriptor
    assert len(outcome) == 1 and isinstance(outcome[0], MailboxGone)  # not EBADF, not a read of a reused fd
    for fd in descriptors:
        with pytest.raises(OSError):
            os.fstat(fd)  # and the descriptors are closed all the same


def test_a_claim_made_before_the_processor_died_still_counts_after_the_close(mailbox: FrameMailbox) -> None:
    """The child claims a replay's frame and dies on it; its mailbox is closed before the capture thread asks.

    The frame was taken (the replay goes on after it); an offer it never claimed is still MailboxGone. Before,
    both raised, and under load the replay offered the dead child's frame again to its successor (CI, stop 43).
    """
    mailbox.offer(offer(1))
    claim_in_another_process(mailbox)
    mailbox.offer(offer(2))
    mailbox.close()
    assert mailbox.wait_claimed(1, timeout_s=0)
    with pytest.raises(MailboxGone):
        mailbox.wait_claimed(2, timeout_s=0)
