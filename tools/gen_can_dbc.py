#!/usr/bin/python3
"""Writes the DBC of a robot's CAN map (models/<robot>/can_map.yaml): one MIT command and one
reply message per motor with the actuator's ranges as factor/offset, and the IMU frames of
docs/can.md (the classic three-frame variant and the FD variant).

usage: tools/gen_can_dbc.py models/quadruped/can_map.yaml [--fd-imu-id 0x090] > models/quadruped/quadruped.dbc

The IMU in the map uses one variant; the DBC describes both, the other one on --fd-imu-id (or
--classic-imu-id), so that a bus log of either can be decoded. Kept in step with the C++ codecs
by tests/runtime/transport/can/check_dbc.py.
"""
import argparse
import sys

import yaml


def num(x):
    return repr(float(x)) if float(x) != int(x) else str(int(x))


def sig_be(name, start, size, lo, hi, unit, bits):
    factor = (hi - lo) / (2 ** bits - 1)
    return (f' SG_ {name} : {start}|{size}@0+ ({factor!r},{num(lo)}) [{num(lo)}|{num(hi)}] "{unit}" Vector__XXX')


def sig_le16(name, start, scale, unit):
    lim = 32767 * scale
    return f' SG_ {name} : {start}|16@1- ({scale!r},0) [{-lim!r}|{lim!r}] "{unit}" Vector__XXX'


def sig_u8(name, start, unit=""):
    return f' SG_ {name} : {start}|8@1+ (1,0) [0|255] "{unit}" Vector__XXX'


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("map")
    ap.add_argument("--fd-imu-id", type=lambda s: int(s, 0), default=0x090)
    ap.add_argument("--classic-imu-id", type=lambda s: int(s, 0), default=0x080)
    a = ap.parse_args()
    m = yaml.safe_load(open(a.map))
    acts = {x["name"]: x for x in m["actuators"]}
    out = []
    out.append('VERSION "pbppo-rt ' + m["robot"] + ' CAN map"')
    out.append("")
    out.append("NS_ :")
    out.append("")
    out.append("BS_:")
    out.append("")
    out.append("BU_: Controller Motor IMU")
    out.append("")
    fd_ids = []
    comments = []
    for mo in m["motors"]:
        r = acts[mo["actuator"]]
        j = mo["joint"]
        out.append(f"BO_ {int(mo['id'])} CMD_{j}: 8 Controller")
        out.append(sig_be("p_des", 7, 16, r["p_min"], r["p_max"], "rad", 16))
        out.append(sig_be("v_des", 23, 12, r["v_min"], r["v_max"], "rad/s", 12))
        out.append(sig_be("kp", 27, 12, r["kp_min"], r["kp_max"], "Nm/rad", 12))
        out.append(sig_be("kd", 47, 12, r["kd_min"], r["kd_max"], "Nm*s/rad", 12))
        out.append(sig_be("t_ff", 51, 12, r["t_min"], r["t_max"], "Nm", 12))
        out.append("")
        out.append(f"BO_ {int(mo['reply_id'])} RPL_{j}: 6 Motor")
        out.append(sig_u8("motor_id", 0))
        out.append(sig_be("p", 15, 16, r["p_min"], r["p_max"], "rad", 16))
        out.append(sig_be("v", 31, 12, r["v_min"], r["v_max"], "rad/s", 12))
        out.append(sig_be("t", 35, 12, r["t_min"], r["t_max"], "Nm", 12))
        out.append("")
        comments.append(f'CM_ BO_ {int(mo["id"])} "MIT command to {j} on bus {mo["bus"]} ({mo["actuator"]}); '
                        f'FF FF FF FF FF FF FF FC/FD/FE are the enter/exit/set-zero frames";')
        comments.append(f'CM_ BO_ {int(mo["reply_id"])} "MIT reply of {j}";')
    for u in m.get("imus", []):
        n = u["name"]
        classic_id = int(u["id"]) if u["format"] == "classic" else a.classic_imu_id
        fd_id = int(u["id"]) if u["format"] == "fd" else a.fd_imu_id
        q, w, acc = 1.0 / 32767.0, 1.0 / 1000.0, 1.0 / 200.0
        # (name, axes, scale, unit) of each vector, in the order the FD frame packs them.
        vectors = [("q", "wxyz", q, ""), ("w", "xyz", w, "rad/s"), ("a", "xyz", acc, "m/s^2")]

        def message(can_id, suffix, length, parts, seq_bit):
            out.append(f"BO_ {can_id} IMU_{n}_{suffix}: {length} IMU")
            bit = 0
            for name, axes, scale, unit in parts:
                for c in axes:
                    out.append(sig_le16(name + c, bit, scale, unit))
                    bit += 16
            if seq_bit is not None:
                out.append(sig_u8("seq", seq_bit))
                out.append(sig_u8("status", seq_bit + 8))
            out.append("")

        # Classic: three 8-byte frames, the vectors after the first ending in seq and status.
        message(classic_id, "Q", 8, vectors[0:1], None)
        message(classic_id + 1, "W", 8, vectors[1:2], 48)
        message(classic_id + 2, "A", 8, vectors[2:3], 48)
        message(fd_id, "FD", 24, vectors, 160)
        fd_ids.append(fd_id)
        comments.append(f'CM_ BO_ {classic_id} "IMU {n}, classic variant frame 0 (orientation)";')
        comments.append(f'CM_ BO_ {fd_id} "IMU {n}, CAN FD variant (whole sample in one frame)";')
    out.extend(comments)
    out.append('BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","reserved","reserved","reserved",'
               '"reserved","reserved","reserved","reserved","reserved","reserved","reserved","reserved","reserved",'
               '"StandardCAN_FD","ExtendedCAN_FD";')
    out.append('BA_DEF_DEF_ "VFrameFormat" "StandardCAN";')
    for i in fd_ids:
        out.append(f'BA_ "VFrameFormat" BO_ {i} 14;')
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
