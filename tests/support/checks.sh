# Sourced by the test scripts: fail MESSAGE, expect FILE PATTERN (the file is printed when the
# extended regular expression is not found in it), fresh_dir DIR (an empty folder),
# start_in SRC WORK (WORK emptied, then into SRC: the scripts run from the source tree),
# trace_difference (two runs' CSV traces compared), log_without_timing (a training log.csv
# without its timing column) and dds_domain (a DDS domain no other test holds).
fail() {
  echo "FAIL: $*"
  exit 1
}
expect() {
  grep -Eq -- "$2" "$1" || { cat "$1"; fail "'$2' not found in $1"; }
}
fresh_dir() {
  rm -rf "$1"
  mkdir -p "$1"
}
start_in() {
  fresh_dir "$2"
  cd "$1"
}
# trace_difference NAME_A A.csv NAME_B B.csv X_COL Y_COL: whether two traces of the same run on two
# machines (first column the time, X_COL and Y_COL a position) are identical; else the row where
# they first differ (float rounding) and the largest distance between the two positions.
trace_difference() {
  local na=$1 a=$2 nb=$3 b=$4 x=$5 y=$6 row cols
  if cmp -s "$a" "$b"; then
    echo "   the traces are identical"
    return
  fi
  row=$(cmp "$a" "$b" | sed -n 's/.*line \([0-9]*\).*/\1/p' || true)
  echo "   the traces first differ at $(sed -n "${row}p" "$b" | cut -d, -f1) s (row $row of $(wc -l <"$b")), float rounding:"
  sed -n "${row}p" "$a" | sed "s/^/     $na: /"
  sed -n "${row}p" "$b" | sed "s/^/     $nb: /"
  cols=$(head -1 "$a" | tr ',' '\n' | wc -l)
  paste -d, "$a" "$b" | awk -F, -v x="$x" -v y="$y" -v c="$cols" \
    'NR > 1 {d = sqrt(($x - $(x + c)) ^ 2 + ($y - $(y + c)) ^ 2); if (d > m) m = d}
     END {printf "     the two positions are never more than %.3g m apart\n", m}'
}

# log_without_timing LOG_CSV: a training run's log.csv without its steps_per_second column (what two
# runs of the same training at other speeds have in common).
log_without_timing() {
  /usr/bin/python3 -c 'import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
k = rows[0].index("steps_per_second")
for r in rows: print(",".join(r[:k] + r[k + 1:]))' "$1"
}

# dds_domain: sets `domain` to a DDS domain (10 ... 229) no other test on this machine holds, held
# by a lock on /tmp/pbppo-dds-domain-N.lock until the script and the programs it started end (the
# C++ tests take theirs the same way: tests/support/dds_domain.hpp).
dds_domain() {
  local start=$(($$ % 220)) k d
  for ((k = 0; k < 220; k++)); do
    d=$((10 + (start + k) % 220))
    exec {dds_domain_fd}>"/tmp/pbppo-dds-domain-$d.lock"
    if flock -n "$dds_domain_fd"; then
      domain=$d
      return
    fi
    exec {dds_domain_fd}>&-
  done
  fail "no free DDS domain (all 220 held)"
}
