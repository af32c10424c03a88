#!/usr/bin/env python3
"""Flies drone uav1 of `taut plant` in attitude offboard over MAVLink, like a companion computer.

Run by services/taut/tests/plant_mavlink.rs against `taut plant --scenario test-a --no-noise`.
The script binds 127.0.0.1:PORT (where the plant's drone streams, PX4 SITL's 14540), answers
to whoever streams there (like mavutil's udpin), and checks, in order:

1. HEARTBEAT from SYSID/1: PX4 quadrotor, disarmed, in Position;
2.-3. a 50 Hz SET_ATTITUDE_TARGET stream (mask 7, thrust 0): after 0.5 s DO_SET_MODE offboard
   is ACCEPTED (PX4 allows any mode change while disarmed) but arming is TEMPORARILY_REJECTED
   (the stream is not yet older than 1 s); after 1.3 s both are ACCEPTED;
4. a climb to z = -1.0 m on a PD altitude loop (level attitude, yaw +30 deg), then a 3 s hold;
5. 1 s of mask 0 (attitude + zero body rates): still proof of life, still offboard, still held;
6. garbage datagrams, corrupted-CRC and truncated setpoints interleaved with the stream;
7. offboard loss (only mask-131 messages, which are no proof of life): AUTO.LAND after
   COM_OF_LOSS_T = 1 s, descent at MPC_LAND_SPEED = 0.7 m/s, landing, auto-disarm;
8. prints one JSON summary line and exits 0; on the first failed check it exits 1 with
   "FAIL: ..." on stderr.
"""

import argparse
import json
import math
import os
import random
import select
import socket
import sys
import time

os.environ["MAVLINK20"] = "1"
try:
    from pymavlink.dialects.v20 import common as mav2
except ImportError as err:  # the Rust test turns this into a clear failure
    print(f"FAIL: pymavlink is not importable: {err}", file=sys.stderr)
    sys.exit(3)

OUR_SYS, OUR_COMP = 42, 191  # companion's ids (MAV_COMP_ID_ONBOARD_COMPUTER)
G = 9.81
HOVER_THROTTLE = 0.6  # holds the bare drone's 2.064 kg
SETPOINT_PERIOD_S = 0.02  # 50 Hz
HEARTBEAT_INTERVAL_US = 50_000  # raised from PX4's 1 Hz so mode changes show within 50 ms
YAW_DEG = 30.0
Z_START_M = -0.12
Z_SP_M = -1.0
KP, KD = 4.0, 3.2  # altitude PD, 1/s^2 and 1/s: natural frequency 2 rad/s, damping 0.8

POSCTL = 3 << 16
OFFBOARD = 6 << 16
AUTO_LAND = (4 << 16) | (6 << 24)
ARMED = mav2.MAV_MODE_FLAG_SAFETY_ARMED  # 128

MASK_ATTITUDE_THRUST = 7  # roll, pitch, yaw rates ignored
MASK_ATTITUDE_AND_RATES = 0  # PX4: attitude wins, the rates are published too
MASK_NO_PROOF_OF_LIFE = 128 | 3  # attitude and roll/pitch rates ignored: PX4 publishes nothing


