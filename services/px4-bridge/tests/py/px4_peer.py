#!/usr/bin/env python3
"""Plays PX4 v1.16 (system 1, component 1, MAVLink 2) towards `taut svc px4-bridge` over UDP and
records what the bridge sends. Run by services/taut/tests/bridge_pymavlink.rs.

It sends to the bridge's udpin port from its own socket: HEARTBEAT at 5 Hz (custom_mode and
the armed bit follow the commands), ODOMETRY 50 Hz, HIGHRES_IMU 100 Hz, ESC_STATUS 20 Hz
(packed by hand: pymavlink 2.4.50's common.xml lacks #291). Commands are answered per scenario:

- flow: SET_MESSAGE_INTERVAL accepted; the first DO_SET_MODE ignored, then ACCEPTED (mode ->
  offboard); the first arm TEMPORARILY_REJECTED, then ACCEPTED (armed). One second after the
  bridge is armed in offboard, 2 s of garbage interleaved with the telemetry (random datagrams,
  bad CRC, truncated frames, an unknown message id, noise before a good frame, a bare header
  announcing 255 bytes); then 2 s without HEARTBEAT (telemetry goes on); then 1 s of heartbeats.
- fail: every DO_SET_MODE TEMPORARILY_REJECTED; runs 4.5 s.

Prints one JSON line (what it received, when, and what it sent) and exits 0; on a broken
expectation of its own (e.g. the handshake never completes) it says why in "error".
"""

import argparse
import json
import os
import random
import select
import socket
import struct
import sys
import time

os.environ["MAVLINK20"] = "1"
try:
    from pymavlink.dialects.v20 import common as mav2
    from pymavlink.generator.mavcrc import x25crc
except ImportError as err:  # the Rust test turns this into a clear failure
    print(f"FAIL: pymavlink is not importable: {err}", file=sys.stderr)
    sys.exit(3)

SYS, COMP = 1, 1
POSCTL, OFFBOARD = 3 << 16, 6 << 16
ARMED = 128
ESC_STATUS_ID, ESC_STATUS_CRC_EXTRA = 291, 10
ODOMETRY = dict(x=1.5, y=-2.0, z=-1.25, q=[0.5 ** 0.5, 0.0, 0.0, 0.5 ** 0.5],
                vx=0.75, vy=-0.5, vz=0.25, rollspeed=0.1, pitchspeed=-0.2, yawspeed=0.3)
IMU = dict(xacc=0.1, yacc=-0.2, zacc=-9.81, xgyro=0.01, ygyro=0.02, zgyro=-0.03)
RPM = [6000, 6100, 6200, 6300]
NAN21 = [float("nan")] * 21


