#!/usr/bin/env bash
# The onnx.models fixture (label onnx): the ONNX test models and their mapping files, built by
# tools/onnx/make_models.py from the shipped blobs' weights (pbppo inspect --json --weights).
# usage: make_models.sh PBPPO SOURCE_DIR OUT_DIR
set -euo pipefail
pbppo=$1 src=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
"$pbppo" inspect --json --weights "$src/policies/frozen/quadruped_walk/flat.blob" >"$out/flat.json"
"$pbppo" inspect --json --weights "$src/policies/frozen/auv_nav/auv_nav.blob" >"$out/auv.json"
# Debian's python3 (python3-onnx, python3-numpy), whatever python3 comes first on PATH.
/usr/bin/python3 "$src/tools/onnx/make_models.py" "$out" --flat-json "$out/flat.json" --auv-json "$out/auv.json"
ls "$out" "$out/bad"
