# Sourced by the test scripts: fail MESSAGE, expect FILE PATTERN (the file is printed when the
# extended regular expression is not found in it), fresh_dir DIR (an empty folder), and
# start_in SRC WORK (WORK emptied, then into SRC: the scripts run from the source tree).
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
