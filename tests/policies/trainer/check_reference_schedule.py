#!/usr/bin/python3
"""pbppo-reference against the released Pb-PPO script's bandit rule, written here from the
script's own definitions as an oracle (no code of ours involved):

    E_i  <- gamma_b * E_i + R          for the arm pulled, N_i <- N_i + 1, N <- N + 1
    U_i   = E_i / (max_j E_j + 0.001)
    wi-ad: U_i <- U_i - mean_j U_j     (one number subtracted from every arm, after dividing)
    arm   = argmax_i U_i + lambda * sqrt(N / (N_i + 1e-6))   (ties: the lowest index)

with lambda 5, gamma_b 0.99, and the script's default variant wo-ad.

1. Synthetic return sequences (rising, negative, crossing zero, a random walk, constant), each of
   at least 400 iterations, replayed open loop through `schedule_replay`: the same arm at every
   iteration and the same exploitation terms, for `pbppo-reference` (no suffix: wo-ad),
   `:wo-ad` and `:wi-ad`.
2. A recorded run: `pbppo train --schedule pbppo-reference` on pendulum for 400 iterations with
   evaluation feedback; the oracle, fed the run's logged feedback, chooses the logged arm at every
   iteration.
3. The sequences tell the computations apart: the order used before (the mean over arms
   subtracted before dividing) chooses differently from the script on some of them.

usage: check_reference_schedule.py SCHEDULE_REPLAY PBPPO WORK_DIR
"""
import csv
import math
import os
import random
import subprocess
import sys

LAMBDA = 5.0
GAMMA = 0.99
ARMS_SPEC = "0.02:0.5:6"
N_ARMS = 6


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def mean(values):
    total = 0.0
    for v in values:
        total += v
    return total / len(values)


class ScriptRule:
    """The released script's rule. old_order: the mean subtracted before dividing (our old wi-ad)."""

    def __init__(self, wi_ad, old_order=False):
        self.wi_ad = wi_ad
        self.old_order = old_order
        self.e = [0.0] * N_ARMS
        self.n_i = [0.0] * N_ARMS
        self.n = 0.0
        self.values = [0.0] * N_ARMS

    def choose(self):
        u = list(self.e)
        if self.old_order and self.wi_ad:
            m = mean(u)
            u = [v - m for v in u]
        denom = max(u) + 0.001
        if denom == 0.0:
            raise ZeroDivisionError("max E + 0.001 == 0: the script divides by zero")
        u = [v / denom for v in u]
        if self.wi_ad and not self.old_order:
            m = mean(u)
            u = [v - m for v in u]
        self.values = u
        best, best_score = 0, None
        for i in range(N_ARMS):
            score = u[i] + LAMBDA * math.sqrt(self.n / (self.n_i[i] + 1e-6))
            if best_score is None or score > best_score:
                best, best_score = i, score
        return best

    def update(self, arm, ret):
        self.e[arm] = GAMMA * self.e[arm] + ret
        self.n_i[arm] += 1.0
        self.n += 1.0


def sequences():
    rng = random.Random(20261127)
    seqs = {}
    seqs["rising"] = [100.0 + 3.0 * t + rng.gauss(0.0, 50.0) for t in range(500)]
    seqs["negative"] = [-500.0 + 0.5 * t + rng.gauss(0.0, 30.0) for t in range(450)]
    seqs["crossing"] = [-300.0 + 1.5 * t + rng.gauss(0.0, 80.0) for t in range(420)]
    walk, x = [], 0.0
    for _ in range(600):
        x += rng.gauss(0.0, 20.0)
        walk.append(x)
    seqs["random_walk"] = walk
    seqs["constant"] = [250.0] * 400
    return seqs


def replay_ours(replay, schedule, path):
    out = subprocess.run([replay, schedule, ARMS_SPEC, path], capture_output=True, text=True)
    if out.returncode != 0:
        fail("%s %s exited with %d: %s" % (replay, schedule, out.returncode, out.stderr.strip()))
    rows = []
    for line in out.stdout.splitlines():
        parts = line.split()
        rows.append((int(parts[0]), [float(v) for v in parts[1:]]))
    return rows


def run_oracle(returns, wi_ad, old_order=False):
    rule = ScriptRule(wi_ad, old_order)
    rows = []
    for r in returns:
        arm = rule.choose()
        rows.append((arm, list(rule.values)))
        rule.update(arm, r)
    return rows


