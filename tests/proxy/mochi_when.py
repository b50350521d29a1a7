"""A MAVProxy module for tests/mavproxy.rs: runs MAVProxy's own commands when a condition
holds, so that a headless MAVProxy (`--daemon --non-interactive`, no terminal) is driven
through a sequence by `--cmd` alone. Loaded with `--load-module mochi_when` (from
PYTHONPATH=tests/proxy).

Commands:
  when-param NAME COMMAND...   run COMMAND once MAVProxy's parameter cache holds NAME
  when-value NAME VALUE COMMAND...
                               run COMMAND once the cache holds NAME with VALUE (within 1e-4)
  when-target COMMAND...       run COMMAND once MAVProxy has heard a vehicle's HEARTBEAT

Each command run is announced on stdout as a JSON line `{"mavproxy": "ran", "command": ...}`
(the test reads MAVProxy's output), and each MISSION_ACK and PARAM_VALUE MAVProxy receives
as `{"mavproxy": "MISSION_ACK", ...}` / `{"mavproxy": "PARAM_VALUE", ...}`.
"""
import json

from MAVProxy.modules.lib import mp_module


def say(**kw):
    print(json.dumps(kw), flush=True)


class WhenModule(mp_module.MPModule):
    def __init__(self, mpstate):
        super(WhenModule, self).__init__(mpstate, "mochi_when", "run commands when a condition holds")
        self.pending = []  # (condition, argument, command)
        self.heard_vehicle = False
        self.add_command("when-param", self.cmd_when_param, "when-param NAME COMMAND")
        self.add_command("when-target", self.cmd_when_target, "when-target COMMAND")
        self.add_command("when-value", self.cmd_when_value, "when-value NAME VALUE COMMAND")

    def cmd_when_param(self, args):
        if len(args) < 2:
            print("usage: when-param NAME COMMAND")
            return
        self.pending.append(("param", args[0].upper(), " ".join(args[1:])))

    def cmd_when_value(self, args):
        if len(args) < 3:
            print("usage: when-value NAME VALUE COMMAND")
            return
        self.pending.append(("value", (args[0].upper(), float(args[1])), " ".join(args[2:])))

    def cmd_when_target(self, args):
        if len(args) < 1:
            print("usage: when-target COMMAND")
            return
        self.pending.append(("target", None, " ".join(args)))

    def holds(self, what, arg):
        if what == "param":
            return arg in self.mav_param
        if what == "value":
            name, value = arg
            return name in self.mav_param and abs(float(self.mav_param[name]) - value) < 1e-4
        return self.heard_vehicle

    def mavlink_packet(self, m):
        t = m.get_type()
        if t == "HEARTBEAT" and m.get_srcSystem() == self.target_system and m.type != 6:
            self.heard_vehicle = True
        elif t == "MISSION_ACK":
            say(mavproxy="MISSION_ACK", type=m.type, mission_type=m.mission_type)
        elif t == "PARAM_VALUE":
            say(mavproxy="PARAM_VALUE", id=m.param_id, value=m.param_value, index=m.param_index)

    def idle_task(self):
        due = [p for p in self.pending if self.holds(p[0], p[1])]
        if not due:
            return
        self.pending = [p for p in self.pending if p not in due]
        for _, _, command in due:
            say(mavproxy="ran", command=command)
            self.mpstate.functions.process_stdin(command)


def init(mpstate):
    return WhenModule(mpstate)
