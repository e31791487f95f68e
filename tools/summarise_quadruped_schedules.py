#!/usr/bin/env python3
"""Summarises tools/compare_quadruped_schedules.sh runs: per clip schedule, the mean over seeds with a
95% Student-t interval of the final training return, the paper's test (mean |error| of vx, vy and the
yaw rate over 50 robots, falls) and the wall time; the training curves (return, vx tracking error)
with one-sd bands (pbppo curves). Usage: summarise_quadruped_schedules.py RUNS_DIR OUT.md SCHEDULE..."""
import json
import os
import subprocess
import sys

from seed_stats import fmt, mean_ci


def main():
    runs, out_md, schedules = sys.argv[1], sys.argv[2], sys.argv[3:]
    rows, groups = [], []
    for s in schedules:
        tag = s.replace(":", "_")
        dirs = sorted(d for d in os.listdir(runs)
                      if d.startswith(tag + "_seed") and os.path.isfile(os.path.join(runs, d, "eval.json")))
        if not dirs:
            continue
        fin, vx, vy, yaw, falls, wall, steps, seeds, per = [], [], [], [], [], [], [], [], []
        for d in dirs:
            summ = json.load(open(os.path.join(runs, d, "summary.json")))
            ev = json.load(open(os.path.join(runs, d, "eval.json")))
            e = ev["mean_abs_error"]
            fin.append(summ["final_return_last100"])
            vx.append(e["vx_mps"])
            vy.append(e["vy_mps"])
            yaw.append(e["yaw_rate_radps"])
            falls.append(ev["falls"])
            wall.append(summ["wall_seconds"] / 60)
            steps.append(summ["env_steps"] + summ["eval_steps"])
            seeds.append(str(summ["seed"]))
            per.append("%.3f/%.3f/%.3f, %d" % (e["vx_mps"], e["vy_mps"], e["yaw_rate_radps"], ev["falls"]))
        groups.append("%s=%s" % (s, ",".join(os.path.join(runs, d) for d in dirs)))
        rows.append((s, len(dirs), ",".join(seeds), min(steps), max(steps), mean_ci(fin), mean_ci(vx), mean_ci(vy),
                     mean_ci(yaw), mean_ci(falls), mean_ci(wall), per))
    os.makedirs(os.path.dirname(out_md), exist_ok=True)
    base = os.path.splitext(out_md)[0]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    pbppo = os.environ.get("PBPPO", os.path.join(root, "build", "default", "policies", "pbppo"))
    notes = []
    for column, suffix, label in (("train_return_100", "", "training return (last 100 episodes)"),
                                  ("tracking_vx_100", "_vx", "mean |vx error| of the last 100 episodes [m/s]")):
        try:
            subprocess.run([pbppo, "curves", "--out", base + suffix + ".png", "--column", column, "--title",
                            "quadruped-walk, flat: %s by clip schedule (mean over seeds, one-sd band)" % label,
                            "--ylabel", label] + groups, check=True, capture_output=True)
            notes.append("![%s](%s%s.png)\n" % (label, os.path.basename(base), suffix))
        except (OSError, subprocess.CalledProcessError) as e:
            notes.append("(plot of %s failed: %s)\n" % (column, e))
    with open(out_md, "w") as f:
        f.write("# Pb-PPO against PPO on quadruped-walk (flat)\n\n")
        f.write("Produced by `tools/compare_quadruped_schedules.sh` (do not edit by hand). Every run uses the shipped "
                "recipe's PPO settings (512 environments x 24 steps, 4 minibatches, 5 epochs, KL-adaptive learning "
                "rate from 1e-3 towards KL 0.01, entropy 0.01, 128-64-32 ELU, privileged critic) and the same "
                "number of environment steps: the bandit (`pbppo`, arms 0.1:0.3:5) takes `rollout` feedback, which "
                "costs no extra steps. The test after training is the paper's: 50 robots x 20 s on flat ground, "
                "commands vx, vy in [-1, 1] m/s and a heading in [-pi, pi] (yaw rate = clip(0.5 heading error, "
                "+-1)), resampled at 10 s, seed 900001. Values are means over seeds ± the half-width of the 95% "
                "Student-t interval; tracking errors in m/s (vx, vy) and rad/s (yaw rate), every step.\n\n")
        f.write("| schedule | seeds | env steps | final training return | test vx | test vy | test yaw rate | "
                "test falls /50 | wall min | per seed (vx/vy/yaw, falls) |\n")
        f.write("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n")
        for (s, n, seeds, lo, hi, fin, vx, vy, yaw, falls, wall, per) in rows:
            st = "%d" % lo if lo == hi else "%d-%d" % (lo, hi)
            f.write("| `%s` | %d (%s) | %s | %s | %s | %s | %s | %s | %s | %s |\n" % (
                s, n, seeds, st, fmt(fin, 2), fmt(vx), fmt(vy), fmt(yaw), fmt(falls, 1), fmt(wall, 1),
                "; ".join(per)))
        f.write("\n" + "\n".join(notes))
    print(open(out_md).read())


if __name__ == "__main__":
    main()
