#!/usr/bin/env bash
# The convert benchmark of issue 2, against trimesh in the same run:
#   1,310,720-triangle binary STL (icosphere, 30% of faces flipped) -> binary PLY, weld + orient.
# Installs trimesh into tools/.venv (benchmarks only; the tests never need it).
# Extra arguments go to `drapekit bench convert` (e.g. --runs 9, --json).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x tools/.venv/bin/python ]; then
  python3 -m venv tools/.venv
  tools/.venv/bin/pip install --quiet trimesh numpy scipy networkx
fi
cargo build --release --quiet
exec target/release/drapekit bench convert --trimesh tools/.venv/bin/python "$@"
