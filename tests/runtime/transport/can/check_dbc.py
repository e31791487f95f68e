#!/usr/bin/python3
"""Keeps models/<robot>/<robot>.dbc in step with the C++ codecs: decodes, with Debian's
python3-canmatrix, every frame that can_vectors (the C++ encoders) wrote, and compares each signal
with the value the C++ decoder read from the same bytes. Also checks that every message the map
implies is in the DBC with the right identifier and length, and that the FD variant is marked FD.

usage: check_dbc.py CAN_VECTORS_BINARY CAN_MAP.yaml DBC
"""
import subprocess
import sys

import canmatrix.formats


def main():
    vectors_bin, can_map, dbc = sys.argv[1:4]
    db = canmatrix.formats.loadp_flat(dbc)
    by_name = {f.name: f for f in db.frames}
    out = subprocess.run([vectors_bin, can_map], check=True, capture_output=True, text=True).stdout
    frames = signals = 0
    failures = []
    seen = set()
    for line in out.splitlines():
        kind, name, ident, data, *values = line.split()
        frame = by_name.get(name)
        if frame is None:
            failures.append(f"{name}: no such message in {dbc}")
            continue
        seen.add(name)
        if ident != "-" and frame.arbitration_id.id != int(ident):
            failures.append(f"{name}: DBC id 0x{frame.arbitration_id.id:X}, C++ id 0x{int(ident):X}")
            continue
        payload = bytes.fromhex(data)
        if frame.size != len(payload):
            failures.append(f"{name}: DBC length {frame.size}, C++ frame {len(payload)} bytes")
            continue
        if kind == "IMUFD" and not frame.is_fd:
            failures.append(f"{name}: not marked as a CAN FD frame (VFrameFormat)")
        decoded = frame.decode(payload)
        frames += 1
        for kv in values:
            sig, want = kv.split("=")
            want = float(want)
            if sig not in decoded:
                failures.append(f"{name}: signal {sig} missing from the DBC")
                continue
            s = frame.signal_by_name(sig)
            got = float(decoded[sig].phys_value)
            # Both sides compute raw * factor + offset; allow rounding of the printed factor.
            tol = 1e-9 * max(1.0, abs(float(s.max) - float(s.min)))
            signals += 1
            if abs(got - want) > tol:
                failures.append(f"{name} {data}: {sig} DBC {got!r} C++ {want!r} (raw {decoded[sig].raw_value})")
    missing = sorted(set(by_name) - seen)
    if missing:
        failures.append("DBC messages no C++ frame exercised: " + ", ".join(missing))
    for f in failures[:40]:
        print("MISMATCH", f)
    print(f"check_dbc: {frames} frames, {signals} signals compared, {len(failures)} mismatches")
    return 1 if failures or frames == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
