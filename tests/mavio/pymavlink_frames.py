#!/usr/bin/env python3
"""The reference reading of a MAVLink log, for tests/mavio.rs: pymavlink's parser over a
.tlog (mavutil, timestamps kept), a raw stream (mavutil with notimestamps) or a pcap/pcapng
capture (the UDP/TCP payloads of each flow fed to pymavlink's parser, in capture order).

Prints one line per frame pymavlink accepts, `time_us sysid compid msgid` (`-` for no
time), `unknown MSGID` for a frame of an id its dialect lacks, `garbage N` for a run of N bytes it skipped, then one line `bad N` with the number of
frames whose checksum failed. Usage: pymavlink_frames.py FORMAT FILE, FORMAT one of tlog, raw, pcapng.
(The pcapng reader handles what the captures hold: Ethernet, IPv4, UDP or TCP.)
"""
import os
import struct
import sys

os.environ.setdefault("MAVLINK20", "1")
os.environ.setdefault("MAVLINK_DIALECT", "ardupilotmega")

from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import ardupilotmega as mav  # noqa: E402


def emit(m, time_us):
    if m.get_type() == "BAD_DATA":
        # Count checksum failures; a run of bytes before a start byte ("Bad prefix") is
        # garbage, which mochi counts in bytes, not runs.
        if "CRC" in m.reason:
            return 1
        print("garbage", len(m.get_msgbuf()))
        return 0
    if m.get_type().startswith("UNKNOWN_"):
        # A message id pymavlink's dialect does not have (its header is not kept).
        print("unknown", m.get_type()[len("UNKNOWN_") :])
        return 0
    t = "-" if time_us is None else str(time_us)
    print(t, m.get_srcSystem(), m.get_srcComponent(), m.get_msgId())
    return 0


def read_raw(path):
    # mavutil would read a `.bin` as an ArduPilot DataFlash log: feed the parser directly.
    p = mav.MAVLink(None)
    p.robust_parsing = True
    data = open(path, "rb").read()
    bad = 0
    for m in p.parse_buffer(data) or []:
        bad += emit(m, None)
    return bad


def read_log(path, fmt):
    conn = mavutil.mavlink_connection(path, dialect="ardupilotmega", robust_parsing=True)
    bad = 0
    while True:
        m = conn.recv_msg()
        if m is None:
            break
        t = None
        t = int(round(m._timestamp * 1e6)) if fmt == "tlog" else None
        bad += emit(m, t)
    return bad


def packets(data):
    """(time_us, payload-bearing packet bytes, link type) of a pcapng file (little-endian)."""
    at = 0
    ifaces = []
    while at + 8 <= len(data):
        kind, length = struct.unpack_from("<II", data, at)
        body = data[at + 8 : at + length - 4]
        if kind == 1:
            link = struct.unpack_from("<H", body, 0)[0]
            unit = 10**6
            o = 8
            while o + 4 <= len(body):
                code, olen = struct.unpack_from("<HH", body, o)
                if code == 0:
                    break
                if code == 9:
                    r = body[o + 4]
                    unit = 10 ** (r & 0x7F) if r & 0x80 == 0 else 2 ** (r & 0x7F)
                o += 4 + (olen + 3) // 4 * 4
            ifaces.append((link, unit))
        elif kind == 6:
            iface, hi, lo, cap = struct.unpack_from("<IIII", body, 0)
            link, unit = ifaces[iface]
            yield ((hi << 32) | lo) * 10**6 // unit, body[20 : 20 + cap], link
        at += length


def flow_payload(pkt, link):
    if link != 1:
        return None
    ethertype = struct.unpack_from(">H", pkt, 12)[0]
    if ethertype != 0x0800:
        return None
    ip = pkt[14:]
    ihl = (ip[0] & 15) * 4
    total = struct.unpack_from(">H", ip, 2)[0]
    proto = ip[9]
    l4 = ip[ihl:total]
    key = (proto, ip[12:16], ip[16:20], l4[0:4])
    if proto == 17:
        return key, l4[8:]
    if proto == 6:
        return key, l4[(l4[12] >> 4) * 4 :]
    return None


def read_pcapng(path):
    data = open(path, "rb").read()
    parsers = {}
    bad = 0
    for t, pkt, link in packets(data):
        fp = flow_payload(pkt, link)
        if fp is None:
            continue
        key, payload = fp
        p = parsers.setdefault(key, mav.MAVLink(None))
        p.robust_parsing = True
        for m in p.parse_buffer(payload) or []:
            bad += emit(m, t)
    return bad


def main():
    fmt, path = sys.argv[1], sys.argv[2]
    if fmt in ("pcapng", "pcap"):
        bad = read_pcapng(path)
    elif fmt == "raw":
        bad = read_raw(path)
    else:
        bad = read_log(path, fmt)
    print("bad", bad)


if __name__ == "__main__":
    main()