class Fail(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Fail(what)


def level_q(yaw_deg):
    """Level attitude with heading `yaw_deg`, (w, x, y, z), body FRD -> NED."""
    h = math.radians(yaw_deg) / 2.0
    return [math.cos(h), 0.0, 0.0, math.sin(h)]


def euler_deg(q):
    """Roll, pitch, yaw (ZYX) in degrees of (w, x, y, z)."""
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return [math.degrees(a) for a in (roll, pitch, yaw)]


class Companion:
    """One UDP link to the drone, a 50 Hz setpoint stream, and the latest telemetry.

    Everything runs in one loop (`spin`): receive what arrived, send the setpoint when due.
    """

    def __init__(self, port, sysid, seed):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.sock.setblocking(False)
        self.plant = None  # learnt from the first datagram
        self.sysid = sysid
        self.tx = mav2.MAVLink(None, srcSystem=OUR_SYS, srcComponent=OUR_COMP)
        self.rx = mav2.MAVLink(None)
        self.rx.robust_parsing = True
        self.rng = random.Random(seed)
        self.t0 = time.monotonic()
        # Setpoint stream.
        self.streaming = False
        self.mask = MASK_ATTITUDE_THRUST
        self.fly = False  # False: thrust 0 (not yet armed)
        self.z_sp = Z_SP_M
        self.q = level_q(YAW_DEG)
        self.next_setpoint = 0.0
        self.next_own_heartbeat = 0.0
        self.last_proof_of_life = None  # time of the last mask-7/0 setpoint sent
        self.sent = {"setpoints": 0, "mask0": 0, "mask131": 0, "bad_crc": 0, "truncated": 0,
                     "garbage_datagrams": 0, "garbage_bytes": 0, "prefixed": 0}
        self.garbage = False
        self.garbage_tick = 0
        # Telemetry.
        self.hb = None
        self.z = None
        self.vz = None
        self.counts = {}
        self.foreign = 0

    def now(self):
        return time.monotonic() - self.t0

    # -- sending -------------------------------------------------------------------------
    def send_raw(self, data):
        if self.plant is not None:
            self.sock.sendto(bytes(data), self.plant)

    def send(self, msg):
        self.send_raw(msg.pack(self.tx))

    def command(self, cmd, params):
        p = list(params) + [0.0] * (7 - len(params))
        self.send(mav2.MAVLink_command_long_message(self.sysid, 1, cmd, 0, *p))

    def thrust(self):
        if not self.fly or self.z is None:
            return 0.0
        accel_up = KP * (self.z - self.z_sp) + KD * self.vz
        return max(0.2, min(0.9, HOVER_THROTTLE * (1.0 + accel_up / G)))

    def setpoint_frame(self, mask):
        ms = int(self.now() * 1000) & 0xFFFFFFFF
        msg = mav2.MAVLink_set_attitude_target_message(
            ms, self.sysid, 1, mask, self.q, 0.0, 0.0, 0.0, self.thrust())
        return bytearray(msg.pack(self.tx))

    def send_setpoint(self):
        mask = self.mask
        frame = self.setpoint_frame(mask)
        if self.garbage:
            self.garbage_tick += 1
            k = self.garbage_tick
            if k % 6 == 0:
                # The setpoint itself arrives with a corrupted checksum: dropped, so one
                # proof of life is missing from the stream (one in six still leaves 42 Hz).
                frame[-1] ^= 0xFF
                self.send_raw(frame)
                self.sent["bad_crc"] += 1
                return
            if k % 6 == 2:
                junk = bytes(self.rng.randrange(256) for _ in range(self.rng.randrange(8, 80)))
                self.send_raw(junk)
                self.sent["garbage_datagrams"] += 1
                self.sent["garbage_bytes"] += len(junk)
            if k % 6 == 3:
                self.send_raw(self.setpoint_frame(mask)[:-5])
                self.sent["truncated"] += 1
            if k % 6 == 4:
                # Noise before a valid frame in one datagram: the parser must resynchronise.
                frame = bytearray(b"\x01\x02\x03\x04\x05\x06\x07") + frame
                self.sent["prefixed"] += 1
        self.send_raw(frame)
        self.sent["setpoints"] += 1
        if mask == MASK_ATTITUDE_AND_RATES:
            self.sent["mask0"] += 1
        if mask == MASK_NO_PROOF_OF_LIFE:
            self.sent["mask131"] += 1
        else:
            self.last_proof_of_life = self.now()

    # -- receiving -----------------------------------------------------------------------
    def handle(self, msg):
        t = msg.get_type()
        if t.startswith("UNKNOWN_"):
            t = {"UNKNOWN_291": "ESC_STATUS"}.get(t, t)  # absent from pymavlink's common.xml
        self.counts[t] = self.counts.get(t, 0) + 1
        if t == "HEARTBEAT" and msg.get_srcComponent() == 1:
            self.hb = msg
        elif t == "LOCAL_POSITION_NED":
            self.z, self.vz = msg.z, msg.vz

    def spin(self, until, predicate=None):
        """Runs the loop until `until` (seconds since start) or until `predicate(msg)` holds
        for a received message (then returns it). Returns None at `until`."""
        while True:
            now = self.now()
            if now >= until:
                return None
            if self.streaming and self.plant is not None and now >= self.next_setpoint:
                self.send_setpoint()
                self.next_setpoint = max(self.next_setpoint + SETPOINT_PERIOD_S, now)
            if self.plant is not None and now >= self.next_own_heartbeat:
                self.send(mav2.MAVLink_heartbeat_message(
                    mav2.MAV_TYPE_ONBOARD_CONTROLLER, mav2.MAV_AUTOPILOT_INVALID, 0, 0, 0,
                    mav2.MAV_STATE_ACTIVE))
                self.next_own_heartbeat = now + 1.0
            wake = min(until, self.next_setpoint if self.streaming else until,
                       self.next_own_heartbeat if self.plant is not None else until)
            timeout = max(0.0, wake - self.now())
            ready, _, _ = select.select([self.sock], [], [], timeout)
            if not ready:
                continue
            while True:
                try:
                    data, src = self.sock.recvfrom(4096)
                except BlockingIOError:
                    break
                if self.plant is None:
                    self.plant = src
                # One MAVLink 2 frame per datagram; its header names the sender.
                if len(data) < 10 or data[0] != 0xFD or data[5] != self.sysid or data[6] != 1:
                    self.foreign += 1
                    continue
                for m in self.rx.parse_buffer(data) or []:
                    if m.get_type() == "BAD_DATA":
                        continue
                    self.handle(m)
                    if predicate is not None and predicate(m):
                        return m

    def wait_for(self, predicate, timeout, what):
        m = self.spin(self.now() + timeout, predicate)
        if m is None:
            raise Fail(f"timed out after {timeout} s waiting for {what}")
        return m

    def sleep(self, seconds):
        self.spin(self.now() + seconds)

    def ack(self, cmd, timeout=1.0):
        return self.wait_for(
            lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd, timeout,
            f"COMMAND_ACK for command {cmd}")

    def heartbeat(self, cond, timeout, what):
        return self.wait_for(
            lambda m: m.get_type() == "HEARTBEAT" and m.get_srcComponent() == 1 and cond(m),
            timeout, what)


def result_name(r):
    return mav2.enums["MAV_RESULT"][r].name if r in mav2.enums["MAV_RESULT"] else str(r)


def run(c, args):
    s = {}

    # 1. Identity and initial state.
    hb = c.heartbeat(lambda m: True, 5.0, f"HEARTBEAT from system {args.sysid}")
    check(hb.type == mav2.MAV_TYPE_QUADROTOR, f"HEARTBEAT type {hb.type}, expected quadrotor")
    check(hb.autopilot == mav2.MAV_AUTOPILOT_PX4, f"HEARTBEAT autopilot {hb.autopilot}")
    check(not hb.base_mode & ARMED, f"armed at start (base_mode {hb.base_mode})")
    check(hb.custom_mode == POSCTL, f"custom_mode {hb.custom_mode:#x} at start, expected POSCTL")
    if c.z is None:
        c.wait_for(lambda m: m.get_type() == "LOCAL_POSITION_NED", 1.0, "LOCAL_POSITION_NED")
    check(abs(c.z - Z_START_M) < 0.03, f"start z {c.z:.3f}, expected {Z_START_M}")
    c.command(mav2.MAV_CMD_SET_MESSAGE_INTERVAL, [0, HEARTBEAT_INTERVAL_US])
    a = c.ack(mav2.MAV_CMD_SET_MESSAGE_INTERVAL)
    check(a.result == mav2.MAV_RESULT_ACCEPTED, f"SET_MESSAGE_INTERVAL(HEARTBEAT) -> {a.result}")
    check(a.target_system == OUR_SYS and a.target_component == OUR_COMP, "ack target fields")

    # 2.-3. Stream, then mode and arming against the 2 Hz / more-than-1-s availability rule.
    c.streaming = True
    c.next_setpoint = c.now()
    t_stream = c.now()
    c.sleep(0.5)
    c.command(mav2.MAV_CMD_DO_SET_MODE, [1, 6, 0])
    r = c.ack(mav2.MAV_CMD_DO_SET_MODE).result
    s["set_mode_at_0_5s"] = result_name(r)
    check(r == mav2.MAV_RESULT_ACCEPTED,
          f"DO_SET_MODE offboard while disarmed after 0.5 s -> {result_name(r)}; PX4 allows "
          "any mode change while disarmed")
    c.heartbeat(lambda m: m.custom_mode == OFFBOARD, 0.5, "HEARTBEAT custom_mode OFFBOARD")
    c.command(mav2.MAV_CMD_COMPONENT_ARM_DISARM, [1])
    r = c.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM).result
    s["arm_at_s"] = round(c.now() - t_stream, 3)
    s["arm_early"] = result_name(r)
    check(c.now() - t_stream < 0.95, "the early arm attempt came too late to test the rule")
    check(r == mav2.MAV_RESULT_TEMPORARILY_REJECTED,
          f"arming {s['arm_at_s']} s into the stream -> {result_name(r)}, expected "
          "TEMPORARILY_REJECTED (offboard needs the stream for more than 1 s)")
    c.spin(t_stream + 1.3)
    c.command(mav2.MAV_CMD_DO_SET_MODE, [1, 6, 0])
    r = c.ack(mav2.MAV_CMD_DO_SET_MODE).result
    check(r == mav2.MAV_RESULT_ACCEPTED, f"DO_SET_MODE offboard after 1.3 s -> {result_name(r)}")
    c.heartbeat(lambda m: m.custom_mode == OFFBOARD, 0.5, "HEARTBEAT custom_mode OFFBOARD")
    c.command(mav2.MAV_CMD_COMPONENT_ARM_DISARM, [1])
    r = c.ack(mav2.MAV_CMD_COMPONENT_ARM_DISARM).result
    check(r == mav2.MAV_RESULT_ACCEPTED, f"arming after 1.3 s of stream -> {result_name(r)}")
    c.fly = True
    t_arm = c.now()
    c.heartbeat(lambda m: m.base_mode & ARMED and m.custom_mode == OFFBOARD, 0.5,
                "HEARTBEAT armed in OFFBOARD")

    # 4. Take-off and hold.
    c.wait_for(lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.z < -0.5, 5.0,
               "take-off (z < -0.5 m within 5 s of arming)")
    s["takeoff_to_0_5m_s"] = round(c.now() - t_arm, 3)
    c.wait_for(lambda m: m.get_type() == "LOCAL_POSITION_NED" and abs(m.z - Z_SP_M) < 0.05
               and abs(m.vz) < 0.1, 5.0, "settling within 5 cm of z = -1.0")
    s["settle_s"] = round(c.now() - t_arm, 3)
    hold = track(c, 3.0)
    s["hold_max_err_m"] = round(hold["max_err"], 4)
    check(hold["max_err"] <= 0.15, f"hold error {hold['max_err']:.3f} m > 0.15 m over 3 s")
    check(hold["modes"] == {OFFBOARD} and hold["armed"], f"left offboard during hold: {hold}")
    for name, rate in (("ODOMETRY", 30.0), ("ATTITUDE_QUATERNION", 50.0)):
        got = hold["counts"].get(name, 0) / 3.0
        s[f"{name.lower()}_hz"] = round(got, 1)
        check(abs(got - rate) <= 0.2 * rate, f"{name} at {got:.1f} Hz, expected {rate}")
    roll, pitch, yaw = hold["euler"]
    s["hold_attitude_deg"] = [round(roll, 2), round(pitch, 2), round(yaw, 2)]
    check(abs(roll) < 2 and abs(pitch) < 2 and abs(yaw - YAW_DEG) < 2,
          f"attitude {roll:.1f}/{pitch:.1f}/{yaw:.1f} deg, expected level at yaw {YAW_DEG}")
    check(abs(hold["odometry_z"] - c.z) < 0.05, "ODOMETRY z disagrees with LOCAL_POSITION_NED")

    # 5. Attitude and body rates both set: PX4 flies the attitude, still proof of life.
    c.mask = MASK_ATTITUDE_AND_RATES
    both = track(c, 1.0)
    c.mask = MASK_ATTITUDE_THRUST
    s["mask0_max_err_m"] = round(both["max_err"], 4)
    check(both["max_err"] <= 0.2, f"mask 0: altitude error {both['max_err']:.3f} m > 0.2 m")
    check(both["modes"] == {OFFBOARD} and both["armed"], f"mask 0 left offboard: {both}")

    # 6. Garbage interleaved with the stream.
    c.garbage = True
    noisy = track(c, 2.0)
    c.garbage = False
    s["garbage_max_err_m"] = round(noisy["max_err"], 4)
    s["sent"] = dict(c.sent)
    check(c.sent["bad_crc"] >= 10 and c.sent["truncated"] >= 10 and c.sent["garbage_bytes"] > 0,
          f"garbage not sent: {c.sent}")
    check(noisy["max_err"] <= 0.15, f"with garbage: altitude error {noisy['max_err']:.3f} m")
    check(noisy["modes"] == {OFFBOARD} and noisy["armed"], f"garbage broke offboard: {noisy}")

    # 7. Offboard loss: the stream goes on with mask 131 only (no proof of life).
    c.mask = MASK_NO_PROOF_OF_LIFE
    t_last = c.last_proof_of_life
    c.heartbeat(lambda m: m.custom_mode != OFFBOARD, 2.0, "the mode to leave OFFBOARD")
    t_fail = c.now() - t_last
    s["failsafe_after_s"] = round(t_fail, 3)
    check(c.hb.custom_mode == AUTO_LAND, f"failsafe mode {c.hb.custom_mode:#x}, expected AUTO.LAND")
    check(c.hb.base_mode & ARMED, "disarmed at the failsafe instead of landing")
    check(c.hb.system_status == mav2.MAV_STATE_CRITICAL,
          f"system_status {c.hb.system_status} in failsafe, expected CRITICAL")
    check(0.95 <= t_fail <= 1.3, f"failsafe {t_fail:.3f} s after the last proof of life, "
          "expected COM_OF_LOSS_T = 1 s (+ one 50 ms heartbeat)")
    t_land_start = c.now()
    descent = []
    landed_at = None
    while landed_at is None:
        m = c.wait_for(lambda m: m.get_type() == "LOCAL_POSITION_NED", 0.5, "LOCAL_POSITION_NED")
        if c.now() - t_land_start > 6.0:
            raise Fail(f"not landed 6 s after the failsafe (z = {m.z:.2f} m)")
        check(c.hb.custom_mode == AUTO_LAND,
              f"left AUTO.LAND during descent ({c.hb.custom_mode:#x})")
        if -0.75 <= m.z <= -0.35:
            descent.append(m.vz)
        if m.z > -0.2:
            landed_at = c.now()
    check(len(descent) >= 5, f"only {len(descent)} samples in the descent window")
    mean_vz = sum(descent) / len(descent)
    s["descent_vz_mean_mps"] = round(mean_vz, 3)
    s["descent_vz_range_mps"] = [round(min(descent), 3), round(max(descent), 3)]
    check(all(0.4 <= v <= 1.0 for v in descent),
          f"descent vz {min(descent):.2f}..{max(descent):.2f} m/s outside 0.4..1.0")
    check(abs(mean_vz - 0.7) <= 0.1, f"mean descent {mean_vz:.3f} m/s, expected 0.7")
    s["landing_s"] = round(landed_at - t_land_start, 3)
    c.heartbeat(lambda m: not m.base_mode & ARMED, 6.0 - (c.now() - t_land_start),
                "auto-disarm within 6 s of the failsafe")
    s["disarm_after_failsafe_s"] = round(c.now() - t_land_start, 3)
    s["disarm_after_touchdown_s"] = round(c.now() - landed_at, 3)
    check(c.z > -0.2, f"disarmed at z = {c.z:.2f} m")
    c.streaming = False
    s["sent"] = dict(c.sent)
    s["received"] = {k: c.counts[k] for k in sorted(c.counts)}
    check(c.foreign == 0, f"{c.foreign} datagrams not a MAVLink 2 frame from {args.sysid}/1")
    return s


