#!/usr/bin/python3
"""candump compatibility: can_vectors writes every frame of the CAN map through CandumpLogger;
Debian's python-can (can.CanutilsLogReader, an independent parser of the candump -L format) must
read back the same identifiers, payloads, FD flags and increasing timestamps.

usage: check_candump.py CAN_VECTORS_BINARY CAN_MAP.yaml OUT_LOG
"""
import subprocess
import sys

import can


def main():
    vectors_bin, can_map, log = sys.argv[1:4]
    out = subprocess.run([vectors_bin, can_map, log], check=True, capture_output=True, text=True).stdout
    expected = []
    for line in out.splitlines():
        kind, name, ident, data, *_ = line.split()
        expected.append((kind, name, None if ident == "-" else int(ident), bytes.fromhex(data)))
    got = list(can.CanutilsLogReader(log))
    failures = []
    if len(got) != len(expected):
        failures.append(f"{len(got)} messages in the log, {len(expected)} frames written")
    last_t = -1.0
    for (kind, name, ident, data), m in zip(expected, got):
        if ident is not None and m.arbitration_id != ident:
            failures.append(f"{name}: id 0x{m.arbitration_id:X} in the log, 0x{ident:X} written")
        if bytes(m.data) != data:
            failures.append(f"{name}: data {bytes(m.data).hex()} in the log, {data.hex()} written")
        if m.is_fd != (kind == "IMUFD"):
            failures.append(f"{name}: is_fd {m.is_fd}")
        if m.is_extended_id or m.is_error_frame or m.channel != "vcan0":
            failures.append(f"{name}: extended {m.is_extended_id} error {m.is_error_frame} channel {m.channel}")
        if not m.timestamp > last_t:
            failures.append(f"{name}: timestamp {m.timestamp} not increasing")
        last_t = m.timestamp
    for f in failures[:40]:
        print("MISMATCH", f)
    print(f"check_candump: {len(got)} messages read by python-can {can.__version__}, {len(failures)} mismatches")
    return 1 if failures or not got else 0


if __name__ == "__main__":
    sys.exit(main())
