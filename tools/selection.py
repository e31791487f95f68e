"""The choice among a training run's candidate blobs, written the same way by tools/select_auv.sh and
tools/select_quadruped.sh: RUN/select.csv (one row per candidate, the union of the rows' columns,
and `selected`), then the chosen blob and its golden vectors as RUN/selected.blob and .golden. Each
file is written beside its place and renamed into it, so that a stopped run leaves no half file."""
import csv
import os
import shutil


def write_choice(run, rows, best, candidates):
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    tmp = os.path.join(run, "select.csv.tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields + ["selected"])
        w.writeheader()
        for i, r in enumerate(rows):
            w.writerow(dict(r, selected=int(i == best)))
    os.replace(tmp, os.path.join(run, "select.csv"))
    src = candidates[best]
    for ext in (".blob", ".golden"):
        tmp = os.path.join(run, "selected" + ext + ".tmp")
        shutil.copyfile(src[: -len(".blob")] + ext, tmp)
        os.replace(tmp, os.path.join(run, "selected" + ext))