class Peer:
    def __init__(self, port, scenario, seed):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.bridge = ("127.0.0.1", port)
        self.scenario = scenario
        self.tx = mav2.MAVLink(None, srcSystem=SYS, srcComponent=COMP)
        self.rx = mav2.MAVLink(None)
        self.rx.robust_parsing = True
        self.rng = random.Random(seed)
        self.mode, self.base_mode = POSCTL, 1
        self.seq = 0
        self.counts = {"set_mode": 0, "arm": 0}
        self.rec = {"setpoints": [], "heartbeats": [], "commands": [], "bad_frames": 0,
                    "non_v2_datagrams": 0, "other": {}, "sent_garbage": {},
                    "heartbeats_sent": []}
        self.heartbeats_on = True
        self.garbage_on = False
        self.t_done = None

    # -- sending -------------------------------------------------------------------------
    def send(self, msg):
        self.sock.sendto(msg.pack(self.tx), self.bridge)

    def esc_status(self, time_usec):
        payload = struct.pack("<Q4i4f4fB", time_usec, *RPM, *([0.0] * 8), 0)
        header = struct.pack("<BBBBBBBHB", 0xFD, len(payload), 0, 0, self.seq & 0xFF, SYS, COMP,
                             ESC_STATUS_ID & 0xFFFF, ESC_STATUS_ID >> 16)
        self.seq += 1
        crc = x25crc(header[1:] + payload)
        crc.accumulate(bytes([ESC_STATUS_CRC_EXTRA]))
        return header + payload + struct.pack("<H", crc.crc)

    def telemetry(self, kind, t):
        usec = int(t * 1e6)
        if kind == "odometry":
            o = ODOMETRY
            return mav2.MAVLink_odometry_message(
                usec, mav2.MAV_FRAME_LOCAL_NED, mav2.MAV_FRAME_LOCAL_NED, o["x"], o["y"], o["z"],
                o["q"], o["vx"], o["vy"], o["vz"], o["rollspeed"], o["pitchspeed"],
                o["yawspeed"], NAN21, NAN21, 0, mav2.MAV_ESTIMATOR_TYPE_AUTOPILOT, 0).pack(self.tx)
        if kind == "imu":
            i = IMU
            return mav2.MAVLink_highres_imu_message(
                usec, i["xacc"], i["yacc"], i["zacc"], i["xgyro"], i["ygyro"], i["zgyro"],
                0, 0, 0, 0, 0, 0, 0, 0x3F, 0).pack(self.tx)
        if kind == "esc":
            return self.esc_status(usec)
        return mav2.MAVLink_heartbeat_message(
            mav2.MAV_TYPE_QUADROTOR, mav2.MAV_AUTOPILOT_PX4, self.base_mode, self.mode,
            mav2.MAV_STATE_ACTIVE if self.base_mode & ARMED else mav2.MAV_STATE_STANDBY,
            3).pack(self.tx)

    def garbage(self, k):
        kinds = ["random", "bad_crc", "truncated", "unknown_id", "prefixed", "bogus_header"]
        kind = kinds[k % len(kinds)]
        good = bytearray(self.telemetry("odometry", time.monotonic()))
        if kind == "random":
            data = bytes(self.rng.randrange(256) for _ in range(self.rng.randrange(8, 80)))
        elif kind == "bad_crc":
            good[-1] ^= 0xFF
            data = bytes(good)
        elif kind == "truncated":
            data = bytes(good[:-7])
        elif kind == "unknown_id":
            frame = bytearray(good)
            frame[7:10] = bytes([0x60, 0xEA, 0x00])  # id 60000, CRC as if CRC_EXTRA were 0
            crc = x25crc(bytes(frame[1:-2]))
            crc.accumulate(bytes([0]))
            frame[-2:] = struct.pack("<H", crc.crc)
            data = bytes(frame)
        elif kind == "prefixed":
            data = bytes([1, 2, 3, 4, 5, 6, 7]) + bytes(good)
        else:
            data = bytes([0xFD, 0xFF, 0, 0, 0, SYS, COMP, 0, 0, 0])
        self.sock.sendto(data, self.bridge)
        self.rec["sent_garbage"][kind] = self.rec["sent_garbage"].get(kind, 0) + 1

    # -- receiving -----------------------------------------------------------------------
    def answer(self, c, now):
        self.rec["commands"].append({"t": now, "command": c.command, "confirmation": c.confirmation,
                                     "target": [c.target_system, c.target_component],
                                     "params": [c.param1, c.param2, c.param3, c.param4]})
        if c.target_system != SYS:
            return
        result = mav2.MAV_RESULT_ACCEPTED
        if c.command == mav2.MAV_CMD_DO_SET_MODE:
            self.counts["set_mode"] += 1
            if self.scenario == "fail":
                result = mav2.MAV_RESULT_TEMPORARILY_REJECTED
            elif self.counts["set_mode"] == 1:
                return  # ignored: the bridge must resend
            else:
                self.mode = OFFBOARD
        elif c.command == mav2.MAV_CMD_COMPONENT_ARM_DISARM:
            self.counts["arm"] += 1
            if self.counts["arm"] == 1:
                result = mav2.MAV_RESULT_TEMPORARILY_REJECTED
            else:
                self.base_mode |= ARMED
        self.send(mav2.MAVLink_command_ack_message(c.command, result, 0, 0, 1, 191))

    def handle(self, m, now):
        t = m.get_type()
        if t == "BAD_DATA":
            self.rec["bad_frames"] += 1
        elif t == "SET_ATTITUDE_TARGET":
            self.rec["setpoints"].append([now, m.type_mask, m.thrust, list(m.q), m.target_system,
                                          m.target_component, m.time_boot_ms])
        elif t == "HEARTBEAT":
            self.rec["heartbeats"].append([now, m.type, m.autopilot, m.get_srcSystem(),
                                           m.get_srcComponent()])
        elif t == "COMMAND_LONG":
            self.answer(m, now)
        else:
            self.rec["other"][t] = self.rec["other"].get(t, 0) + 1

    def receive(self, timeout):
        ready, _, _ = select.select([self.sock], [], [], timeout)
        if not ready:
            return
        while True:
            try:
                data, _ = self.sock.recvfrom(65536)
            except BlockingIOError:
                return
            now = time.monotonic()
            if len(data) < 12 or data[0] != 0xFD:
                self.rec["non_v2_datagrams"] += 1
            for m in self.rx.parse_buffer(data) or []:
                self.handle(m, now)

    def run(self, args):
        start = time.monotonic()
        periods = {"heartbeat": 0.2, "odometry": 0.02, "imu": 0.01, "esc": 0.05, "garbage": 0.02}
        due = {k: start for k in periods}
        k_garbage = 0
        end = start + (4.5 if self.scenario == "fail" else args.timeout)
        while True:
            now = time.monotonic()
            if now >= end:
                break
            if self.scenario == "flow":
                if self.t_done is None and self.base_mode & ARMED and self.mode == OFFBOARD:
                    self.t_done = now
                    self.rec["t_done"] = now
                    end = now + 1.0 + 2.0 + 2.0 + 1.0
                    self.rec["t_garbage"] = [now + 1.0, now + 3.0]
                    self.rec["t_no_heartbeat"] = now + 3.0
                    self.rec["t_heartbeat_again"] = now + 5.0
                if self.t_done is not None:
                    self.garbage_on = self.t_done + 1.0 <= now < self.t_done + 3.0
                    self.heartbeats_on = not (self.t_done + 3.0 <= now < self.t_done + 5.0)
            for kind, period in periods.items():
                if now < due[kind]:
                    continue
                due[kind] = max(due[kind] + period, now)
                if kind == "garbage":
                    if self.garbage_on:
                        self.garbage(k_garbage)
                        k_garbage += 1
                elif kind != "heartbeat" or self.heartbeats_on:
                    if kind == "heartbeat":
                        self.rec["heartbeats_sent"].append(now)
                    self.sock.sendto(self.telemetry(kind, now), self.bridge)
            self.receive(max(0.0, min(due.values()) - time.monotonic()))
        if self.scenario == "flow" and self.t_done is None:
            self.rec["error"] = f"the bridge was not armed in offboard within {args.timeout} s"
        self.rec["counts"] = self.counts
        self.rec["t_start"], self.rec["t_end"] = start, time.monotonic()
        print(json.dumps(self.rec))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--port", type=int, required=True, help="the bridge's udpin port")
    p.add_argument("--scenario", choices=["flow", "fail"], required=True)
    p.add_argument("--timeout", type=float, default=8.0, help="flow: limit for the handshake")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    Peer(args.port, args.scenario, args.seed).run(args)


if __name__ == "__main__":
    main()
