"""Processor hosting: everything that runs a researcher's processor and hands it frames.

- :mod:`~uav_tui.hosting.host`: ``ProcessorHost``, the Protocol both hosts satisfy, and what they hand the platform.
- :mod:`~uav_tui.hosting.thread_host`: ``isolation = "thread"``, the processor on a thread of the platform.
  :mod:`~uav_tui.hosting.thread_logs` bounds the log records it makes there.
- :mod:`~uav_tui.hosting.process_host`: ``isolation = "process"``, the processor in a child process of its own.
  It joins :mod:`~uav_tui.hosting.frame_feeder` (frames offered to the child),
  :mod:`~uav_tui.hosting.child_link` (its pipe) and :mod:`~uav_tui.hosting.supervisor` (watchdog and restarts).
- :mod:`~uav_tui.hosting.wire` and :mod:`~uav_tui.hosting.pipe`: every message between platform and child, and
  how it travels; :mod:`~uav_tui.hosting.frame_call`: the one per-frame call every host (and eval) makes.
- :mod:`~uav_tui.hosting.child_process`: one child as the platform sees it (started, its output, its end).
- :mod:`~uav_tui.hosting.child`: the child's main loop (``python -m uav_tui.hosting.child``).
- :mod:`~uav_tui.hosting.frame_ring` and :mod:`~uav_tui.hosting.frame_mailbox`: frames in shared memory and the
  newest one on offer to the child.
- :mod:`~uav_tui.hosting.operator_calls`, :mod:`~uav_tui.hosting.exception_reports`: the operator's calls into the
  processor, and its exceptions said as events.
- :mod:`~uav_tui.hosting.malloc_tuning`, :mod:`~uav_tui.hosting.opencv_pool`: allocator and OpenCV thread pool
  settings for processes that handle images every frame.

The child imports only what it needs from here (``tests/hosting/test_isolation.py`` lists it): importing this package
loads nothing else.
"""
