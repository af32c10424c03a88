#!/usr/bin/env python3
"""Real-peer check of sim-plant's emulated PX4 MAVLink endpoint, with pymavlink.

Run by sim-plant/tests/mavlink_link_pymavlink.rs, which steps a fake vehicle behind the
endpoint. The script binds 127.0.0.1:LOCAL (where the endpoint streams) and talks to
127.0.0.1:REMOTE (the endpoint). It exits 0 after printing a JSON summary line, or non-zero
with a message naming the first failed check.

The fake vehicle it expects: custom_mode 3<<16 (POSCTL) until DO_SET_MODE, rotors at
770..773 rad/s, hovering at z = -1.5 m with specific force (0, 0, -9.81).
"""

import argparse
import json
import math
import os
import random
import socket
import struct
import sys
import time

os.environ["MAVLINK20"] = "1"
try:
    from pymavlink.dialects.v10 import common as mav1
    from pymavlink.dialects.v20 import common as mav2
    from pymavlink.generator.mavcrc import x25crc
except ImportError as err:  # the Rust test turns this into a clear failure
    print(f"FAIL: pymavlink is not importable: {err}", file=sys.stderr)
    sys.exit(3)

OUR_SYS, OUR_COMP = 42, 191  # companion's ids (MAV_COMP_ID_ONBOARD_COMPUTER)
ESC_STATUS_ID, ESC_STATUS_CRC_EXTRA, ESC_STATUS_LEN = 291, 10, 57  # absent from pymavlink's common
DEFAULT_RATES = {
    "ATTITUDE_QUATERNION": 50.0,
    "HIGHRES_IMU": 50.0,
    "LOCAL_POSITION_NED": 30.0,
    "ODOMETRY": 30.0,
    "ESC_STATUS": 10.0,
}
EXPECTED_RPM = [round(w * 60.0 / (2.0 * math.pi)) for w in (770.0, 771.0, 772.0, 773.0)]


