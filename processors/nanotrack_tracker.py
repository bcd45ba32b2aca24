"""NanoTrack (OpenCV's learned Siamese tracker) that says when the target is gone and takes it back when it returns."""

from __future__ import annotations

import logging
import math
import statistics
from collections import deque

import cv2
import numpy as np

from processors import target_search
from processors.follow import TargetFollower
from processors.models import create_nanotrack
from processors.nanotrack_template import SelectedTemplate
from processors.steering import Box, as_box

logger = logging.getLogger(__name__)

_APPEARANCE_HISTORY = 5
"""Recent tracked frames whose appearance scores make the target's own baseline (their median): short, so that
a gradual change of appearance moves it and only a sudden drop counts as evidence (as in ``csrt``)."""

_SCORE_HISTORY = 10
"""Recent tracked frames whose NanoTrack scores make its running level (their median)."""

_MOTION_HISTORY = 5
"""Recent frames whose centre steps (in box sizes) say how the target has been moving."""

_MIN_SPREAD = 0.03
"""Least spread of NanoTrack's score: on a steady target its scores can sit within 0.01 of each other for
a while, and a flying gull then dips 0.03 (ten frames of dtb70-Gull2) without anything being wrong."""

_MIN_LOOK = 0.3
"""Correlation below this says nothing about the target: it never takes a target back, whatever its median."""

_EXEMPLAR_PX = 64
"""About how many pixels NanoTrack's 127-px template gives the target (the template spans twice its size):
shrinking the frame until the target is this size loses nothing the network would have seen."""


