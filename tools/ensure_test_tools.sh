#!/usr/bin/env bash
# Installs the third-party checkers the glTF tests run, into DIR (default: target/test-tools):
#   DIR/node_modules/gltf-validator   the Khronos glTF validator (npm)
#   DIR/venv                          Python with trimesh and numpy (PyPI)
# Pinned versions; a second run with both present does nothing. Concurrent runs wait on a lock.
# Usage: tools/ensure_test_tools.sh [DIR]; exit status 0 when both are ready.
set -euo pipefail
VALIDATOR_VERSION="2.0.0-dev.3.10"
TRIMESH_VERSION="5.2.0"
NUMPY_VERSION="2.4.6"
dir="${1:-$(dirname "$0")/../target/test-tools}"
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
exec 9>"$dir/.lock"
flock 9
stamp="$dir/.installed-$VALIDATOR_VERSION-$TRIMESH_VERSION-$NUMPY_VERSION"
if [ -f "$stamp" ]; then
    exit 0
fi
if [ ! -f "$dir/node_modules/gltf-validator/package.json" ] ||
    ! grep -q "\"version\": \"$VALIDATOR_VERSION\"" "$dir/node_modules/gltf-validator/package.json"; then
    npm install --prefix "$dir" --no-audit --no-fund --silent "gltf-validator@$VALIDATOR_VERSION" >&2
fi
if [ ! -x "$dir/venv/bin/python" ]; then
    python3 -m venv "$dir/venv"
fi
"$dir/venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    "trimesh==$TRIMESH_VERSION" "numpy==$NUMPY_VERSION" >&2
touch "$stamp"
