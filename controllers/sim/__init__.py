"""Built-in simulated vehicle: a PX4-like quadrotor speaking MAVLink 2 on loopback (or, with
``--autopilot ardupilot``, an ArduCopter-like one: see :mod:`controllers.sim.dialect`).

Run it with ``python -m controllers.sim`` (or ``uav-tui sim``); start it from code with
:class:`controllers.sim.launcher.SimVehicle`; connect MAVSDK with ``udpin://127.0.0.1:MAVLINK_PORT``
(loopback only: nothing on the network reaches either side).

Ground-truth channel: UDP JSON datagrams on 127.0.0.1:TRUTH_PORT, one JSON object per datagram.

Requests (the simulator replies to the sender with one JSON object; an "id" in the request is echoed):
    {"cmd": "subscribe"}      -> {"ok": true}; then truth datagrams at 50 Hz to that address
    {"cmd": "unsubscribe"}    -> {"ok": true}; the stream to that address stops
    {"cmd": "state"}          -> {"ok": true, "state": TRUTH}
    {"cmd": "set_wind", "n": N, "e": E}                       -> {"ok": true}
    {"cmd": "teleport", "n": N, "e": E, "d": D, "yaw": DEG}   -> {"ok": true, "state": TRUTH}
    {"cmd": "rc_mode", "mode": M}  -> {"ok": true, "state": TRUTH}; M in POSCTL, HOLD, RTL, LAND, LOITER, as an RC pilot
    {"cmd": "rc_throttle", "pwm": P}  -> {"ok": true, "state": TRUTH}; the RC throttle (ardupilot dialect), 800..2200
    {"cmd": "link_quality", "pct": P}  -> {"ok": true}; the RC signal in RC_CHANNELS, percent; null: no receiver
    {"cmd": "stream", "msg_id": ID, "interval_us": US} -> {"ok": true}; a stream (a sensor) stops (-1), or comes back
                                         (0: its default rate), as SET_MESSAGE_INTERVAL
    {"cmd": "setpoints", "since_mono_ns": T}  -> {"ok": true, "records": [REC, ...], "more": bool}
    {"cmd": "landing_targets", "since_mono_ns": T}  -> {"ok": true, "records": [LT, ...], "more": bool}
    anything else             -> {"ok": false, "error": "..."}

TRUTH (streamed datagrams carry no "id" and no "ok"):
    t_mono_ns, t_wall_ns      time.monotonic_ns() and time.time_ns() in the simulator
    time_boot_ms              the simulator's MAVLink clock (time_boot_ms in ATTITUDE, GLOBAL_POSITION_INT...)
    n, e, d, vn, ve, vd       local NED position (m, origin at home, d = 0 on the ground) and velocity (m/s)
    roll, pitch, yaw          degrees, yaw from north clockwise
    armed, in_air             booleans
    mode                      MANUAL, POSCTL, HOLD, TAKEOFF, LAND, RTL, OFFBOARD or ORBIT; PRECLAND (px4);
                              GUIDED, LOITER (ardupilot)
    lat, lon, alt             degrees, degrees, metres AMSL
    battery, wind_n, wind_e   remaining fraction 0..1, steady wind m/s
    rc_throttle               the RC throttle input in the ardupilot dialect (default 1000, SITL's), else null
    link_quality              the RC signal RC_CHANNELS reports, percent (``--link-quality``), null: unknown

REC (one per SET_POSITION_TARGET_LOCAL_NED received, oldest first, at most 400 per reply):
    t_mono_ns                 time.monotonic_ns() when the simulator read the datagram
    vx, vy, vz, frame         the velocity fields and MAV_FRAME as sent

LT (one per LANDING_TARGET received, oldest first, at most 400 per reply):
    t_mono_ns                 time.monotonic_ns() when the simulator read the datagram
    time_usec, frame, position_valid   as sent (time_usec: the capture on the simulator's boot clock, time_boot_ms)
    used                      the dialect took a pad position from it (else it was dropped, as the autopilot would)
"""
