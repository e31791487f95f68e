#!/usr/bin/env python3
"""Writes the MuJoCo table (tools/mujoco_table.sh) from a `pbppo sweep` folder: per task and clip
schedule the final policies' deterministic evaluation return, mean over seeds with its 95 % Student-t
interval, beside the paper's Table 1; whether each fixed-bound row agrees with the paper's; the
environment steps spent on training and on the bandit's evaluations; learning curves with bands and
the clip bound the bandit chose over time (PNG, drawn by `pbppo curves`: PBPPO names the binary,
default build/default/policies/pbppo); and how often each arm was chosen, by quarter of the run.
Usage: summarise_mujoco_table.py SWEEP_DIR... OUT.md (the runs of every folder together; runs of the ant
with --contact-forces zero get a section of their own)"""
import csv
import json
import math
import os
import subprocess
import sys

from seed_stats import mean_ci

TASKS = ["hopper", "walker2d", "half-cheetah", "ant"]
NAMES = {"hopper": "Hopper", "walker2d": "Walker2d", "half-cheetah": "HalfCheetah", "ant": "Ant"}
# The paper's Table 1 (mean final return over seeds at 10^6 steps; Pb-PPO with its spread).
PAPER = {
    "ant": {"fixed:0.02": 1686, "fixed:0.15": 2458, "fixed:0.23": 2458, "pbppo": (3152, 546)},
    "half-cheetah": {"fixed:0.02": 1284, "fixed:0.15": 1608, "fixed:0.23": 1568, "pbppo": (2781, 1188)},
    "hopper": {"fixed:0.02": 2858, "fixed:0.15": 2274, "fixed:0.23": 2327, "pbppo": (3415, 217)},
    "walker2d": {"fixed:0.02": 1887, "fixed:0.15": 2542, "fixed:0.23": 2340, "pbppo": (3913, 699)},
}
FIXED = ["fixed:0.02", "fixed:0.15", "fixed:0.23"]
ORDER = FIXED + ["pbppo-paper:wi-ad", "pbppo-reference", "pbppo"]


def runs(sweeps):
    """Every finished run of the folders: (task, schedule, seed, run folder, result); the ant's runs
    with its contact forces left at zero (--contact-forces zero) go to a second list."""
    out, zero = [], []
    for sweep in sweeps:
        for d, _, files in os.walk(sweep):
            if "result.json" in files:
                r = json.load(open(os.path.join(d, "result.json")))
                row = (r["grid"].get("env"), r["grid"].get("schedule"), r["seed"], d, r)
                (zero if r["grid"].get("contact-forces") == "zero" else out).append(row)
    key = lambda x: (x[0], x[1], x[2])
    return sorted(out, key=key), sorted(zero, key=key)


def evaluation(pbppo, d, r, blob, through):
    """The mean return of BLOB (a path in the run's folder d) on the run's final-evaluation episodes and
    seed, as episodes end or, with through, as the paper's released script measured (every episode 1000
    steps, on through terminations: `pbppo eval --through-ends`); cached beside the blob as
    <blob>.eval.json or <blob>.eval_through_ends.json (the final policy's plain figure is the run's own
    result)."""
    if blob == "policy.blob" and not through:
        return r["final_eval"]["mean_return"]
    stem = "eval" if blob == "policy.blob" else blob + ".eval"  # the final policy's cache keeps its old name
    path = os.path.join(d, stem + ("_through_ends" if through else "") + ".json")
    if not os.path.exists(path):
        args = [pbppo, "eval", os.path.join(d, blob), "--env", r["grid"]["env"],
                "--episodes", str(r["final_eval"]["episodes"]), "--seed", str(r["final_eval"]["seed"]), "--json"]
        if through:
            args.append("--through-ends")
        if r["grid"].get("contact-forces"):
            args += ["--contact-forces", r["grid"]["contact-forces"]]
        out = subprocess.run(args, check=True, stdout=subprocess.PIPE, text=True).stdout
        tmp = path + ".part"
        open(tmp, "w").write(out)
        os.replace(tmp, path)
    return json.load(open(path))["mean_return"]


