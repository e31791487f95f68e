#!/usr/bin/python3
"""Decodes the MIT command frames of a stand run's candump log (candump -L format, written by the
controller) with Debian's python3-canmatrix through models/quadruped/quadruped.dbc, and compares
each decoded signal with the value the controller meant to send (its command record), in order,
per joint. A decoded value may differ from the intended one by at most half a quantisation step
(the DBC factor / 2): the encoder rounds to nearest.

usage: check_stand_dbc.py CANDUMP_LOG COMMAND_RECORDS DBC
COMMAND_RECORDS: one line per command, "tick joint q dq kp kd tau".
"""
import collections
import re
import sys

import canmatrix.formats

LINE = re.compile(r"^\((\d+\.\d+)\) (\S+) ([0-9A-Fa-f]+)#([0-9A-Fa-f]*)$")
SPECIAL = ("fffffffffffffffc", "fffffffffffffffd", "fffffffffffffffe")


def main():
    log, records, dbc = sys.argv[1:4]
    db = canmatrix.formats.loadp_flat(dbc)
    cmd_by_id = {f.arbitration_id.id: f for f in db.frames if f.name.startswith("CMD_")}
    decoded = collections.defaultdict(list)
    for line in open(log):
        m = LINE.match(line.strip())
        if not m:
            continue  # FD frames (##), error frames and others are not commands
        ident, data = int(m.group(3), 16), m.group(4).lower()
        frame = cmd_by_id.get(ident)
        if frame is None or len(data) != 16 or data in SPECIAL:
            continue
        values = frame.decode(bytes.fromhex(data))
        decoded[frame.name[4:]].append({k: (float(v.phys_value), frame.signal_by_name(k)) for k, v in values.items()})
    sent = collections.defaultdict(list)
    for line in open(records):
        tick, joint, q, dq, kp, kd, tau = line.split()
        sent[joint].append({"p_des": float(q), "v_des": float(dq), "kp": float(kp), "kd": float(kd), "t_ff": float(tau)})
    failures, compared = [], 0
    for joint, rows in sent.items():
        got = decoded.get(joint, [])
        if len(got) != len(rows):
            failures.append(f"{joint}: {len(rows)} commands recorded, {len(got)} CMD frames in the log")
            continue
        for i, (want, have) in enumerate(zip(rows, got)):
            for sig, value in want.items():
                phys, s = have[sig]
                compared += 1
                if abs(phys - value) > float(s.factor) / 2 + 1e-9:
                    failures.append(f"{joint} command {i}: {sig} decoded {phys!r}, sent {value!r}")
    for f in failures[:20]:
        print("MISMATCH", f)
    print(f"check_stand_dbc: {sum(len(v) for v in decoded.values())} command frames decoded with the DBC, "
          f"{compared} signals compared, {len(failures)} mismatches")
    return 1 if failures or compared == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