def first_difference(a, b):
    for t, (x, y) in enumerate(zip(a, b)):
        if x[0] != y[0]:
            return t
    return None


def check_synthetic(replay, work):
    diverged = []
    for name, returns in sequences().items():
        path = os.path.join(work, name + ".txt")
        with open(path, "w") as f:
            f.write("".join("%.17g\n" % r for r in returns))
        oracle = {wi_ad: run_oracle(returns, wi_ad) for wi_ad in (False, True)}
        for schedule, wi_ad in (("pbppo-reference", False), ("pbppo-reference:wo-ad", False),
                                ("pbppo-reference:wi-ad", True)):
            ours = replay_ours(replay, schedule, path)
            script = oracle[wi_ad]
            if len(ours) != len(returns):
                fail("%s %s: %d choices for %d returns" % (name, schedule, len(ours), len(returns)))
            t = first_difference(ours, script)
            if t is not None:
                fail("%s %s: iteration %d: ours chose arm %d, the script's rule arm %d"
                     % (name, schedule, t, ours[t][0], script[t][0]))
            for t, ((_, ov), (_, sv)) in enumerate(zip(ours, script)):
                for i in range(N_ARMS):
                    if abs(ov[i] - sv[i]) > 1e-12 * max(1.0, abs(sv[i])):
                        fail("%s %s: iteration %d arm %d: value %.17g, the script's %.17g"
                             % (name, schedule, t, i, ov[i], sv[i]))
            print("%-12s %-22s %d iterations: every choice and value as the script's rule"
                  % (name, schedule, len(returns)))
        t = first_difference(run_oracle(returns, True, old_order=True), oracle[True])
        if t is not None:
            diverged.append((name, t))
    if not diverged:
        fail("no sequence tells the old order (mean before dividing) from the script's rule")
    for name, t in diverged:
        print("the old order (mean subtracted before dividing) leaves the script's choices on %s at iteration %d"
              % (name, t))


def check_recorded(pbppo, work):
    out_dir = os.path.join(work, "run")
    cmd = [pbppo, "train", "--env", "pendulum", "--schedule", "pbppo-reference", "--arms", ARMS_SPEC,
           "--feedback", "eval", "--eval-episodes", "1", "--envs", "1", "--rollout", "32", "--steps",
           str(32 * 400), "--epochs", "1", "--minibatch", "32", "--threads", "1", "--seed", "3",
           "--no-plots", "--quiet", "--out", out_dir]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        fail("%s exited with %d: %s" % (" ".join(cmd), res.returncode, res.stderr.strip()))
    with open(os.path.join(out_dir, "log.csv")) as f:
        rows = list(csv.DictReader(f))
    if len(rows) < 400:
        fail("the recorded run logged %d iterations, not 400" % len(rows))
    rule = ScriptRule(wi_ad=False)
    feedback = []
    counts = [0] * N_ARMS
    for row in rows:
        t = int(row["iteration"])
        arm = rule.choose()
        if int(row["arm"]) != arm:
            fail("recorded run, iteration %d: the trainer chose arm %s, the script's rule arm %d"
                 % (t, row["arm"], arm))
        counts[arm] += 1
        for i in range(N_ARMS):
            logged = float(row["arm%d_value" % i])
            if abs(logged - rule.values[i]) > 1e-5 * max(1.0, abs(rule.values[i])):
                fail("recorded run, iteration %d arm %d: logged value %s, the script's %.9g"
                     % (t, i, row["arm%d_value" % i], rule.values[i]))
        r = float(row["feedback"])
        if not math.isfinite(r):
            fail("recorded run, iteration %d: feedback %s is not finite" % (t, row["feedback"]))
        feedback.append(r)
        rule.update(arm, r)
    print("recorded pendulum run, %d iterations (feedback %.1f .. %.1f): every choice as the script's rule; "
          "pulls per arm %s" % (len(rows), min(feedback), max(feedback), counts))


def main():
    if len(sys.argv) != 4:
        print(__doc__)
        sys.exit(2)
    replay, pbppo, work = sys.argv[1:]
    os.makedirs(work, exist_ok=True)
    check_synthetic(replay, work)
    check_recorded(pbppo, work)
    print("pbppo-reference chooses as the released script, both variants")


if __name__ == "__main__":
    main()
