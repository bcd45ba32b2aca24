"""NanoTrack (a learned Siamese tracker) that says when the target is gone and takes it back when it returns."""

from __future__ import annotations

import copy
import logging
import math
import statistics
from collections import deque

import cv2
import numpy as np

from processors import colour_contrast, target_search
from processors.detector_help import DetectorHelp
from processors.follow import FOLLOW_GAIN, TargetFollower
from processors.nanotrack_net import HOLD_SHARPNESS, RIVAL_LEVEL, NanoTrackNet
from processors.steering import as_box
from uav_values.box import Box

logger = logging.getLogger(__name__)

_APPEARANCE_HISTORY = 5
"""Recent sure frames whose appearance scores make the target's own baseline (their median): short, so that a
gradual change of appearance moves it and only a sudden drop counts as evidence (as in ``csrt``)."""

_MIN_LOOK = 0.3
"""Correlation below this says nothing about the target: a searched place under it is not tried, nor taken where the
target's own level has fallen under it (a car that turned away from its selected appearance: its median then
passed a bush beside it)."""

_SURE = 2.0
"""A place found by the whole-frame search is taken only with a peak this many times ``hold`` as sharp (the 10th
percentile on tracked frames is 7.3, twice the default) and an appearance at least its median: elsewhere in the
frame a look-alike (another walker, another car) is likelier than the target, and the nearby wait takes the target
back at the usual evidence."""

_ADAPT_RATE = 0.01
"""Weight of the box's patch in the adapted appearance on a sure frame that matches as well as usual: it follows
the quick start's car as it turns (10 degrees a second), and at 0.02 or more it learned car14's look-alike too."""

COLOUR_RISE = 0.35
"""Default ``colour_rise``: on the development set a rise of the box's background likeness (-1..1) this far over its
recent median for :data:`_COLOUR_AFTER` frames comes on no tracked target, and a covered target's rises 0.5-0.7
over it where the background's colours are not the target's (car14, group3_2); 0.3 and 0.4 score alike."""

_COLOUR_AFTER = 3
"""Frames in a row whose colours say background that make the target lost: one more than ``lost_after``'s
default, as NanoTrack is sure on them."""

_EXEMPLAR_PX = 64
"""About how many pixels NanoTrack's 127-px template gives the target (the template spans twice its size):
shrinking the frame until the target is this size loses nothing the network would have seen."""


