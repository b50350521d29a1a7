#!/usr/bin/env python3
"""Real MAVLink peers for tests/proxy.rs: a ground station and a vehicle written with
pymavlink, and the same roles played by MAVSDK (its client plugins and its server plugins).

Usage: peers.py ROLE URL [ARGS...]. Each role prints one JSON object per line on stdout
(events as they happen, then a final `{"done": ...}` for the ground-station roles) and exits
0; a vehicle runs until killed or until `--seconds` pass.
"""
import json
import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")


def say(**kw):
    print(json.dumps(kw), flush=True)


# ---------------------------------------------------------------- pymavlink vehicle
def pymavlink_vehicle(url, behaviour, seconds, heartbeat=False):
    """A vehicle at system 1, component 1: the mission, parameter and command protocols
    as an autopilot serves them. `behaviour` is `honest` or `early-ack` (acknowledges an
    upload after the first few items: the seed's stale buffer). With `heartbeat` it also
    sends its HEARTBEAT (an ArduPilot quadrotor, disarmed) once a second, as a real
    autopilot does (MAVProxy waits for one before it talks to the vehicle)."""
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(url, source_system=1, source_component=1, dialect="common")
    params = {"MC_PITCH_P": 6.5, "MC_PITCHRATE_FF": 0.0, "MC_PITCHRATE_MAX": 220.0}
    end = time.time() + seconds
    upload = None  # (gcs sys, gcs comp, count, next seq, items, last request time, retries)
    next_heartbeat = 0.0
    while time.time() < end:
        if heartbeat and time.time() >= next_heartbeat:
            # MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_ARDUPILOTMEGA, custom mode enabled,
            # MAV_STATE_STANDBY. Before the first datagram a udpin end has nobody to send to.
            try:
                m.mav.heartbeat_send(2, 3, 1, 0, 3)
            except OSError:
                pass
            next_heartbeat = time.time() + 1.0
        msg = m.recv_match(blocking=True, timeout=0.2)
        if upload is not None and msg is None:
            gs, gc, count, i, items, _, retries = upload
            if retries >= 5:
                say(event="upload-abandoned", seq=i)
                upload = None
            else:
                m.mav.mission_request_int_send(gs, gc, i, 0)
                upload = (gs, gc, count, i, items, time.time(), retries + 1)
            continue
        if msg is None:
            continue
        t = msg.get_type()
        src = (msg.get_srcSystem(), msg.get_srcComponent())
        if t == "MISSION_COUNT":
            say(event="count", count=msg.count, src=src)
            if msg.count == 0:
                m.mav.mission_ack_send(src[0], src[1], 0, 0)
                m.mav.mission_current_send(0)
                continue
            upload = (src[0], src[1], msg.count, 0, [], time.time(), 0)
            m.mav.mission_request_int_send(src[0], src[1], 0, 0)
        elif t == "MISSION_ITEM_INT" and upload is not None:
            gs, gc, count, i, items, _, _ = upload
            if msg.seq != i:
                continue
            items.append([msg.seq, msg.frame, msg.command, msg.current, msg.autocontinue,
                          msg.param1, msg.param2, msg.param3, msg.param4, msg.x, msg.y, msg.z])
            i += 1
            early = behaviour == "early-ack" and i == 3
            if i == count or early:
                m.mav.mission_ack_send(gs, gc, 0, 0)
                m.mav.mission_current_send(0)
                say(event="mission", items=items, acked_early=early)
                upload = None
            else:
                upload = (gs, gc, count, i, items, time.time(), 0)
                m.mav.mission_request_int_send(gs, gc, i, 0)
        elif t == "PARAM_REQUEST_READ":
            pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            if pid == "" and 0 <= msg.param_index < len(params):
                pid = list(params)[msg.param_index]
            if pid in params:
                m.mav.param_value_send(pid.encode(), params[pid], 9, len(params),
                                       list(params).index(pid))
        elif t == "PARAM_REQUEST_LIST":
            # The whole list, one PARAM_VALUE per parameter (mavlink.io's parameter service).
            say(event="param_list")
            for i, (pid, value) in enumerate(params.items()):
                m.mav.param_value_send(pid.encode(), value, 9, len(params), i)
        elif t == "PARAM_SET":
            pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            say(event="param_set", id=pid, value=msg.param_value)
            params[pid] = msg.param_value
            m.mav.param_value_send(pid.encode(), msg.param_value, 9, len(params),
                                   list(params).index(pid) if pid in params else 0)
        elif t == "COMMAND_LONG":
            say(event="command", command=msg.command, param1=msg.param1)
            m.mav.command_ack_send(msg.command, 0, 0, 0, src[0], src[1])
            if msg.command == 400:
                armed = 128 if msg.param1 == 1 else 0
                m.mav.heartbeat_send(2, 3, 1 | armed, 0, 4)
    return 0


