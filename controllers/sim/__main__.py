"""``python -m controllers.sim``: run the simulated vehicle until SIGTERM / SIGINT."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
from collections.abc import Sequence

from controllers.autopilots import Autopilot
from controllers.sim.dialect import DIALECTS
from controllers.sim.geo import Home, parse_wind
from controllers.sim.guidance import OFFBOARD_LOSS_ACTIONS
from controllers.sim.physics import PhysicsConfig
from controllers.sim.vehicle import ServerConfig, SimVehicleServer

logger = logging.getLogger(__name__)


def _pair(text: str) -> tuple[float, float]:
    try:
        return parse_wind(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def _home(text: str) -> Home:
    try:
        return Home.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def build_parser(parser_class: type[argparse.ArgumentParser] = argparse.ArgumentParser) -> argparse.ArgumentParser:
    p = parser_class(
        prog="uav-tui sim",
        description="Simulated PX4-like quadrotor speaking MAVLink 2 on loopback. "
        "Connect MAVSDK with udpin://127.0.0.1:MAVLINK_PORT.",
    )
    p.add_argument("--mavlink-port", type=int, default=14540, help="ground side's listening UDP port")
    p.add_argument("--autopilot", choices=sorted(map(str, DIALECTS)), default="px4",
                   help="the autopilot it plays: px4, or ardupilot (ArduCopter modes; LOITER follows an RC throttle "
                   "held at its minimum, as in ArduCopter SITL)")
    p.add_argument("--truth-port", type=int, default=14600, help="ground-truth JSON channel (0 = any free)")
    p.add_argument("--home", type=_home, default=Home(), metavar="LAT,LON,ALT", help="home position")
    p.add_argument("--wind", type=_pair, default=(0.0, 0.0), metavar="N,E", help="steady wind, m/s")
    p.add_argument("--seed", type=int, default=0, help="random seed (noise)")
    p.add_argument("--noise", action="store_true", help="add sensor noise to the telemetry")
    p.add_argument(
        "--offboard-loss-timeout",
        type=float,
        default=1.0,
        metavar="S",
        help="offboard setpoints missing this long -> hold (PX4 COM_OF_LOSS_T)",
    )
    p.add_argument(
        "--offboard-loss-action",
        type=int,
        default=0,
        choices=sorted(OFFBOARD_LOSS_ACTIONS),
        help="what the offboard-loss failsafe does: 0 Position mode (sinks without --radio), 3 return, 4 land, "
        "5 hold (PX4 COM_OBL_RC_ACT)",
    )
    p.add_argument("--radio", action="store_true",
                   help="PX4: a radio is connected (SYS_STATUS shows the RC receiver; Position mode is held)")
    p.add_argument("--link-quality", type=float, default=None, metavar="PCT",
                   help="the RC receiver's signal RC_CHANNELS reports, 0-100 percent (default: no receiver, unknown)")
    p.add_argument("--climb-drift", type=float, default=0.0, metavar="M_S",
                   help="velocity setpoints drift upwards this fast (PX4 SIH: about 0.2); position holds correct it")
    p.add_argument(
        "--failsafe-land-after",
        type=float,
        default=10.0,
        metavar="S",
        help="after an offboard-loss hold, land if no client takes over within S",
    )
    p.add_argument("--speed-time-constant", type=float, default=0.4, metavar="S", help="velocity response")
    p.add_argument("--max-accel", type=float, default=3.0, metavar="M_S2", help="acceleration limit")
    p.add_argument("--takeoff-alt", type=float, default=2.5, metavar="M", help="MIS_TAKEOFF_ALT")
    p.add_argument("--rtl-alt", type=float, default=10.0, metavar="M", help="RTL_RETURN_ALT")
    p.add_argument("--battery", type=float, default=100.0, metavar="PCT", help="battery charge at boot, percent")
    p.add_argument("--battery-minutes", type=float, default=20.0, metavar="MIN",
                   help="minutes of flight from a full battery to an empty one")
    p.add_argument("--gps-delay", type=float, default=0.5, metavar="S", help="seconds until a 3D fix")
    p.add_argument("--rate", type=float, default=50.0, metavar="HZ", help="physics step rate")
    p.add_argument("--gps-clock-offset", type=float, default=0.0, metavar="S",
                   help="UTC time sent in SYSTEM_TIME minus this computer's clock (play a ground computer whose "
                   "clock is wrong)")
    p.add_argument("--plnd-enabled", action="store_true",
                   help="ArduPilot dialect: PLND_ENABLED=1, LAND flies over the LANDING_TARGET pad")
    p.add_argument("--parent-pid", type=int, default=None, metavar="PID", help="exit when PID stops being our parent")
    p.add_argument("--log-level", default="INFO", help="logging level on stderr")
    return p


def config_from_args(args: argparse.Namespace) -> ServerConfig:
    physics = PhysicsConfig(
        speed_time_constant_s=args.speed_time_constant,
        max_accel_ms2=args.max_accel,
        noise=args.noise,
        takeoff_alt_m=args.takeoff_alt,
        rtl_alt_m=args.rtl_alt,
        gps_fix_after_s=args.gps_delay,
        climb_drift_ms=args.climb_drift,
        battery_start=max(0.0, min(1.0, args.battery / 100.0)),
        battery_flight_minutes=max(0.1, args.battery_minutes),
    )
    return ServerConfig(
        mavlink_port=args.mavlink_port,
        autopilot=Autopilot(args.autopilot),
        truth_port=args.truth_port,
        home=args.home,
        wind=args.wind,
        seed=args.seed,
        rate_hz=args.rate,
        offboard_loss_timeout_s=args.offboard_loss_timeout,
        offboard_loss_action=args.offboard_loss_action,
        failsafe_land_after_s=args.failsafe_land_after,
        radio=args.radio,
        link_quality_pct=args.link_quality,
        parent_pid=args.parent_pid,
        gps_clock_offset_s=args.gps_clock_offset,
        precland_enabled=args.plnd_enabled,
        physics=physics,
    )


def main(argv: Sequence[str] | None = None,
         parser_class: type[argparse.ArgumentParser] = argparse.ArgumentParser) -> int:
    """Run the simulator; prints one ``ready`` line on stdout, returns 0 after SIGTERM/SIGINT.

    ``parser_class``: ``uav-tui sim`` passes the platform's, whose errors suggest the flag meant.
    """
    args = build_parser(parser_class).parse_args(argv)
    sys.setswitchinterval(0.001)  # the MAVLink reader gets the interpreter promptly when a command arrives
    logging.basicConfig(
        level=args.log_level.upper(),
        stream=sys.stderr,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        server = SimVehicleServer(config_from_args(args))
    except OSError as exc:
        print(f"uav-tui sim: error: cannot start the simulated vehicle: {exc}", file=sys.stderr)
        return 2
    previous = {sig: signal.signal(sig, lambda *_: server.stop()) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        print(f"{server.describe()}", flush=True)
        server.run()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    logger.info("sim vehicle stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
