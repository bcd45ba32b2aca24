"""The decoder thread count a replay keeps: the faster one, one thread on a tie, the other tried again in time."""

from __future__ import annotations

from sources.decoder_threads import FFMPEG_DEFAULT, MIN_FRAMES, RETRY_S, SINGLE, WINDOW_S, DecoderThreads


def replay(choice: DecoderThreads, fps: dict[int, float], start: float, seconds: float) -> tuple[float, list[int]]:
    """Feed frames at ``fps[current count]`` for ``seconds``, switching as asked; the time and the switches."""
    now, switches = start, []
    while now < start + seconds:
        now += 1 / fps[choice.threads]
        wanted = choice.frame(now)
        if wanted is not None:
            switches.append(wanted)
            choice.switched(wanted, now)
    return now, switches


def test_starts_on_one_thread_tries_ffmpegs_and_keeps_one_on_a_tie() -> None:
    choice = DecoderThreads()
    now, switches = replay(choice, {SINGLE: 1000, FFMPEG_DEFAULT: 1030}, 0.0, 4.5 * WINDOW_S)
    # warm-up, a window on one thread, a window on FFmpeg's (3 % faster: not enough), back to one
    assert switches == [FFMPEG_DEFAULT, SINGLE]
    assert choice.threads == SINGLE
    assert set(choice.rates) == {SINGLE, FFMPEG_DEFAULT}


def test_keeps_ffmpegs_threads_when_they_replay_faster_and_tries_one_again_later() -> None:
    choice = DecoderThreads()
    now, switches = replay(choice, {SINGLE: 1000, FFMPEG_DEFAULT: 1200}, 0.0, 5 * WINDOW_S)
    assert switches == [FFMPEG_DEFAULT] and choice.threads == FFMPEG_DEFAULT
    # the processor got slower (a target selected): decoding no longer limits the rate, one thread is enough
    now, switches = replay(choice, {SINGLE: 100, FFMPEG_DEFAULT: 100}, now, 3 * WINDOW_S)
    assert switches == [SINGLE]
    # and FFmpeg's threads are tried again once their rate is RETRY_S old: one window, then back
    now, switches = replay(choice, {SINGLE: 100, FFMPEG_DEFAULT: 100}, now, RETRY_S + 2 * WINDOW_S)
    assert switches == [FFMPEG_DEFAULT, SINGLE]


def test_a_window_holds_enough_frames_to_compare() -> None:
    choice = DecoderThreads()
    slow = {SINGLE: 5, FFMPEG_DEFAULT: 5}  # a slow processor: 30 frames take 6 s
    now, switches = replay(choice, slow, 0.0, (2 * MIN_FRAMES - 1.5) / 5)
    assert switches == []  # the warm-up and the first window need MIN_FRAMES frames each
    _, switches = replay(choice, slow, now, 1.0)
    assert switches == [FFMPEG_DEFAULT]