class NanoTrackProcessor(TargetFollower):
    """Track an operator-selected target with NanoTrack v2; judge loss on evidence; re-acquire it when it is back.

    ``cv2.TrackerNano`` with the NanoTrack v2 models shipped in :mod:`processors.models` updates the box on
    every frame. Its own score stays high when the target has gone (the network finds *something*), so loss
    is judged on evidence that does drop, on ``lost_after`` frames without a frame in between that shows the
    target again (until then the box is kept):

    * the appearance at the box (normalised correlation with the selected target's template, see
      :mod:`processors.target_search`) falls below ``loss_ratio`` of the target's own recent median **and**
      NanoTrack's score falls below its own running median by more than ``score_spread`` times its usual
      spread (1.4826 x the median absolute deviation: a standard deviation robust to the outliers it is
      looking for, at least :data:`_MIN_SPREAD`); at the frame's edge (a target leaving it, where correlation
      sees part of it) the weak score alone is evidence; frames on which the score is not weak update the
      medians and the spread (the appearance's median only while the score is at least its median: a changing
      target under a sure network); the template itself never changes (an adapted copy followed the
      look-alike NanoTrack had moved to, and hid the loss: car14 18 of 25 absent frames said lost, 22 without);
    * a step of the box that breaks the recent motion (more than ``jump`` box sizes and ``jump_factor`` times
      the recent steps) is checked against where the motion says the target is: if the appearance there is
      at least as good, NanoTrack restarts there (it had jumped to a look-alike), else the step stands.

    While lost, NanoTrack keeps running: a target that comes back near it is taken back when both pieces of
    evidence hold again (appearance ``accept_ratio`` of its median, score above the floor, away from the
    frame's edge). Else a correlation search around the last position runs (a window that grows with the
    frames lost, up to 3 target sizes), and every ``wide_every`` lost frames a coarse one of the whole frame;
    a place further than the target could have gone since (its largest recent step + 1 size, per frame) is
    ignored. The best place is tried with a NanoTrack holding the selected template
    (:class:`~processors.nanotrack_template.SelectedTemplate`), taken on the same evidence: at most one
    search and one extra NanoTrack update a lost frame.

    Frames are tracked shrunk by the largest whole factor that keeps the target at least
    :data:`_EXEMPLAR_PX` across (NanoTrack resamples its window to 255 px anyway); boxes are in full-frame
    pixels. The vector, the overlay and the buttons are :class:`~processors.follow.TargetFollower`'s.

    Args:
        camera: "down" or "forward".
        gain, dead_band, max_speed, vector_t: steering (see processors.steering.Steering).
        follow: "vehicle" (vectors) or "gimbal" (the vehicle holds, the gimbal keeps the target centred:
            ``gimbal_gain`` deg/s per degree off centre, at most ``gimbal_max_rate``; see processors.follow).
        loss_ratio, loss_score: appearance evidence: below both ``loss_ratio`` x the recent median and ``loss_score``.
        score_spread: NanoTrack-score evidence: this many spreads below its running median.
        jump, jump_factor: a step of the box (centre, in box sizes) that is checked against the motion.
        lost_after: frames of evidence, with none showing the target between them, that make the target lost.
        accept_ratio: appearance score, relative to the median, that takes the target back.
        wide_every: lost frames between whole-frame searches.
    """

    def __init__(
        self,
        camera: str = "down",
        gain: float = 0.8,
        dead_band: float = 0.05,
        max_speed: float = 1.0,
        vector_t: float = 0.5,
        follow: str = "vehicle",
        gimbal_gain: float = 2.0,
        gimbal_max_rate: float = 60.0,
        loss_ratio: float = 0.5,
        loss_score: float = 0.45,
        score_spread: float = 2.0,
        jump: float = 0.75,
        jump_factor: float = 4.0,
        lost_after: int = 2,
        accept_ratio: float = 0.75,
        wide_every: int = 5,
    ) -> None:
        super().__init__(camera, gain, dead_band, max_speed, vector_t, follow=follow, gimbal_gain=gimbal_gain,
                         gimbal_max_rate=gimbal_max_rate)
        self.loss_ratio, self.loss_score, self.score_spread = loss_ratio, loss_score, score_spread
        self.jump, self.jump_factor = jump, jump_factor
        self.lost_after, self.accept_ratio = max(1, int(lost_after)), accept_ratio
        self.wide_every = max(1, int(wide_every))
        self._tracker: cv2.TrackerNano | None = None
        self._selected: SelectedTemplate | None = None  # NanoTrack's template at selection, to start it elsewhere
        self._looks: deque[float] = deque(maxlen=_APPEARANCE_HISTORY)
        self._levels: deque[float] = deque(maxlen=_SCORE_HISTORY)
        self._steps: deque[float] = deque(maxlen=_MOTION_HISTORY)
        self._nano_box: Box | None = None  # work-frame pixels: where NanoTrack is now (it keeps running while lost)
        self._velocity = (0.0, 0.0)  # work-frame pixels per frame of the accepted box's centre
        self._speed = 0.0  # the largest recent step (box sizes a frame) when the target was lost
        self.look = 0.0
        """Appearance score (normalised correlation) of the last box: diagnostics."""

    # ---- hooks ----------------------------------------------------------------------------------
    def _start(self, frame: np.ndarray, roi: Box) -> bool:
        self._shrink = max(1, int(math.sqrt(roi[2] * roi[3]) // _EXEMPLAR_PX))
        work = self._work_frame(frame)
        box = as_box(v / self._shrink for v in roi)
        appearance = target_search.template(cv2.cvtColor(work, cv2.COLOR_BGR2GRAY), box)
        if appearance is None:
            logger.warning("NanoTrackProcessor: ROI %s is too small to track, ignored", roi)
            return False
        self._templates = [appearance]
        self._selected = SelectedTemplate(work, box)
        self._looks.clear()
        self._levels.clear()
        self._restart(work, box)
        logger.info("NanoTrackProcessor: target %s selected (tracked at 1/%d)", roi, self._shrink)
        return True

    def _track(self, frame: np.ndarray) -> None:
        work = self._work_frame(frame)
        if self._tracking:
            self._update(work)
        else:
            self._lost_frames += 1
            self._update_lost(work)
        if self._force_search:
            self._force_search = False
            self._search(work, whole=True)

    def _drop(self) -> None:
        self._tracker, self._templates, self._work_box, self._nano_box = None, [], None, None
        self._selected = None
        self._tracking = False

    # ---- internals ------------------------------------------------------------------------------
    def _restart(self, work: np.ndarray, box: Box) -> None:
        """NanoTrack (re)started on ``box``: its template is what is there now."""
        self._tracker = create_nanotrack()
        self._tracker.init(work, tuple(int(round(v)) for v in box))
        self._work_box = self._nano_box = box
        self._tracking = True
        self._evidence = self._lost_frames = 0
        self._steps.clear()
        self._velocity = (0.0, 0.0)

    def _nano(self, work: np.ndarray) -> tuple[Box, float]:
        assert self._tracker is not None  # a target is selected
        _, (x, y, w, h) = self._tracker.update(work)
        box = self._nano_box = (float(x), float(y), float(w), float(h))
        self.score = float(self._tracker.getTrackingScore())
        return box, self.score

    def _appearance(self, work: np.ndarray, box: Box, radius: float = 0.25,
                    scales: tuple[float, ...] = (1.0,)) -> target_search.Found | None:
        """Best correlation of the templates with ``work`` around ``box`` (only the window it can touch is read)."""
        x, y, w, h = box
        reach = radius * max(w, h) * max(scales) * 1.3 + 2
        x0, y0 = max(int(x - reach), 0), max(int(y - reach), 0)
        x1, y1 = min(int(x + w + reach) + 1, work.shape[1]), min(int(y + h + reach) + 1, work.shape[0])
        if x1 - x0 < 4 or y1 - y0 < 4:
            return None
        gray = cv2.cvtColor(work[y0:y1, x0:x1], cv2.COLOR_BGR2GRAY)
        found = target_search.search(gray, self._templates, (x - x0, y - y0, w, h), radius, scales)
        if found is None:
            return None
        fx, fy, fw, fh = found.box
        return target_search.Found((fx + x0, fy + y0, fw, fh), found.score)

    def _look_median(self) -> float:
        return statistics.median(self._looks) if self._looks else self.look  # numpy's costs 50x on 5 values

    def _score_floor(self) -> float:
        """NanoTrack scores below this are evidence: its running median less ``score_spread`` spreads."""
        if len(self._levels) < 3:
            return 0.0
        level = statistics.median(self._levels)
        spread = 1.4826 * statistics.median(abs(v - level) for v in self._levels)
        return level - self.score_spread * max(spread, _MIN_SPREAD)

    def _is_target(self, look: float, score: float | None, box: Box, work: np.ndarray) -> bool:
        """The evidence that takes a target back: appearance near its median and, for a place that was searched
        for (``score`` given: the best of many places correlates better than a chance one), NanoTrack's score
        above its floor; away from the frame's edge (where part of a target cannot be told from the ground)."""
        return (look >= max(self.accept_ratio * self._look_median(), _MIN_LOOK)
                and (score is None or score >= self._score_floor()) and not _at_edge(box, work))

    def _update(self, work: np.ndarray) -> None:
        previous = self._work_box
        assert previous is not None  # set whenever tracking starts
        box, score = self._nano(work)
        step = _step(previous, box)
        usual = statistics.median(self._steps) if self._steps else 0.0
        if step > max(self.jump, self.jump_factor * usual):
            box, step = self._check_jump(work, previous, box, step)
        match = self._appearance(work, box)
        self.look = match.score if match is not None else -1.0
        baseline, floor = self._look_median(), self._score_floor()
        weak_look = self.look < min(self.loss_ratio * baseline, self.loss_score)
        weak_score = score < floor
        if weak_score and (weak_look or _at_edge(box, work)):
            self._evidence += 1
            if self._evidence >= self.lost_after:
                logger.info("NanoTrackProcessor: target lost (appearance %.2f of median %.2f, score %.2f under %.2f)",
                            self.look, baseline, score, floor)
                self._tracking = False
                self._lost_frames = 0
                self._speed = max(self._steps, default=0.0)
            return  # the last box is kept until the evidence is conclusive
        if self._is_target(self.look, score, box, work):
            self._evidence = 0  # only a frame that shows the target clears the evidence (one that merely is not
            # evidence, like a patch of road at the frame's edge correlating by chance, leaves it standing)
        px, py = _centre(previous)
        cx, cy = _centre(box)
        self._velocity = (cx - px, cy - py)
        self._work_box = box
        self._steps.append(step)
        if weak_score or (weak_look and score < statistics.median(self._levels or [score])):
            return  # a doubtful frame: the box stands, the target's baselines do not learn from it
        self._looks.append(self.look)  # a weak look under a sure network: the target changes its appearance
        self._levels.append(score)

    def _check_jump(self, work: np.ndarray, previous: Box, box: Box, step: float) -> tuple[Box, float]:
        """NanoTrack stepped further than the target has been moving: keep the step or go where the motion says."""
        x, y, w, h = previous
        predicted = (x + self._velocity[0], y + self._velocity[1], w, h)
        stayed = self._appearance(work, predicted, 0.5)
        jumped = self._appearance(work, box)
        if stayed is not None and (jumped is None or stayed.score >= jumped.score):
            logger.info("NanoTrackProcessor: a %.1f-box step against the motion; back where the target was "
                        "(appearance %.2f vs %.2f)", step, stayed.score, jumped.score if jumped else -1.0)
            self._tracker = create_nanotrack()  # its template: the target as it looks now, where it is
            self._tracker.init(work, tuple(int(round(v)) for v in stayed.box))
            self._nano_box = stayed.box
            return stayed.box, _step(previous, stayed.box)
        return box, step

    def _update_lost(self, work: np.ndarray) -> None:
        """While lost: NanoTrack's box is taken back on the evidence; else search near, then the whole frame."""
        box, score = self._nano(work)
        match = self._appearance(work, box)
        self.look = match.score if match is not None else -1.0
        if self._is_target(self.look, None, box, work):  # NanoTrack's own box: its score dips on a returning target
            logger.info("NanoTrackProcessor: back on the target (appearance %.2f, score %.2f)", self.look, score)
            self._tracking, self._evidence, self._work_box = True, 0, box
            self._steps.clear()
            return
        self._search(work, whole=self._lost_frames % self.wide_every == 0)

    def _search(self, work: np.ndarray, whole: bool) -> None:
        """Correlation search near the last position (a window growing with the frames lost) or of the whole frame;
        the best place is tried with a NanoTrack holding the selected template, and taken on the same evidence."""
        last, selected = self._work_box, self._selected
        assert last is not None and selected is not None  # a target was selected and tracked
        if whole:
            radius = max(work.shape[:2]) / max(last[2], last[3])
            coarse = target_search.search(cv2.cvtColor(work, cv2.COLOR_BGR2GRAY), self._templates, last, radius,
                                          (1.0,), max_side=16)
            found = self._appearance(work, coarse.box, 0.25, (0.8, 1.0, 1.25)) if coarse is not None else None
        else:
            found = self._appearance(work, last, min(0.5 + 0.5 * self._lost_frames, 3.0), (0.8, 1.0, 1.25))
        if found is None or found.score < max(self.accept_ratio * self._look_median(), _MIN_LOOK):
            return
        if _step(last, found.box) > self._lost_frames * (self._speed + 1.0):
            return  # further than the target could have gone since it was lost
        probe = selected.tracker_at(work, found.box)
        _, placed = probe.update(work)
        box, score = as_box(placed), float(probe.getTrackingScore())
        match = self._appearance(work, box)
        look = match.score if match is not None else -1.0
        if self._is_target(look, score, box, work):
            logger.info("NanoTrackProcessor: re-acquired %s (appearance %.2f, score %.2f)",
                        "in the whole frame" if whole else "nearby", look, score)
            self._tracker, self.look, self.score = probe, look, score
            self._work_box = self._nano_box = box
            self._tracking, self._evidence = True, 0
            self._steps.clear()
            self._velocity = (0.0, 0.0)


def _at_edge(box: Box, work: np.ndarray) -> bool:
    """The box is within half its size of the frame's edge (its centre within one size): the target may be
    leaving the frame, and correlation there sees part of it."""
    x, y, w, h = box
    return x <= w / 2 or y <= h / 2 or x + 1.5 * w >= work.shape[1] or y + 1.5 * h >= work.shape[0]


def _centre(box: Box) -> tuple[float, float]:
    return box[0] + box[2] / 2, box[1] + box[3] / 2


def _step(previous: Box, box: Box) -> float:
    """Centre displacement from ``previous`` to ``box``, in ``previous``'s sizes (geometric mean of its sides)."""
    (px, py), (cx, cy) = _centre(previous), _centre(box)
    return math.hypot(cx - px, cy - py) / max(math.sqrt(previous[2] * previous[3]), 1.0)
