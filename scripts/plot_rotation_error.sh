#!/usr/bin/env bash
# Regenerates docs/rotation-error.png ([2] Fig. 3 for shtool's Taylor rotations): builds
# and runs rotation_error_csv, then plots with matplotlib (Debian: python3-matplotlib).
#   scripts/plot_rotation_error.sh [BUILD_DIR] [OUT.png]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
png="${2:-$root/docs/rotation-error.png}"
cmake --build "$build" --target rotation_error_csv -j "$(nproc)"
csv="$(mktemp --suffix=.csv)"
trap 'rm -f "$csv"' EXIT
"$(find "$build" -name rotation_error_csv -type f -perm -u+x | head -n 1)" "$csv"
/usr/bin/python3 "$root/scripts/plot_rotation_error.py" "$csv" "$png"
echo "wrote $png"
