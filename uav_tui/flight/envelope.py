"""The autonomy envelope: where, how high and how long the processor's vectors may fly the vehicle.

The autonomy gate asks :meth:`Envelope.confine` about every vector it would send: a vector whose predicted end
point (position + velocity x (duration + ``response_lag_s``)) leaves the radius or the polygon is cut short to end
on the boundary, or refused when nothing of it is left; within ``boundary_band_m`` of the boundary its outward
component is removed first (it slides along the boundary, never through it); a vehicle outside (the envelope was
set in flight, wind) is flown only back in. Its watchdog asks :meth:`Envelope.breach`: a vehicle outside the
height band, an engagement longer than ``max_autonomy_s``, a battery below its floor, a link quality below its
floor for ``link_floor_s`` (a quality nothing reports, or none for :data:`LINK_FRESH_S`, never acts) or a target
the processor stopped reporting for ``lost_after_s`` ends autonomy with the configured action (:func:`carry_out`;
``last_seen`` flies back to where the vehicle was when the target was last reported, :mod:`.fly_back`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from controllers.base import FlightController, Telemetry
from controllers.sim.geo import Home
from uav_tui.config import Config, EnvelopeConfig
from uav_tui.errors import ConfigError
from uav_tui.events import EventLog
from uav_tui.flight.envelope_shape import Circle, Point, Polygon, Shape, origin_of, read_polygon, to_local
from uav_tui.flight.geolocate import ground_height
from uav_tui.flight.telemetry import TelemetryManager

MIN_VECTOR_S = 0.05
"""A vector cut shorter than this is refused: one setpoint, nothing a processor can steer with."""

MIN_DRIFT_MS = 0.05
"""Outward speed below this, in the boundary band, is not braked (a vehicle holding still, sensor noise)."""

LINK_FRESH_S = 5.0
"""A link quality received longer ago than this is not known (its source went quiet: the heartbeat judges the link
then)."""

_GROUND_FIELDS = ("roll_deg", "pitch_deg", "rangefinder_m", "terrain_height_m", "rangefinder_t_ns", "terrain_t_ns",
                  "rel_alt_m")


@dataclass(frozen=True, slots=True)
class Confined:
    """What the envelope makes of a vector: the vector to fly (None: refused) and what it changed, with the
    stable ``key`` repeats of the same refusal are counted under."""

    vector: tuple[float, float, float] | None
    note: str = ""
    key: str = ""


@dataclass(frozen=True, slots=True)
class Breach:
    """A limit the vehicle is past: what to do (``hold``, ``rtl``, ``land``, ``last_seen``) and why; ``point``
    (north, east) is where ``last_seen`` flies to."""

    action: str
    reason: str
    point: Point | None = None


class Envelope:
    """The configured limits, checked against the newest telemetry.

    The polygon is in latitude/longitude; it becomes local metres once home is known (:meth:`set_home`, or the
    first telemetry with a position), and a polygon that does not contain home then refuses autonomy
    (:attr:`refusal`).
    """

    def __init__(self, config: EnvelopeConfig, events: EventLog, clock: Callable[[], float] = time.monotonic) -> None:
        self.config = config
        self.events = events
        self.clock = clock
        self.cut = 0
        """Vectors cut short or turned at the boundary."""
        self.refused = 0
        """Vectors refused (also counted in the gate's rejected)."""
        self.refusal = ""
        """Why autonomy may not be switched on (a polygon that does not contain home)."""
        self._vertices = read_polygon(config.polygon) if config.polygon.strip() else None
        self.shapes: list[Shape] = [Circle(config.radius_m)] if config.radius_m > 0 else []
        self._engaged_at: float | None = None
        self._seen_at: float | None = None
        """When the processor last reported its target (a box or a vector) in this engagement."""
        self._seen_where: Point | None = None
        """Where the vehicle was then (north, east), if its position was known."""
        self._link_low_since: float | None = None
        """Since when the link quality has been below its floor (None: it is not, or is not known)."""

    def describe(self) -> str:
        """The limits in force, in one line (said at start)."""
        c = self.config
        limits = [f"radius {c.radius_m:g} m"] if c.radius_m else []
        limits += [f"polygon {Path(c.polygon).name}"] if c.polygon.strip() else []
        for low, high, what in ((c.min_height_m, c.max_height_m, "above the ground"),
                                (c.min_home_height_m, c.max_home_height_m, "above home")):
            band = " to ".join(f"{v:g} m" for v in (low, high) if v)
            limits += [f"height {'>= ' if low and not high else '<= ' if high and not low else ''}{band} {what} "
                       f"({c.height_action})"] if band else []
        limits += [f"{c.max_autonomy_s:g} s an engagement ({c.time_action})"] if c.max_autonomy_s else []
        floors = " or ".join(f"{v:g} {unit}" for v, unit in ((c.battery_floor_pct, "%"), (c.battery_floor_v, "V")) if v)
        limits += [f"battery above {floors} ({c.battery_action})"] if floors else []
        limits += [f"link quality above {c.link_floor_pct:g} % (for {c.link_floor_s:g} s, {c.link_action})"
                   ] if c.link_floor_pct else []
        limits += [f"target lost {c.lost_after_s:g} s ({c.lost_action})"] if c.lost_after_s else []
        return "envelope: " + ("; ".join(limits) or "none")

    @property
    def horizontal(self) -> bool:
        """A radius or a polygon is configured."""
        return bool(self.shapes) or self._vertices is not None

    def set_home(self, lat_deg: float, lon_deg: float) -> None:
        """Place the polygon around home; raises ConfigError when home is not inside it."""
        if self._vertices is None:
            return
        name = f"the polygon of {Path(self.config.polygon).name}"
        polygon = Polygon(to_local(self._vertices, (lat_deg, lon_deg)), name)
        self._vertices = None
        self.shapes.append(polygon)
        if not polygon.contains((0.0, 0.0)):
            depth, _ = polygon.nearest((0.0, 0.0))
            self.refusal = (f"home ({lat_deg:.6f},{lon_deg:.6f}) is {-depth:.0f} m outside the polygon of "
                            f"{self.config.polygon}: fix the file or take off inside it")
            raise ConfigError(self.refusal, key="polygon")

    def on_telemetry(self, telemetry: Telemetry) -> None:
        """A telemetry listener: times the link quality below its floor; places the polygon at the first position
        that gives home."""
        t = telemetry
        quality = self._link_quality(t)
        if quality is None or quality >= self.config.link_floor_pct:
            self._link_low_since = None
        elif self._link_low_since is None:
            self._link_low_since = self.clock()
        if self._vertices is None or None in (t.lat_deg, t.lon_deg, t.north_m, t.east_m):
            return
        try:
            self.set_home(*origin_of(t.lat_deg, t.lon_deg, t.north_m, t.east_m))  # type: ignore[arg-type]
        except ConfigError as exc:
            self.events.emit("error", "autonomy", f"autonomy will be refused: {exc}")

    def engage(self) -> None:
        """Autonomy was switched on: the engagement's clock starts."""
        self._engaged_at, self._seen_at, self._seen_where = self.clock(), None, None

    def saw(self, target: bool, t: Telemetry) -> None:
        """A frame under autonomy: whether the processor reported its target on it (a box or a vector), ``t`` the
        telemetry then."""
        if target:
            self._seen_at = self.clock()
            if t.north_m is not None and t.east_m is not None:
                self._seen_where = (t.north_m, t.east_m)

    def breach(self, t: Telemetry, *, strict: bool = False) -> Breach | None:
        """The first limit the vehicle is past (height, engagement time, battery), or None; with ``strict`` also a
        height band without a height to check (a vector is refused then, but nothing is ended for it)."""
        c = self.config
        ground, source, _ = ground_height({name: getattr(t, name) for name in _GROUND_FIELDS}, t.t_mono_ns)
        for height, low, high, what in ((ground, c.min_height_m, c.max_height_m, f"above the ground ({source})"),
                                        (t.rel_alt_m, c.min_home_height_m, c.max_home_height_m, "above home")):
            if not (low or high):
                continue
            if height is None and strict:
                return Breach(c.height_action, f"no height {what}: the height band cannot be checked")
            if height is None:
                continue
            if low and height < low:
                return Breach(c.height_action, f"height {height:.1f} m {what} is below the floor {low:g} m")
            if high and height > high:
                return Breach(c.height_action, f"height {height:.1f} m {what} is above the ceiling {high:g} m")
        if c.max_autonomy_s and self._engaged_at is not None and self.clock() - self._engaged_at > c.max_autonomy_s:
            return Breach(c.time_action, f"autonomy ran its longest engagement, {c.max_autonomy_s:g} s")
        if c.lost_after_s and self._seen_at is not None and self.clock() - self._seen_at > c.lost_after_s:
            return self._lost()
        if self._link_low_since is not None and self.clock() - self._link_low_since >= c.link_floor_s and (
                quality := self._link_quality(t)) is not None and quality < c.link_floor_pct:
            return Breach(c.link_action, f"link quality {quality:.0f} % below the floor {c.link_floor_pct:g} % for "
                                         f"{c.link_floor_s:g} s")
        if c.battery_floor_pct and t.battery_pct is not None and t.battery_pct < c.battery_floor_pct:
            return Breach(c.battery_action, f"battery {t.battery_pct:.0f} % below the floor {c.battery_floor_pct:g} %")
        if c.battery_floor_v and t.battery_v is not None and t.battery_v < c.battery_floor_v:
            return Breach(c.battery_action, f"battery {t.battery_v:.2f} V below the floor {c.battery_floor_v:g} V")
        return None

    def _link_quality(self, t: Telemetry) -> float | None:
        """The link quality when the floor is on and it is known and fresh, else None."""
        if not self.config.link_floor_pct or t.link_quality_pct is None or t.link_quality_t_ns is None:
            return None
        return t.link_quality_pct if t.t_mono_ns - t.link_quality_t_ns <= LINK_FRESH_S * 1e9 else None

    def _lost(self) -> Breach:
        reason = f"target lost for {self.config.lost_after_s:g} s"
        if self.config.lost_action != "last_seen":
            return Breach(self.config.lost_action, reason)
        if self._seen_where is None:
            return Breach("hold", f"{reason} (no position when it was last seen: hold instead of last_seen)")
        north, east = self._seen_where
        return Breach("last_seen", f"{reason} (last seen at {north:.1f} m N, {east:.1f} m E)", self._seen_where)

    def confine(self, vector: tuple[float, float, float], t: Telemetry) -> Confined:
        """``vector`` (vx forward, vy right, duration) as the envelope lets it fly from where the vehicle is: the
        limits of :meth:`breach`, then :meth:`keep_inside`; cuts and refusals counted."""
        breach = self.breach(t, strict=True)
        if breach is not None:
            return self._refuse(f"refused: {breach.reason}", "envelope breach")
        confined = self.keep_inside(vector, t)
        if confined.vector is None:
            return self._refuse(confined.note, confined.key)
        if confined.note:
            self.cut += 1
        return confined

    def keep_inside(self, vector: tuple[float, float, float], t: Telemetry) -> Confined:
        """``vector`` as the radius and the polygon let it fly from where the vehicle is (uncounted)."""
        if not self.horizontal:
            return Confined(vector)
        if self._vertices is not None:
            return Confined(None, "refused: home is not known yet, so the polygon cannot be placed", "no home")
        if None in (t.north_m, t.east_m, t.yaw_deg):
            return Confined(None, "refused: no position or heading: the envelope cannot be checked", "no position")
        yaw = math.radians(t.yaw_deg)  # type: ignore[arg-type]
        forward, right = (math.cos(yaw), math.sin(yaw)), (-math.sin(yaw), math.cos(yaw))
        vx, vy, duration = vector
        v = (vx * forward[0] + vy * right[0], vx * forward[1] + vy * right[1])
        moving = None if t.vn_ms is None or t.ve_ms is None else (t.vn_ms, t.ve_ms)
        confined = self._confine_ned((t.north_m, t.east_m), v, duration, moving)  # type: ignore[arg-type]
        if confined.vector is None:
            return confined
        (vn, ve, duration) = confined.vector
        return Confined((vn * forward[0] + ve * forward[1], vn * right[0] + ve * right[1], duration), confined.note)

    def _confine_ned(self, p: Point, v: Point, duration: float, moving: Point | None) -> Confined:
        """:meth:`confine` in NED: ``v`` (north, east) for ``duration`` s from ``p``, the vehicle ``moving`` so.

        In the boundary band the vehicle's own outward speed is taken off the vector too (it brakes what it carries
        towards the boundary instead of coasting through), for at most ``response_lag_s``.
        """
        nearest = [(s.nearest(p), s) for s in self.shapes]
        (depth, outward), shape = min(nearest, key=lambda found: found[0][0])
        if depth < 0:
            inward = -(v[0] * outward[0] + v[1] * outward[1])
            if inward <= 1e-3:
                return Confined(None, f"refused: {-depth:.1f} m outside {shape.describe()}: only a vector back in "
                                      "flies", "outside")
            return Confined((-outward[0] * inward, -outward[1] * inward, duration),
                            f"{-depth:.1f} m outside {shape.describe()}: flown straight back in")
        notes = []
        for (depth, outward), s in nearest:
            if depth >= self.config.boundary_band_m:
                continue
            out = max(0.0, v[0] * outward[0] + v[1] * outward[1])
            drift = 0.0 if moving is None else moving[0] * outward[0] + moving[1] * outward[1]
            drift = drift if drift > MIN_DRIFT_MS else 0.0
            if out or drift:
                v = (v[0] - (out + drift) * outward[0], v[1] - (out + drift) * outward[1])
                notes.append(f"slid along {s.describe()}")
            if drift:
                duration = min(duration, self.config.response_lag_s)
        if math.hypot(*v) < 1e-3:
            return Confined(None, f"refused: at {shape.describe()}, the vector points out", "at the boundary")
        span = duration + self.config.response_lag_s
        d = (v[0] * span, v[1] * span)
        exits = [(s.exit_fraction(p, d), s) for s in self.shapes]
        crossings = [(f, s) for f, s in exits if f is not None]
        if crossings:
            fraction, crossed = min(crossings, key=lambda c: c[0])
            cut = fraction * span - self.config.response_lag_s
            if cut < MIN_VECTOR_S:
                return Confined(None, f"refused: at {crossed.describe()}, nothing of the vector stays inside",
                                "at the boundary")
            notes.append(f"cut to {cut:.2f} s at {crossed.describe()}")
            duration = cut
        return Confined((v[0], v[1], duration), "; ".join(notes))

    def _refuse(self, note: str, key: str) -> Confined:
        self.refused += 1
        return Confined(None, note, key)


async def carry_out(controller: FlightController, action: str) -> None:
    """Do a breach's action: ``hold`` (the gate's own stop holds), ``rtl`` or ``land``."""
    if action == "rtl":
        await controller.return_to_home()
    elif action == "land":
        await controller.land()


def configured_envelope(config: Config, events: EventLog, telemetry: TelemetryManager | None = None) -> Envelope:
    """The run's envelope, placed by ``telemetry``'s first position; ConfigError when its polygon cannot be used.
    With the built-in simulator home is configured (``[sim] home``), so a polygon without it stops the start here."""
    try:
        envelope = Envelope(config.envelope, events)
    except ValueError as exc:  # the file changed since the configuration was read
        raise ConfigError(f"envelope: polygon: {exc}", key="polygon") from None
    if config.fc.strip().lower() == "sim":
        home = config.sim.vehicle()["home"] or Home()
        envelope.set_home(home.lat_deg, home.lon_deg)
    if telemetry is not None:
        telemetry.add_listener(envelope.on_telemetry)
    events.emit("info", "autonomy", envelope.describe())
    return envelope