# ---------------------------------------------------------------- pymavlink ground station
def gcs_connection(url):
    from pymavlink import mavutil

    return mavutil.mavlink_connection(url, source_system=255, source_component=190, dialect="common")


def mission_items(path):
    """The items of a QGC WPL mission file, as MISSION_ITEM_INT fields."""
    items = []
    with open(path) as f:
        lines = f.read().splitlines()
    if not lines or not lines[0].startswith("QGC WPL"):
        raise SystemExit(f"{path}: not a QGC WPL file")
    for line in lines[1:]:
        c = line.split("\t")
        if len(c) < 12:
            continue
        seq, current, frame, command = int(c[0]), int(c[1]), int(c[2]), int(c[3])
        p = [float(x) for x in c[4:11]]
        autocontinue = int(float(c[11]))
        items.append([seq, frame, command, current, autocontinue, p[0], p[1], p[2], p[3],
                      int(round(p[4] * 1e7)), int(round(p[5] * 1e7)), p[6]])
    return items


def pymavlink_mission(url, path, timeout):
    m = gcs_connection(url)
    items = mission_items(path)
    m.mav.mission_count_send(1, 1, len(items), 0)
    end = time.time() + timeout
    last = time.time()
    while time.time() < end:
        msg = m.recv_match(type=["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"],
                           blocking=True, timeout=0.5)
        if msg is None:
            if time.time() - last > 2:
                # Nothing asked for a while: the count was lost or dropped; send it again.
                m.mav.mission_count_send(1, 1, len(items), 0)
                last = time.time()
            continue
        last = time.time()
        if msg.get_type() == "MISSION_ACK":
            say(done="mission", ack=msg.type, items=items)
            return 0
        s = msg.seq
        if 0 <= s < len(items):
            it = items[s]
            m.mav.mission_item_int_send(1, 1, it[0], it[1], it[2], it[3], it[4], it[5], it[6],
                                        it[7], it[8], it[9], it[10], it[11], 0)
    say(done="mission", ack=None, items=items)
    return 0


def pymavlink_param(url, value, timeout):
    m = gcs_connection(url)
    got = {}
    for pid in ["MC_PITCH_P", "MC_PITCHRATE_FF"]:
        end = time.time() + timeout
        while pid not in got and time.time() < end:
            m.mav.param_request_read_send(1, 1, pid.encode(), -1)
            msg = m.recv_match(type="PARAM_VALUE", blocking=True, timeout=1)
            if msg is not None and msg.param_id == pid:
                got[pid] = msg.param_value
    m.mav.param_set_send(1, 1, b"MC_PITCHRATE_MAX", value, 9)
    echo = None
    end = time.time() + min(timeout, 3)
    while echo is None and time.time() < end:
        msg = m.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.5)
        if msg is not None and msg.param_id == "MC_PITCHRATE_MAX":
            echo = msg.param_value
    say(done="param", read=got, echo=echo)
    return 0