class Fail(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Fail(what)


class EscStatus:
    """ESC_STATUS decoded by hand (CRC checked with its CRC_EXTRA)."""

    def __init__(self, payload):
        p = bytes(payload) + bytes(ESC_STATUS_LEN - len(payload))
        fields = struct.unpack("<Q4i4f4fB", p)
        self.time_usec = fields[0]
        self.rpm = list(fields[1:5])
        self.index = fields[13]

    def get_type(self):
        return "ESC_STATUS"


class Peer:
    def __init__(self, local, remote, sysid, compid):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", local))
        self.sock.settimeout(0.05)
        self.remote = ("127.0.0.1", remote)
        self.sysid, self.compid = sysid, compid
        self.tx = mav2.MAVLink(None, srcSystem=OUR_SYS, srcComponent=OUR_COMP)
        self.tx1 = mav1.MAVLink(None, srcSystem=OUR_SYS, srcComponent=OUR_COMP)
        self.rx = mav2.MAVLink(None)
        self.rx.robust_parsing = True
        self.last_seq = None
        self.seq_gaps = 0
        self.frames = 0

    # -- sending -----------------------------------------------------------------------
    def send(self, msg):
        self.sock.sendto(msg.pack(self.tx), self.remote)

    def send_v1(self, msg):
        self.sock.sendto(msg.pack(self.tx1), self.remote)

    def send_raw(self, data):
        self.sock.sendto(bytes(data), self.remote)

    def command(self, cmd, params, target=None):
        ts, tc = target if target else (self.sysid, self.compid)
        p = list(params) + [0.0] * (7 - len(params))
        self.send(mav2.MAVLink_command_long_message(ts, tc, cmd, 0, *p))

    # -- receiving ---------------------------------------------------------------------
    def _frames(self, data):
        """Messages of one datagram; the endpoint sends one MAVLink 2 frame per datagram."""
        if len(data) >= 12 and data[0] == 0xFD:
            seq = data[4]
            if self.last_seq is not None and seq != (self.last_seq + 1) % 256:
                self.seq_gaps += 1
            self.last_seq = seq
            self.frames += 1
            check(data[5] == self.sysid and data[6] == self.compid,
                  f"frame from {data[5]}/{data[6]}, expected {self.sysid}/{self.compid}")
            msgid = data[7] | (data[8] << 8) | (data[9] << 16)
            if msgid == ESC_STATUS_ID:
                n = data[1]
                crc = x25crc(bytes(data[1:10 + n]))
                crc.accumulate(bytes([ESC_STATUS_CRC_EXTRA]))
                got = struct.unpack("<H", bytes(data[10 + n:12 + n]))[0]
                check(crc.crc == got, "ESC_STATUS checksum mismatch")
                return [EscStatus(data[10:10 + n])]
        msgs = self.rx.parse_buffer(data) or []
        return [m for m in msgs if m.get_type() != "BAD_DATA"]

    def recv_for(self, seconds):
        """All messages received during `seconds`."""
        out = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                data, _ = self.sock.recvfrom(4096)
            except socket.timeout:
                continue
            out.extend(self._frames(data))
        return out

    def wait_for(self, predicate, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                data, _ = self.sock.recvfrom(4096)
            except socket.timeout:
                continue
            for m in self._frames(data):
                if predicate(m):
                    return m
        raise Fail(f"timed out after {timeout} s waiting for {what}")

    def ack(self, cmd, timeout=2.0):
        return self.wait_for(
            lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd, timeout,
            f"COMMAND_ACK for command {cmd}")

    def rate(self, name, seconds):
        msgs = self.recv_for(seconds)
        return sum(1 for m in msgs if m.get_type() == name) / seconds


def with_extension(frame, base_len, extension, crc_extra):
    """A MAVLink 2 frame with extension field bytes added to its payload (trailing zeros
    trimmed, checksum recomputed)."""
    n = frame[1]
    payload = bytes(frame[10:10 + n]) + bytes(base_len - n) + extension
    payload = payload.rstrip(b"\x00") or b"\x00"
    header = bytes([len(payload)]) + bytes(frame[2:10])
    crc = x25crc(header + payload)
    crc.accumulate(bytes([crc_extra]))
    return b"\xfd" + header + payload + struct.pack("<H", crc.crc)


def within(value, expected, tol=0.2):
    return abs(value - expected) <= tol * expected


def run(peer, args):
    summary = {}
    # 1. Heartbeat identity.
    hb = peer.wait_for(lambda m: m.get_type() == "HEARTBEAT", 5.0, "HEARTBEAT")
    check(hb.type == mav2.MAV_TYPE_QUADROTOR, f"HEARTBEAT type {hb.type}")
    check(hb.autopilot == mav2.MAV_AUTOPILOT_PX4, f"HEARTBEAT autopilot {hb.autopilot}")
    check(hb.custom_mode == args.expect_custom_mode,
          f"HEARTBEAT custom_mode {hb.custom_mode}, expected {args.expect_custom_mode}")
    check(hb.get_srcSystem() == peer.sysid and hb.get_srcComponent() == peer.compid,
          "HEARTBEAT sender ids")
    check(hb.base_mode & mav2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, "custom mode flag not set")
    peer.send(mav2.MAVLink_heartbeat_message(mav2.MAV_TYPE_ONBOARD_CONTROLLER,
                                             mav2.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3))

    # 2. Default rates over 2 s, plus field checks.
    window = 2.0
    msgs = peer.recv_for(window)
    counts = {}
    last = {}
    for m in msgs:
        counts[m.get_type()] = counts.get(m.get_type(), 0) + 1
        last[m.get_type()] = m
    rates = {name: counts.get(name, 0) / window for name in DEFAULT_RATES}
    summary["default_rates_hz"] = rates
    summary["heartbeats_in_2s"] = counts.get("HEARTBEAT", 0)
    for name, expected in DEFAULT_RATES.items():
        check(within(rates[name], expected), f"{name} at {rates[name]:.1f} Hz, expected {expected}")
    check(1 <= counts.get("HEARTBEAT", 0) <= 3, f"{counts.get('HEARTBEAT', 0)} heartbeats in 2 s")
    odo = last["ODOMETRY"]
    check(odo.frame_id == mav2.MAV_FRAME_LOCAL_NED, f"ODOMETRY frame_id {odo.frame_id}")
    check(odo.child_frame_id == mav2.MAV_FRAME_LOCAL_NED, f"ODOMETRY child_frame_id {odo.child_frame_id}")
    check(odo.estimator_type == mav2.MAV_ESTIMATOR_TYPE_AUTOPILOT, "ODOMETRY estimator_type")
    check(math.isnan(odo.pose_covariance[1]) and math.isnan(odo.velocity_covariance[1]),
          "ODOMETRY off-diagonal covariance must be NaN")
    check(abs(math.sqrt(sum(q * q for q in odo.q)) - 1.0) < 1e-5, "ODOMETRY q not unit")
    check(abs(odo.z + 1.5) < 1e-3, f"ODOMETRY z {odo.z}")
    lpos = last["LOCAL_POSITION_NED"]
    check(abs(lpos.z + 1.5) < 1e-3, f"LOCAL_POSITION_NED z {lpos.z}")
    att = last["ATTITUDE_QUATERNION"]
    check(abs(math.sqrt(att.q1**2 + att.q2**2 + att.q3**2 + att.q4**2) - 1.0) < 1e-5, "q not unit")
    imu = last["HIGHRES_IMU"]
    check(abs(imu.zacc + 9.81) < 1e-3 and imu.fields_updated == 0x3F, "HIGHRES_IMU accel/flags")
    esc = last["ESC_STATUS"]
    check(esc.rpm == EXPECTED_RPM and esc.index == 0, f"ESC_STATUS rpm {esc.rpm}")

    # 3. SET_MESSAGE_INTERVAL: ODOMETRY to 100 Hz, off, back to default; unsupported id.
    def set_interval(msg_id, interval_us, expected_result):
        peer.command(mav2.MAV_CMD_SET_MESSAGE_INTERVAL, [msg_id, interval_us])
        a = peer.ack(mav2.MAV_CMD_SET_MESSAGE_INTERVAL)
        check(a.result == expected_result, f"SET_MESSAGE_INTERVAL({msg_id}, {interval_us}) -> {a.result}")
        check(a.target_system == OUR_SYS and a.target_component == OUR_COMP, "ack target fields")

    set_interval(331, 10000, mav2.MAV_RESULT_ACCEPTED)
    summary["odometry_at_10000us_hz"] = r = peer.rate("ODOMETRY", 1.5)
    check(within(r, 100.0), f"ODOMETRY at {r:.1f} Hz after interval 10000 us")
    set_interval(331, -1, mav2.MAV_RESULT_ACCEPTED)
    peer.recv_for(0.05)
    summary["odometry_disabled_hz"] = r = peer.rate("ODOMETRY", 0.5)
    check(r == 0.0, f"ODOMETRY still at {r} Hz after interval -1")
    set_interval(331, 0, mav2.MAV_RESULT_ACCEPTED)
    summary["odometry_restored_hz"] = r = peer.rate("ODOMETRY", 1.5)
    check(within(r, 30.0), f"ODOMETRY at {r:.1f} Hz after interval 0")
    set_interval(33, 10000, mav2.MAV_RESULT_DENIED)

    # 4. Commands: mode, arm, unknown id, wrong target, AUTOPILOT_VERSION, MAVLink 1.
    peer.command(mav2.MAV_CMD_DO_SET_MODE, [1, 6])
    a = peer.ack(mav2.MAV_CMD_DO_SET_MODE)
    check(a.result == mav2.MAV_RESULT_ACCEPTED, f"DO_SET_MODE -> {a.result}")
    check(a.target_system == OUR_SYS and a.target_component == OUR_COMP, "DO_SET_MODE ack target")
    peer.wait_for(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 6 << 16, 3.0,
                  "HEARTBEAT in offboard (custom_mode 6<<16)")
    peer.command(mav2.MAV_CMD_COMPONENT_ARM_DISARM, [1])
    check(peer.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM).result == mav2.MAV_RESULT_ACCEPTED, "arm")
    peer.wait_for(lambda m: m.get_type() == "HEARTBEAT" and m.base_mode & 128, 3.0,
                  "HEARTBEAT armed")
    peer.command(60000, [1, 2, 3])
    a = peer.ack(60000)
    check(a.result == mav2.MAV_RESULT_UNSUPPORTED, f"command 60000 -> {a.result}")
    peer.command(mav2.MAV_CMD_COMPONENT_ARM_DISARM, [1], target=(0, 0))
    try:
        peer.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM, timeout=0.5)
        raise Fail("a command to system 0 was acknowledged (PX4 ignores it)")
    except Fail as e:
        if "timed out" not in str(e):
            raise
    peer.command(mav2.MAV_CMD_REQUEST_MESSAGE, [148])
    peer.wait_for(lambda m: m.get_type() == "AUTOPILOT_VERSION", 2.0, "AUTOPILOT_VERSION")
    peer.send_v1(mav1.MAVLink_command_long_message(peer.sysid, peer.compid,
                                                   mav1.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                                   1, 0, 0, 0, 0, 0, 0))
    check(peer.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM).result == mav2.MAV_RESULT_ACCEPTED,
          "MAVLink 1 COMMAND_LONG not acknowledged")

    # 5. Attitude setpoints: one for us, one for system 99.
    def attitude_target(time_ms, target_system=None):
        """SET_ATTITUDE_TARGET frame bytes, with the thrust_body extension appended by hand
        (pymavlink's bundled common.xml predates it)."""
        msg = mav2.MAVLink_set_attitude_target_message(
            time_ms, target_system if target_system is not None else peer.sysid, peer.compid, 7,
            [0.5, 0.5, -0.5, 0.5], 0.125, -0.25, 0.5, 0.625)
        return with_extension(msg.pack(peer.tx), 39, struct.pack("<3f", 0.0625, 0.125, -0.75),
                              mav2.MAVLink_set_attitude_target_message.crc_extra)

    peer.send_raw(attitude_target(123456))
    peer.send_raw(attitude_target(999, target_system=99))

    # 6. Garbage, a corrupted CRC, a truncated frame, an unknown id, then valid traffic.
    rng = random.Random(7)
    peer.send_raw(bytes(rng.randrange(256) for _ in range(300)))
    bad_crc = bytearray(attitude_target(777))
    bad_crc[-1] ^= 0xFF
    peer.send_raw(bad_crc)
    peer.send_raw(attitude_target(666)[:-5])
    unknown = bytearray([0xFD, 4, 0, 0, 0, OUR_SYS, OUR_COMP, 0xDE, 0xBC, 0x0A, 1, 2, 3, 4])
    crc = x25crc(bytes(unknown[1:]))
    crc.accumulate(bytes([0]))
    peer.send_raw(unknown + struct.pack("<H", crc.crc))
    peer.send_raw(b"\x01\x02\x03\x04\x05" + attitude_target(888))
    peer.command(mav2.MAV_CMD_COMPONENT_ARM_DISARM, [1])
    check(peer.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM).result == mav2.MAV_RESULT_ACCEPTED,
          "no COMMAND_ACK after bad frames: the endpoint stopped")

    summary["frames_received"] = peer.frames
    summary["sequence_gaps"] = peer.seq_gaps
    check(peer.seq_gaps <= max(2, peer.frames // 100),
          f"{peer.seq_gaps} sequence gaps in {peer.frames} frames")
    return summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--local", type=int, required=True, help="our UDP port (endpoint streams here)")
    ap.add_argument("--remote", type=int, required=True, help="the endpoint's UDP port")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--expect-custom-mode", type=int, default=3 << 16)
    args = ap.parse_args()
    peer = Peer(args.local, args.remote, args.sysid, args.compid)
    try:
        summary = run(peer, args)
    except Fail as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    print(json.dumps(summary, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