def through_ends(pbppo, d, r):
    """The run's final policy evaluated as the paper's released script did (evaluation above)."""
    return evaluation(pbppo, d, r, "policy.blob", True)


def cell(xs, p=0):
    if not xs:
        return "–"
    m, h = mean_ci(xs)
    s = "%.*f" % (p, m) + ("" if math.isnan(h) else " ± %.*f" % (p, h))
    return s + (" (n=%d)" % len(xs) if len(xs) != 5 else "")


def arms_by_quarter(log):
    """{epsilon: [share of iterations in each quarter]} from a run's log.csv."""
    rows = list(csv.DictReader(open(log)))
    if not rows:
        return {}
    shares = {}
    n = len(rows)
    for q in range(4):
        part = rows[q * n // 4:(q + 1) * n // 4]
        for r in part:
            e = "%.3f" % float(r["epsilon"])
            shares.setdefault(e, [0.0] * 4)[q] += 1.0 / max(len(part), 1)
    return shares


def arguments(usage, figures):
    """SWEEP_DIR... OUT.md from the command line (else exits with usage): (the sweep folders, OUT.md,
    the pbppo binary: PBPPO or the default build's, the plots' folder FIGURES beside OUT.md, made)."""
    if len(sys.argv) < 3:
        sys.exit(usage)
    sweeps, out_md = sys.argv[1:-1], sys.argv[-1]
    pbppo = os.environ.get("PBPPO", os.path.join(os.path.dirname(__file__), "..", "build/default/policies/pbppo"))
    figdir = os.path.join(os.path.dirname(out_md), figures)
    os.makedirs(figdir, exist_ok=True)
    return sweeps, out_md, pbppo, figdir


def main():
    sweeps, out_md, pbppo, figdir = arguments(__doc__, "mujoco_table")
    all_runs, zero_runs = runs(sweeps)
    by = {}
    for t, s, seed, d, r in all_runs:
        by.setdefault((t, s), []).append((seed, d, r))
    schedules = [s for s in ORDER if any(k[1] == s for k in by)] + sorted(
        {k[1] for k in by if k[1] not in ORDER})
    tasks = [t for t in TASKS if any(k[0] == t for k in by)]
    first = all_runs[0][4]["final_eval"] if all_runs else {}
    eval_episodes, eval_seed = first.get("episodes", "?"), first.get("seed", "?")

    md = ["# The paper's table: Hopper, Walker2d, HalfCheetah and Ant", "",
          "Generated by `tools/mujoco_table.sh` (`pbppo sweep`, then `tools/summarise_mujoco_table.py`) from "
          "%d finished runs. Environments: docs/mujoco_tasks.md. Every run: 10^6 training environment steps "
          "with the paper's PPO settings (one environment, 2048-step rollouts, minibatch 64, 10 epochs, "
          "Adam lr 3e-4, 64-64 tanh, gamma 0.99, GAE lambda 0.95, gradient norm 0.5, no normalisation); "
          "bandit schedules over 6 arms linspace(0.02, 0.5) with 2 deterministic evaluation episodes per "
          "iteration as feedback (counted below, not in the budget). Return: the final policy's mean over "
          "%s deterministic episodes (`pbppo eval`, seed %s), mean over seeds ± the half-width of the "
          "95 %% Student-t interval." % (len(all_runs), eval_episodes, eval_seed), ""]
    md += ["## Returns", "",
           "| task | " + " | ".join(schedules) + " |", "| --- |" + " ---: |" * len(schedules)]
    for t in tasks:
        row = []
        for s in schedules:
            row.append(cell([r["final_eval"]["mean_return"] for _, _, r in by.get((t, s), [])]))
        md.append("| %s | %s |" % (NAMES[t], " | ".join(row)))
    md += ["", "The paper's Table 1 (mean over seeds; Pb-PPO ± its spread):", "",
           "| task | PPO ε=0.02 | PPO ε=0.15 | PPO ε=0.23 | Pb-PPO |", "| --- | ---: | ---: | ---: | ---: |"]
    for t in TASKS:
        p = PAPER[t]
        md.append("| %s | %d | %d | %d | %d ± %d |" % (NAMES[t], p["fixed:0.02"], p["fixed:0.15"], p["fixed:0.23"],
                                                   p["pbppo"][0], p["pbppo"][1]))

    md += ["", "## Fixed bounds against the paper", "",
           "The paper gives no spread for its PPO rows, so a row agrees when the paper's mean lies within our "
           "seeds' range (min to max) and is counted as close when it lies within our 95 % interval.", "",
           "| task | bound | ours: mean [min, max] | paper | within our range | within our interval |",
           "| --- | --- | --- | ---: | --- | --- |"]
    agree = {}
    for t in tasks:
        for s in FIXED:
            xs = [r["final_eval"]["mean_return"] for _, _, r in by.get((t, s), [])]
            if not xs:
                continue
            m, h = mean_ci(xs)
            paper = PAPER[t][s]
            in_range = min(xs) <= paper <= max(xs)
            in_ci = not math.isnan(h) and abs(paper - m) <= h
            agree.setdefault(t, []).append(in_range)
            md.append("| %s | %s | %.0f [%.0f, %.0f] | %d | %s | %s |" % (
                NAMES[t], s[6:], m, min(xs), max(xs), paper, "yes" if in_range else "no", "yes" if in_ci else "no"))
    tasks_ok = sum(1 for t in agree if all(agree[t]))
    md += ["", "Tasks whose three fixed-bound rows all agree: %d of %d measured." % (tasks_ok, len(agree))]
    if zero_runs:
        zby, zte = {}, {}
        for t, s_, _, d, r in zero_runs:
            zby.setdefault(s_, []).append(r["final_eval"]["mean_return"])
            zte.setdefault(s_, []).append(through_ends(pbppo, d, r))
        md += ["", "### Ant with its contact forces left at zero", "",
               "The paper's software ran the ant on mujoco-py with MuJoCo 2.x, which never computed the external "
               "contact forces: 84 of the 111 observations were always 0 and the contact cost was 0. "
               "`--contact-forces zero` runs the ant that way (docs/mujoco_tasks.md); the same fixed bounds, "
               "seeds and settings (%d runs):" % len(zero_runs), "",
               "| bound | contact forces computed: mean [min, max] | left at zero | left at zero, evaluated through "
               "episode ends (the paper's software in both) | paper | paper within the last two ranges |",
               "| --- | --- | --- | --- | ---: | --- |"]
        for s_ in FIXED:
            xs = zby.get(s_, [])
            ys = [r["final_eval"]["mean_return"] for _, _, r in by.get(("ant", s_), [])]
            if not xs:
                continue
            paper = PAPER["ant"][s_]
            fmt = lambda v: "%s [%.0f, %.0f]" % (cell(v), min(v), max(v)) if v else "–"
            zs = zte.get(s_, [])
            inside = lambda v: "yes" if v and min(v) <= paper <= max(v) else "no"
            md.append("| %s | %s | %s | %s | %d | %s, %s |" % (s_[6:], fmt(ys), fmt(xs), fmt(zs), paper, inside(xs),
                                                              inside(zs)))

    md += ["", "## Returns as the paper's script measured them", "",
           "The released script evaluates a policy for 1000 deterministic steps and ignores episode ends; the "
           "v3 tasks keep paying the healthy reward after a termination. The same final policies, seeds and "
           "episodes evaluated that way (`pbppo eval --through-ends`):", "",
           "| task | " + " | ".join(schedules) + " |", "| --- |" + " ---: |" * len(schedules)]
    agree_te = {}
    for t in tasks:
        row = []
        for s in schedules:
            xs = [through_ends(pbppo, d, r) for _, d, r in by.get((t, s), [])]
            row.append(cell(xs))
            if s in FIXED and xs:
                agree_te.setdefault(t, []).append(min(xs) <= PAPER[t][s] <= max(xs))
        md.append("| %s | %s |" % (NAMES[t], " | ".join(row)))
    md += ["", "Read this way, tasks whose three fixed-bound rows all hold the paper's figure within our seeds' "
           "range: %d of %d (%s)." % (sum(1 for t in agree_te if all(agree_te[t])), len(agree_te),
                                      ", ".join("%s %d/3" % (NAMES[t], sum(agree_te[t])) for t in agree_te))]

    md += ["", "## Steps and time", "",
           "| task | schedule | training steps | bandit evaluation steps | wall s per run |",
           "| --- | --- | ---: | ---: | ---: |"]
    for t in tasks:
        for s in schedules:
            rs = [r for _, _, r in by.get((t, s), [])]
            if rs:
                md.append("| %s | %s | %.0f | %.0f | %.0f |" % (
                    NAMES[t], s, sum(r["train"]["env_steps"] for r in rs) / len(rs),
                    sum(r["train"]["eval_steps"] for r in rs) / len(rs),
                    sum(r["train"]["wall_seconds"] for r in rs) / len(rs)))

    total = sum(r["train"]["wall_seconds"] for _, _, _, _, r in all_runs)
    md += ["", "Training wall time of the %d runs (each on one core): %.0f s, %.1f hours of 2 cores running two at "
           "a time (times measured while the machine also did other work are longer than alone)."
           % (len(all_runs), total, total / 2 / 3600)]
    md += ["", "## Learning curves and the bandit's choices", ""]
    for t in tasks:
        groups = ["%s=%s" % (s, ",".join(d for _, d, _ in by[(t, s)])) for s in schedules if (t, s) in by]
        png = os.path.join(figdir, "%s_return.png" % t)
        subprocess.run([pbppo, "curves", *groups, "--out", png, "--title", "%s: training return (mean of seeds, band)" % NAMES[t]],
                       check=True, stdout=subprocess.DEVNULL)
        md.append("![%s](mujoco_table/%s)" % (NAMES[t], os.path.basename(png)))
        bandit = ["%s=%s" % (s, ",".join(d for _, d, _ in by[(t, s)])) for s in schedules
                  if (t, s) in by and not s.startswith("fixed")]
        if bandit:
            png = os.path.join(figdir, "%s_epsilon.png" % t)
            subprocess.run([pbppo, "curves", *bandit, "--out", png, "--column", "epsilon", "--ylabel", "clip bound",
                            "--title", "%s: the clip bound chosen (mean of seeds, band)" % NAMES[t]],
                           check=True, stdout=subprocess.DEVNULL)
            md.append("![%s clip bound](mujoco_table/%s)" % (NAMES[t], os.path.basename(png)))
        md.append("")
    md += ["Share of iterations that chose each arm, by quarter of the run (all seeds):", "",
           "| task | schedule | arm | 1st | 2nd | 3rd | 4th quarter |", "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    for t in tasks:
        for s in schedules:
            if s.startswith("fixed") or (t, s) not in by:
                continue
            total = {}
            runs_here = by[(t, s)]
            for _, d, _ in runs_here:
                for e, q in arms_by_quarter(os.path.join(d, "log.csv")).items():
                    acc = total.setdefault(e, [0.0] * 4)
                    for i in range(4):
                        acc[i] += q[i] / len(runs_here)
            for e in sorted(total, key=float):
                md.append("| %s | %s | %s | %s |" % (NAMES[t], s, e, " | ".join("%.0f %%" % (100 * v) for v in total[e])))
    for f in os.listdir(figdir):  # the drawing's gnuplot script and log: not results
        if f.endswith((".gp", ".log")):
            os.remove(os.path.join(figdir, f))
    open(out_md + ".part", "w").write("\n".join(md) + "\n")
    os.replace(out_md + ".part", out_md)  # never a half-written report
    print("wrote %s (%d runs) and %s/" % (out_md, len(all_runs), figdir))


if __name__ == "__main__":
    main()
