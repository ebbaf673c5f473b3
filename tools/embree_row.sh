#!/usr/bin/env bash
# One industrial reference number for the report (issue 39): Embree 3's
# Mrays/s on the triangles of OBJ and the rays of RAYS (FORMATS.md), MODE
# closest or occluded, printed as one line "mrays=<x>". bin/embree_ref is
# built only by `make embree` (needs libembree-dev); without it this prints
# nothing and exits 1, and the report says "not measured here".
# Usage: tools/embree_row.sh OBJ RAYS MODE
# bin/embree_ref prints one key=value line (tools/embree_ref.c); its
# median over --passes passes after a warm-up is the number taken here.
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 OBJ RAYS closest|occluded" >&2; exit 2; }
cd "$(dirname "$0")/.."
[ -x bin/embree_ref ] || exit 1
case "$3" in
  closest) mode=single ;;
  occluded) mode=occluded ;;
  *) echo "embree_row.sh: mode $3: closest or occluded" >&2; exit 2 ;;
esac
out=$(bin/embree_ref --obj "$1" --rays "$2" --mode "$mode" --passes "${EMBREE_PASSES:-5}")
x=$(printf '%s\n' "$out" | sed -n -e 's/.* mrays=\([0-9.eE+-]*\).*/\1/p' | head -1)
[ -n "$x" ] || { echo "embree_row.sh: no Mrays/s in: $out" >&2; exit 1; }
echo "mrays=$x"
