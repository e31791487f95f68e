# Sourced by the test scripts: fail MESSAGE, and expect FILE PATTERN (the file is printed when the
# extended regular expression is not found in it).
fail() {
  echo "FAIL: $*"
  exit 1
}
expect() {
  grep -Eq -- "$2" "$1" || { cat "$1"; fail "'$2' not found in $1"; }
}