class NanoTrackProcessor(TargetFollower):
    """Track an operator-selected target with NanoTrack v2; judge loss on evidence; re-acquire it when it is back.

    :class:`~processors.nanotrack_net.NanoTrackNet` (NanoTrack v2 on the models shipped in
    :mod:`processors.models`, with the published scale penalty) moves the box on every frame, lost or not, with
    the template of the selection; where its response map has no sharp peak (sharpness under ``hold``) the box
    holds still, so a hidden target is waited for where it was rather than swapped for a look-alike.

    Whether the box is reported is judged apart from tracking. NanoTrack's own score stays high when the target
    has gone (the network finds *something*), so each frame is judged on two questions: is NanoTrack *sure*
    (its map's peak is sharp) and is the target *there* (the appearance at the box, normalised correlation with
    the selected target or with a copy adapted slowly as it changes, whichever is higher
    (:mod:`processors.target_search`), is at least ``loss_ratio`` of its own recent median,
    and no peak of ``rival`` or more stands away from the box). A frame is evidence of loss when the target is
    not there and NanoTrack is unsure or the box is at the frame's edge (a target leaving the view, where a
    sharp peak on what is left of it says little); ``lost_after`` such frames in a row make the target lost
    (``box`` None), until then the box is kept. A sure frame where the target is there takes it back.

    A covered target leaves the box on background where NanoTrack is often sure of a peak, and the template's
    correlation there may be as high as on the target. So the box's colours are judged too
    (:func:`~processors.colour_contrast.background_likeness`: how much more they are like the ring around the
    box than like the selection's): :data:`_COLOUR_AFTER` frames in a row where that rises ``colour_rise`` or more
    above its median over the last tracked frames make the target lost, sure or not, and such a box does not
    take it back.

    While lost, every ``wide_every`` lost frames a coarse correlation search of the whole frame finds the place
    that looks most like the selected target; NanoTrack is tried there (the same template) and moved there only
    on a frame surer than a tracked one (:data:`_SURE`). F2 runs that search on the next frame.

    With ``detect_every`` (the default), a detector helps too (:class:`~processors.detector_help.DetectorHelp`,
    the shipped Yolo-Fastest): at selection it finds the target's class, and while the target is lost, every
    ``detect_every``-th lost frame, the detections of that class near where it was lost are scored by their
    appearance; NanoTrack is tried at the best one and moved there on the ordinary evidence (sure and there,
    the appearance at least its median and :data:`_MIN_LOOK`): the detector's class is the evidence the
    whole-frame search lacks. Not where the target was lost at the frame's edge: it left the view and comes
    back through the edge, where the wait takes it back, and another of its class inside the view is likelier
    than the target. Without a class the whole-frame search alone looks for it, as it does anyway. At most one
    detection, one search and two extra NanoTrack updates a lost frame.

    Frames are tracked shrunk by the largest whole factor that keeps the target at least
    :data:`_EXEMPLAR_PX` across (NanoTrack resamples its window to 255 px anyway); boxes are in full-frame
    pixels. The vector, the overlay and the buttons are :class:`~processors.follow.TargetFollower`'s.

    Args:
        camera: "down" or "forward".
        gain, dead_band, max_speed, vector_t: steering (see processors.steering.Steering).
        follow: "vehicle" (vectors) or "gimbal" (the vehicle holds, the gimbal keeps the target centred:
            ``gimbal_gain`` deg/s per degree off centre, at most ``gimbal_max_rate``; see processors.follow).
        hold: response-map sharpness (peak-to-sidelobe ratio) under which the box holds still and NanoTrack is
            unsure (see :data:`~processors.nanotrack_net.HOLD_SHARPNESS`).
        loss_ratio: appearance, relative to its recent median, under which the box does not show the target.
        rival: a peak this high away from the box (see :func:`~processors.nanotrack_net.rival`) says the
            target may be elsewhere; NanoTrack does not follow such a look-alike when it overtakes the target.
        lost_after: frames of evidence in a row that make the target lost.
        colour_rise: rise of the box's background likeness over its recent median that says the box shows
            background (``inf``: colours not judged).
        wide_every: lost frames between whole-frame searches.
        detect_every: lost frames between detections of the target's class; 0: no detector.
    """

    def __init__(
        self,
        camera: str = "down",
        gain: float = FOLLOW_GAIN,
        dead_band: float = 0.05,
        max_speed: float = 1.0,
        vector_t: float = 0.5,
        follow: str = "vehicle",
        gimbal_gain: float = 2.0,
        gimbal_max_rate: float = 60.0,
        hold: float = HOLD_SHARPNESS,
        loss_ratio: float = 0.5,
        rival: float = RIVAL_LEVEL,
        lost_after: int = 2,
        colour_rise: float = COLOUR_RISE,
        wide_every: int = 5,
        detect_every: int = 2,
    ) -> None:
        super().__init__(camera, gain, dead_band, max_speed, vector_t, follow=follow, gimbal_gain=gimbal_gain,
                         gimbal_max_rate=gimbal_max_rate)
        self.hold, self.loss_ratio, self.rival = hold, loss_ratio, rival
        self.lost_after, self.wide_every = max(1, int(lost_after)), max(1, int(wide_every))
        self.colour_rise = float(colour_rise)
        self._net: NanoTrackNet | None = None
        self._helper = DetectorHelp(every=detect_every) if detect_every > 0 else None
        self._looks: deque[float] = deque(maxlen=_APPEARANCE_HISTORY)
        self._likeness: deque[float] = deque(maxlen=_APPEARANCE_HISTORY)
        self._colours: np.ndarray | None = None
        self._likeness_now: float | None = None
        self._background = False
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
        self._templates = [appearance, appearance.copy()]
        self._colours = colour_contrast.box_histogram(work, box)
        self._likeness.clear()
        self._net = NanoTrackNet(self.hold, self.rival)
        self._net.init(work, tuple(int(round(v)) for v in box))
        self._looks.clear()
        self._on_target(box)
        self._lost_frames, self._left_view = 0, False
        if self._helper is not None:
            self._helper.select(frame, roi)
        logger.info("NanoTrackProcessor: target %s selected (tracked at 1/%d)", roi, self._shrink)
        return True

    def _track(self, frame: np.ndarray) -> None:
        assert self._net is not None  # a target is selected
        work = self._work_frame(frame)
        box, sure, there = self._step(self._net, work)
        search_due = False
        if self._tracking:
            self._update(work, box, sure, there)
        elif sure and there:
            logger.info("NanoTrackProcessor: back on the target (sharpness %.1f, appearance %.2f)",
                        self._net.sharpness, self.look)
            self._on_target(box)
        else:
            self._lost_frames += 1
            search_due = self._lost_frames % self.wide_every == 0
            if self._helper is not None and not self._left_view:
                self._detect(frame, work)
                search_due = search_due and not self._tracking  # not when the detector took it back
        if search_due or self._force_search:  # one search a frame, F2's or the lost target's
            self._force_search = False
            self._search(work)

    def _drop(self) -> None:
        self._net, self._templates, self._work_box = None, [], None
        self._tracking = False

    # ---- internals ------------------------------------------------------------------------------
    def _on_target(self, box: Box) -> None:
        """The target is tracked at ``box`` (selected, or taken back), with no evidence of loss yet."""
        self._work_box, self._tracking, self._evidence = box, True, 0
        if self._helper is not None:
            self._helper.found()

    def _step(self, net: NanoTrackNet, work: np.ndarray) -> tuple[Box, bool, bool]:
        """``net`` updated on ``work``: its box, whether NanoTrack is sure of it (a sharp peak) and whether the
        target is there (its appearance holds and nothing else in the window competes; and, for a lost target, its
        colours are not the background's). The diagnostics ``score`` and ``look`` are this frame's."""
        _, placed = net.update(work)
        box = as_box(placed)
        self.score = net.score
        found = self._appearance(work, box)
        self.look = found.score if found is not None else -1.0
        there = self.look >= self.loss_ratio * self._look_median() and net.rival < self.rival
        self._background = self._shows_background(work, box)
        return box, net.sharpness >= self.hold, there and (self._tracking or not self._background)

    def _shows_background(self, work: np.ndarray, box: Box) -> bool:
        """The box's colours are ``colour_rise`` more like its surroundings than usual (the last tracked frames'
        median); the frame's likeness is kept in ``_likeness_now`` for :meth:`_update`."""
        likeness = None if self._colours is None else colour_contrast.background_likeness(work, box, self._colours)
        self._likeness_now = likeness
        if likeness is None:
            return False
        usual = statistics.median(self._likeness) if self._likeness else likeness
        return likeness >= usual + self.colour_rise

    def _look_median(self) -> float:
        return statistics.median(self._looks) if self._looks else self.look  # numpy's costs 50x on 5 values

    def _update(self, work: np.ndarray, box: Box, sure: bool, there: bool) -> None:
        """A tracked frame: count the evidence, else take the box (and on a sure frame learn the appearance's level,
        and move the adapted appearance towards the box's where it matches as well as usual, away from the edge)."""
        at_edge = _at_edge(box, work)
        weak = (not sure or at_edge) and not there
        if weak or self._background:
            self._evidence += 1
            if self._evidence >= (self.lost_after if weak else _COLOUR_AFTER):
                assert self._net is not None  # a target is selected
                logger.info("NanoTrackProcessor: target lost (sharpness %.1f, appearance %.2f, colours %s)",
                            self._net.sharpness, self.look, "the background's" if self._background else "kept")
                self._tracking, self._lost_frames, self._left_view = False, 0, at_edge
            return  # the last box is kept until the evidence is conclusive
        self._evidence = 0
        self._work_box = box
        if self._likeness_now is not None:
            self._likeness.append(self._likeness_now)
        if sure:
            usual = self._look_median()
            self._looks.append(self.look)
            if self.look >= usual and not at_edge:  # at the edge the patch may be partly the frame's surroundings
                self._templates[1] = target_search.adapted(self._templates[1], work, box, _ADAPT_RATE)

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

    def _search(self, work: np.ndarray) -> None:
        """Coarse correlation search of the whole frame; NanoTrack is tried at the best place and moved there when
        that frame shows the target surely (:data:`_SURE`)."""
        last = self._work_box
        assert last is not None  # a target was selected
        radius = max(work.shape[:2]) / max(last[2], last[3])
        coarse = target_search.search(cv2.cvtColor(work, cv2.COLOR_BGR2GRAY), self._templates, last, radius,
                                      (1.0,), max_side=16)
        found = self._appearance(work, coarse.box, 0.25, (0.8, 1.0, 1.25)) if coarse is not None else None
        if found is not None and found.score >= _MIN_LOOK:
            self._try(work, found.box, _SURE, "in the whole frame")

    def _detect(self, frame: np.ndarray, work: np.ndarray) -> None:
        """The detector's candidate that looks most like the target (:data:`_MIN_LOOK` at least); NanoTrack is
        tried there and moved there on the ordinary evidence (:meth:`_try`)."""
        assert self._helper is not None and self._work_box is not None  # a target was selected
        k = self._shrink
        found = [self._appearance(work, as_box(v / k for v in d.box), 0.25, (0.8, 1.0, 1.25))
                 for d in self._helper.candidates(frame, as_box(v * k for v in self._work_box))]
        best = max((f for f in found if f is not None), key=lambda f: f.score, default=None)
        if best is not None and best.score >= _MIN_LOOK:
            self._try(work, best.box, 1.0, "by the detector")

    def _try(self, work: np.ndarray, place: Box, sharper: float, how: str) -> None:
        """NanoTrack tried at ``place``; moved there when that frame shows the target (there, a peak ``sharper``
        times ``hold`` and an appearance at least its median and :data:`_MIN_LOOK`)."""
        net = self._net
        assert net is not None  # a target was selected
        probe = copy.copy(net)
        probe.move_to(place)
        tracked = self.score, self.look
        box, _, there = self._step(probe, work)
        if there and probe.sharpness >= sharper * self.hold and self.look >= max(self._look_median(), _MIN_LOOK):
            logger.info("NanoTrackProcessor: re-acquired %s at %s (sharpness %.1f, appearance %.2f, last box %s)",
                        how, tuple(round(v * self._shrink) for v in box), probe.sharpness, self.look,
                        tuple(round(v * self._shrink) for v in self._work_box or box))
            self._net = probe
            self._on_target(box)
        else:  # the frame's diagnostics stay those of the tracker kept
            self.score, self.look = tracked


def _at_edge(box: Box, work: np.ndarray) -> bool:
    """The box is within half its size of the frame's edge (its centre within one size): the target may be
    leaving the frame, and correlation there sees part of it."""
    x, y, w, h = box
    return x <= w / 2 or y <= h / 2 or x + 1.5 * w >= work.shape[1] or y + 1.5 * h >= work.shape[0]
