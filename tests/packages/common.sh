# Sourced by the package tests: make_packages BUILD_DIR OUT_DIR: cpack of a build tree into OUT_DIR
# (its log printed when it fails).
make_packages() {
  cpack --config "$1/CPackConfig.cmake" -B "$2" >"$2.cpack.log" 2>&1 || {
    cat "$2.cpack.log"
    fail "cpack of $1 failed"
  }
}
