#!/usr/bin/python3
"""Writes the quadruped's gamepad sessions (models/quadruped_gamepad/sessions/): the events an
Xbox-style pad gives through Linux evdev, as reading /dev/input/eventN returns them on a 64-bit
machine (24-byte records: s64 seconds, s64 microseconds, u16 type, u16 code, s32 value,
little-endian).

  demo    a person stands the robot up, walks it, lets go of the dead-man, walks again, presses
          the e-stop (the robot sinks, damped), re-arms (passive), stands it up and walks until
          the pad is unplugged
  switch  stands up, walks, switches to the next policy (RB) while walking, then back
  sit     stands up, walks, sits down (R3) from the walk, is passive, stands up again from the
          ground (START), walks, stands, sits and shuts down (B) from passive

  /usr/bin/python3 tools/gamepad_session.py demo models/quadruped_gamepad/sessions/demo.ev

pbppo-hil plays it (--gamepad FILE) on the controller's tick clock; tests/sim_hil/test_gamepad_hil.cpp
checks each step at the times below.
"""
import math
import struct
import sys

EV_SYN, EV_KEY, EV_ABS, EV_MSC = 0, 1, 3, 4
SYN_REPORT, MSC_SCAN = 0, 4
ABS_X, ABS_Y, ABS_RX = 0, 1, 3
BTN_SOUTH, BTN_EAST, BTN_TL, BTN_TR, BTN_SELECT, BTN_START, BTN_MODE = 0x130, 0x131, 0x136, 0x137, 0x13A, 0x13B, 0x13C
BTN_THUMBR = 0x13E
EPOCH_US = 1_764_000_000_000_000  # a wall-clock time: the file's times are the kernel's


class Session:
    def __init__(self):
        self.records = []

    def at(self, t_s, type_, code, value):
        us = round(t_s * 1e6) + EPOCH_US
        self.records.append(struct.pack("<qqHHi", us // 1_000_000, us % 1_000_000, type_, code, value))

    def key(self, t, code, down):
        self.at(t, EV_MSC, MSC_SCAN, 0x90001)  # what the pad sends before a key, mapped to nothing
        self.at(t, EV_KEY, code, 1 if down else 0)
        self.at(t, EV_SYN, SYN_REPORT, 0)

    def press(self, t, code):
        self.key(t, code, True)
        self.key(t + 0.1, code, False)

    def forward(self, t, v):
        """The left stick for v m/s forward (models/quadruped_gamepad: dead zone 0.1, scale -1)."""
        n = -(v * 0.9 + 0.1) if v != 0 else 0.0
        raw = (n * 65535 - 1) / 2  # the raw value whose normalised value (2 raw + 1) / 65535 is n
        self.at(t, EV_ABS, ABS_Y, int(math.copysign(math.floor(abs(raw) + 0.5), raw)))  # half away from 0
        self.at(t, EV_SYN, SYN_REPORT, 0)


def demo():
    s = Session()
    s.forward(0.0, 0.0)          # the pad's first report: sticks centred
    s.press(0.2, BTN_START)      # arm: stand up (1 s), hold
    s.key(1.8, BTN_TL, True)     # the dead-man, held
    s.press(1.9, BTN_SOUTH)      # A: walk
    s.forward(2.1, 0.5)          # 0.5 m/s (the pad's rate limit: 1 m/s per s)
    s.forward(7.5, 0.0)
    s.key(8.5, BTN_TL, False)    # the dead-man released: the robot stands
    s.key(10.0, BTN_TL, True)
    s.press(10.1, BTN_SOUTH)     # walk again
    s.forward(10.5, 0.5)
    s.forward(12.0, 0.0)
    s.key(12.5, BTN_TL, False)
    s.press(13.0, BTN_SELECT)    # BACK: e-stop (latched)
    s.press(14.0, BTN_MODE)      # the Xbox button: re-arm (0.5 s healthy since the e-stop): passive
    s.press(14.5, BTN_START)     # stand up from where it lies (1 s), hold
    s.key(16.0, BTN_TL, True)
    s.press(16.1, BTN_SOUTH)
    s.forward(16.5, 0.5)
    s.forward(18.0, 0.5)         # the last report: the pad is unplugged after it, mid-walk
    return s


def switch():
    s = Session()
    s.forward(0.0, 0.0)
    s.press(0.2, BTN_START)      # arm
    s.key(1.8, BTN_TL, True)     # the dead-man, held throughout
    s.press(1.9, BTN_SOUTH)      # walk (the first policy)
    s.forward(2.1, 0.5)
    s.press(5.0, BTN_TR)         # RB: the next policy, blended in over 0.5 s, walking
    s.press(9.0, BTN_TR)         # RB: back to the first
    s.forward(12.0, 0.0)
    s.key(12.5, BTN_TL, False)   # stand
    s.press(14.0, BTN_EAST)      # B: shut down
    return s


def sit():
    s = Session()
    s.forward(0.0, 0.0)
    s.press(0.2, BTN_START)      # arm: stand up, hold
    s.key(1.8, BTN_TL, True)
    s.press(1.9, BTN_SOUTH)      # walk
    s.forward(2.1, 0.5)
    s.forward(5.0, 0.0)
    s.press(6.0, BTN_THUMBR)     # R3 while walking: sit down (1.5 s), then passive
    s.key(6.5, BTN_TL, False)
    s.press(8.5, BTN_SOUTH)      # walk from passive: refused
    s.press(10.0, BTN_START)     # stand up from the ground (1 s), hold
    s.key(11.5, BTN_TL, True)
    s.press(11.6, BTN_SOUTH)     # walk again
    s.forward(11.8, 0.5)
    s.forward(15.0, 0.0)
    s.key(16.0, BTN_TL, False)   # stand
    s.press(17.3, BTN_THUMBR)    # sit down from hold
    s.press(19.5, BTN_EAST)      # B from passive: damping, motors off, done
    return s


SESSIONS = {"demo": demo, "switch": switch, "sit": sit}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in SESSIONS:
        sys.exit("usage: gamepad_session.py demo|switch|sit OUT.ev")
    with open(sys.argv[2] + ".part", "wb") as f:
        f.write(b"".join(SESSIONS[sys.argv[1]]().records))
    import os
    os.replace(sys.argv[2] + ".part", sys.argv[2])