def track(c, seconds):
    """Flies for `seconds` and reports the altitude error, modes and telemetry seen."""
    out = {"max_err": 0.0, "modes": set(), "armed": True, "counts": {}, "euler": [0, 0, 0],
           "odometry_z": None}

    def watch(m):
        t = m.get_type()
        out["counts"][t] = out["counts"].get(t, 0) + 1
        if t == "LOCAL_POSITION_NED":
            out["max_err"] = max(out["max_err"], abs(m.z - c.z_sp))
        elif t == "HEARTBEAT" and m.get_srcComponent() == 1:
            out["modes"].add(m.custom_mode)
            out["armed"] &= bool(m.base_mode & ARMED)
        elif t == "ATTITUDE_QUATERNION":
            out["euler"] = euler_deg([m.q1, m.q2, m.q3, m.q4])
        elif t == "ODOMETRY":
            out["odometry_z"] = m.z
        return False

    c.spin(c.now() + seconds, watch)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, required=True,
                    help="our UDP port, where the drone streams (PX4 SITL: 14540)")
    ap.add_argument("--sysid", type=int, default=1, help="the drone's MAVLink system id")
    ap.add_argument("--seed", type=int, default=7, help="seed of the garbage bytes")
    args = ap.parse_args()
    c = Companion(args.port, args.sysid, args.seed)
    try:
        summary = run(c, args)
    except Fail as e:
        hb = f"{c.hb.custom_mode:#x}/{c.hb.base_mode}" if c.hb else "none"
        print(f"FAIL: {e} (at {c.now():.2f} s; z = {c.z}, last heartbeat mode/base {hb})",
              file=sys.stderr)
        return 1
    print(json.dumps(summary, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