def pymavlink_arm(url, timeout):
    m = gcs_connection(url)
    m.mav.command_long_send(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
    ack = None
    armed = None
    end = time.time() + timeout
    while (ack is None or armed is None) and time.time() < end:
        msg = m.recv_match(type=["COMMAND_ACK", "HEARTBEAT"], blocking=True, timeout=0.5)
        if msg is None:
            continue
        if msg.get_type() == "COMMAND_ACK":
            ack = [msg.command, msg.result]
        elif msg.get_srcSystem() == 1:
            armed = bool(msg.base_mode & 128)
    say(done="arm", ack=ack, armed=armed)
    return 0


# ---------------------------------------------------------------- MAVSDK
def mavsdk_url(url):
    # pymavlink's `udpin:HOST:PORT` is MAVSDK's `udpin://HOST:PORT`.
    scheme, rest = url.split(":", 1)
    return f"{scheme}://{rest}"


def mavsdk_vehicle(url, seconds):
    """MAVSDK as an autopilot: mission_raw_server, param_server and action_server."""
    from mavsdk import ComponentType, Configuration, Mavsdk
    from mavsdk.plugins.action_server import ActionServer
    from mavsdk.plugins.mission_raw_server import MissionRawServer
    from mavsdk.plugins.param_server import ParamServer

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.AUTOPILOT))
    say(event="connection", result=str(sdk.add_any_connection(mavsdk_url(url))))
    sc = sdk.server_component()
    missions = MissionRawServer(sc)
    params = ParamServer(sc)
    actions = ActionServer(sc)

    def on_mission(result, plan, *_):
        items = [[i.seq, i.frame, i.command, i.current, i.autocontinue, i.param1, i.param2,
                  i.param3, i.param4, i.x, i.y, i.z] for i in (plan.mission_items if plan else [])]
        say(event="mission", result=str(result), items=items)

    missions.subscribe_incoming_mission(on_mission)
    for name, value in [("MC_PITCH_P", 6.5), ("MC_PITCHRATE_FF", 0.0), ("MC_PITCHRATE_MAX", 220.0)]:
        say(event="param", name=name, result=str(params.provide_param_float(name, value)))
    actions.set_allowable_flight_modes(_flight_modes(actions))
    actions.set_allow_takeoff(True)
    actions.set_armable(True, True)
    actions.subscribe_arm_disarm(lambda result, arm, *_: say(event="arm", result=str(result), arm=_arm(arm)))
    end = time.time() + seconds
    while time.time() < end:
        time.sleep(0.1)
    return 0


def _flight_modes(actions):
    from mavsdk.plugins.action_server import AllowableFlightModes

    return AllowableFlightModes(can_auto_mode=True, can_guided_mode=True, can_stabilize_mode=True)


def _arm(arm):
    return getattr(arm, "arm", arm)


def mavsdk_gcs(url, what, arg, timeout):
    from mavsdk import ComponentType, Configuration, Mavsdk

    sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    sdk.add_any_connection(mavsdk_url(url))
    system = sdk.first_autopilot(timeout)
    if system is None:
        say(done=what, error="no autopilot discovered")
        return 0
    try:
        if what == "mission":
            from mavsdk.plugins.mission_raw import MissionItem, MissionRaw

            items = mission_items(arg)
            # MAVSDK wants exactly one current item (QGroundControl marks the first).
            for i in items:
                i[3] = 1 if i[0] == 0 else 0
            plugin = MissionRaw(system)
            plan = [MissionItem(seq=i[0], frame=i[1], command=i[2], current=i[3], autocontinue=i[4],
                                param1=i[5], param2=i[6], param3=i[7], param4=i[8], x=i[9], y=i[10],
                                z=i[11], mission_type=0) for i in items]
            plugin.upload_mission(plan)
            say(done="mission", result="ok", items=items)
        elif what == "param":
            from mavsdk.plugins.param import Param

            plugin = Param(system)
            # param-set.chor: read the two gains, then set the rate within their bound.
            p = plugin.get_param_float("MC_PITCH_P")
            ff = plugin.get_param_float("MC_PITCHRATE_FF")
            plugin.set_param_float("MC_PITCHRATE_MAX", float(arg))
            say(done="param", read={"MC_PITCH_P": p, "MC_PITCHRATE_FF": ff}, after=float(arg))
        elif what == "arm":
            from mavsdk.plugins.action import Action

            Action(system).arm()
            say(done="arm", result="ok")
    except Exception as e:  # noqa: BLE001 -- the test reads the error
        say(done=what, error=f"{type(e).__name__}: {e}")
    return 0


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    role, url, rest = argv[1], argv[2], argv[3:]
    if role == "vehicle":
        return pymavlink_vehicle(url, rest[0] if rest else "honest", float(rest[1]) if len(rest) > 1 else 30,
                                 len(rest) > 2 and rest[2] == "heartbeat")
    if role == "gcs-mission":
        return pymavlink_mission(url, rest[0], float(rest[1]) if len(rest) > 1 else 30)
    if role == "gcs-param":
        return pymavlink_param(url, float(rest[0]), 10)
    if role == "gcs-arm":
        return pymavlink_arm(url, 10)
    if role == "mavsdk-vehicle":
        return mavsdk_vehicle(url, float(rest[0]) if rest else 30)
    if role == "mavsdk-gcs":
        return mavsdk_gcs(url, rest[0], rest[1] if len(rest) > 1 else None, 20)
    print(f"unknown role {role}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
