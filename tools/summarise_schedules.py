#!/usr/bin/env python3
"""Summarises tools/compare_auv_schedules.sh runs: per schedule the mean over seeds with a 95%
Student-t interval of the final training return, the deterministic evaluation's success rate and
return, and the total environment steps; writes a Markdown table and a plot of the training curves
(mean over seeds with a one-sd band, drawn by `pbppo curves`: PBPPO names the binary, default
build/default/policies/pbppo). Usage: summarise_schedules.py RUNS_DIR OUT.md SCHEDULE..."""
import json
import os
import subprocess
import sys

# Two-sided 95% quantiles of Student's t by degrees of freedom.
from seed_stats import fmt, mean_ci


def main():
    runs, out_md, schedules = sys.argv[1], sys.argv[2], sys.argv[3:]
    rows, groups = [], []
    reward = "the paper's reward"  # from the runs' summaries
    for s in schedules:
        tag = s.replace(":", "_")
        dirs = sorted(d for d in os.listdir(runs) if d.startswith(tag + "_seed") and
                      os.path.isfile(os.path.join(runs, d, "eval.json")))
        if not dirs:
            continue
        fin, succ, evret, steps, tsucc, seeds = [], [], [], [], [], []
        for d in dirs:
            summ = json.load(open(os.path.join(runs, d, "summary.json")))
            if summ.get("progress") == "geodesic":
                reward = "geodesic progress" + (", margin %s" % summ["geodesic_margin"]
                                                if summ.get("geodesic_margin") else "")
            ev = json.load(open(os.path.join(runs, d, "eval.json")))
            fin.append(summ["final_return_last100"])
            tsucc.append(100 * summ.get("task_success_100", float("nan")))
            succ.append(100 * ev["success_rate"])
            evret.append(ev["mean_return"])
            steps.append(summ["env_steps"] + summ["eval_steps"])
            seeds.append(str(summ["seed"]))
        groups.append("%s=%s" % (s, ",".join(os.path.join(runs, d) for d in dirs)))
        rows.append((s, len(dirs), ",".join(seeds), mean_ci(fin), mean_ci(tsucc), mean_ci(succ), mean_ci(evret),
                     min(steps), max(steps), succ))
    os.makedirs(os.path.dirname(out_md), exist_ok=True)
    base = os.path.splitext(out_md)[0]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    pbppo = os.environ.get("PBPPO", os.path.join(root, "build", "default", "policies", "pbppo"))
    try:
        subprocess.run([pbppo, "curves", "--out", base + ".png", "--title", "auv-nav hard: training return by clip "
                        "schedule (mean over seeds, one-sd band)", "--ylabel", "training return (last 100 episodes)"]
                       + groups, check=True, capture_output=True)
        plot_note = "![training curves](%s.png)\n" % os.path.basename(base)
    except (OSError, subprocess.CalledProcessError) as e:
        plot_note = "(plot failed: %s)\n" % e
    with open(out_md, "w") as f:
        f.write("# Clip schedules on auv-nav, hard layout\n\n")
        f.write("Produced by `tools/compare_auv_schedules.sh` (do not edit by hand). Same PPO settings for every run "
                "(16 envs x 256 steps, minibatch 512, 10 epochs, lr 3e-4, gamma 0.99, GAE 0.95, 64-64 tanh, "
                "observation normalisation and reward scaling, %s, the observation of `models/auv/io_layout.yaml`); "
                "bandit arms `0.05:0.4:6` with `rollout` feedback, so every run uses the same total environment steps (no evaluation steps). Evaluation after "
                "training: 100 deterministic hard episodes from seed 900001 (no training seed). Values are means "
                "over seeds ± the half-width of the 95%% Student-t interval.\n\n" % reward)
        f.write("| schedule | seeds | total env steps | final training return (last 100 ep.) | training success "
                "(last 100 ep.) % | eval success % | eval return | eval success per seed % |\n")
        f.write("| --- | --- | --- | --- | --- | --- | --- | --- |\n")
        for (s, n, seeds, fin, ts, su, er, lo, hi, per) in rows:
            st = "%d" % lo if lo == hi else "%d-%d" % (lo, hi)
            f.write("| `%s` | %d (%s) | %s | %s | %s | %s | %s | %s |\n" % (
                s, n, seeds, st, fmt(fin, 1), fmt(ts, 1), fmt(su, 1), fmt(er, 1), ", ".join("%.0f" % x for x in per)))
        f.write("\n" + plot_note)
    print(open(out_md).read())


if __name__ == "__main__":
    main()
