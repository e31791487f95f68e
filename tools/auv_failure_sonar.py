#!/usr/bin/env python3
"""How well the sonar saw the random obstacle an AUV evaluation episode collided with.

Reads the two CSVs of one `pbppo eval --env auv-nav` run (--outcomes and --trajectories, same
blob, layout, episodes and seed) and, for every collision whose nearest obstacle is a random one,
traces the thin sonar beams (BEAMS evenly over 360 degrees from the bow, MAX_RANGE m) against that
obstacle along the trajectory: the surface distance at which a beam first hit it and at which the
last unbroken run of hits up to the collision began, in how many of the last 30 control periods
a beam hit it, and its bearing from the bow at the collision. Thin beams only (written for the
earlier thin-beam auv.yaml; the shipped beams are 22.5 deg wide and see at least what a thin beam on
their axis sees); other obstacles that would shadow the obstacle are ignored.
Usage: tools/auv_failure_sonar.py OUTCOMES.csv TRAJECTORIES.csv [BEAMS=16] [MAX_RANGE=15]
"""
import collections
import csv
import math
import statistics
import sys


def beam_hits(x, y, yaw, circle, beams, max_range):
    cx, cy, r = circle
    for k in range(beams):
        a = yaw + 2 * math.pi * k / beams
        dx, dy = math.cos(a), math.sin(a)
        fx, fy = cx - x, cy - y
        t = fx * dx + fy * dy
        d2 = fx * fx + fy * fy - t * t
        if t > 0 and d2 <= r * r and t - math.sqrt(r * r - d2) <= max_range:
            return True
    return False


def main():
    if len(sys.argv) not in (3, 4, 5):
        sys.exit(__doc__.strip().splitlines()[-1])
    try:
        beams = int(sys.argv[3]) if len(sys.argv) > 3 else 16
        max_range = float(sys.argv[4]) if len(sys.argv) > 4 else 15.0
    except ValueError as e:
        sys.exit(f"auv_failure_sonar: BEAMS / MAX_RANGE: {e}")
    if beams < 1 or not max_range > 0:
        sys.exit(f"auv_failure_sonar: BEAMS {beams} / MAX_RANGE {max_range:g} must be positive")
    for path in sys.argv[1:3]:
        try:
            open(path).close()
        except OSError as e:
            sys.exit(f"auv_failure_sonar: cannot read '{path}': {e.strerror}")
    steps = collections.defaultdict(list)
    with open(sys.argv[2]) as f:
        for r in csv.DictReader(f):
            steps[int(r["episode"])].append((float(r["x_m"]), float(r["y_m"]), float(r["yaw_rad"])))
    first_seen, tracked, visible, bearings = [], [], [], []
    with open(sys.argv[1]) as f:
        for o in csv.DictReader(f):
            if o["outcome"] != "collision" or o["nearest"] != "random":
                continue
            e = int(o["episode"])
            if e not in steps:
                sys.exit(f"episode {e} of {sys.argv[1]} is not in {sys.argv[2]} (not the same eval run?)")
            x, y = float(o["x_m"]), float(o["y_m"])
            circles = [tuple(map(float, c.split(":"))) for c in o["random_obstacles"].split()]
            c = min(circles, key=lambda c: math.hypot(x - c[0], y - c[1]) - c[2])
            # Per control period: the obstacle's surface distance and whether a beam hit it.
            track = [(math.hypot(px - c[0], py - c[1]) - c[2], beam_hits(px, py, yaw, c, beams, max_range))
                     for px, py, yaw in steps[e]]
            first_seen.append(next((d for d, hit in track if hit), None))
            run_start = None
            for d, hit in reversed(track):
                if not hit:
                    break
                run_start = d
            tracked.append(run_start)
            last = track[-30:]
            visible.append(sum(hit for _, hit in last) / len(last))
            px, py, yaw = steps[e][-1]
            b = math.degrees(math.atan2(c[1] - py, c[0] - px) - yaw)
            bearings.append(abs((b + 180) % 360 - 180))
    n = len(first_seen)
    print(f"{n} collisions with a random obstacle ({beams} thin beams, {max_range:g} m)")
    if n == 0:
        return
    never = sum(s is None for s in first_seen)
    seen = [s for s in first_seen if s is not None]
    print(f"  never hit by a beam: {never}; first hit at a surface distance < 3 m: {sum(s < 3 for s in seen)}, "
          f"3-6 m: {sum(3 <= s < 6 for s in seen)}, >= 6 m: {sum(s >= 6 for s in seen)}")
    runs = [t if t is not None else 0.0 for t in tracked]
    print(f"  unbroken run of hits up to the collision began at a surface distance of median {statistics.median(runs):.1f} m"
          f" (< 3 m: {sum(t < 3 for t in runs)}, 3-6 m: {sum(3 <= t < 6 for t in runs)}, >= 6 m: {sum(t >= 6 for t in runs)})")
    print(f"  hit in the last 30 periods (3 s): median {100 * statistics.median(visible):.0f} %, "
          f"all 30 in {sum(v == 1 for v in visible)} collisions")
    print(f"  bearing from the bow at the collision: < 30 deg {sum(b < 30 for b in bearings)}, "
          f"30-60 {sum(30 <= b < 60 for b in bearings)}, 60-90 {sum(60 <= b < 90 for b in bearings)}, "
          f">= 90 {sum(b >= 90 for b in bearings)}")


if __name__ == "__main__":
    main()
