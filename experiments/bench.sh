#!/usr/bin/env bash
# make bench: the benchmark tables of the issues' closing notes, with bin/trace.
# Prints CSV lines (see `bin/trace --csv`) into build/bench/*.csv and a summary.
# Also shows that counters cost nothing when off: the same trace from a build
# with -DACCEL_COUNTERS=0 (no counter code at all) beside the normal build.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/bench; mkdir -p "$out"
shared=../shared/scenes
bunny=$shared/bunny.off
T="bin/trace --csv --size 512x512 --repeat 5"
# One header per file (one schema): later runs append their records only.
append() { local f=$1; if [ -s "$f" ]; then tail -n +2 | tee -a "$f"; else tee -a "$f"; fi; }
run() { local name=$1; shift; echo "== $name: $*" >&2; $T "$@" | append "$out/$name.csv"; }
rm -f "$out"/*.csv

# Grid (issue 3): build speed, bytes/triangle, primary and diffuse Mrays/s.
for sc in soup:tris=1000000 teapot_stadium ${bunny:+$bunny}; do
  [ -e "$sc" ] || [[ "$sc" != *.off ]] || continue
  run grid --scene "$sc" --accel grid --rays primary,diffuse
done
run grid_brute --scene "$bunny" --accel brute --rays primary --size 64x64 --repeat 1 || true

# Nested grid (issue 4).
for sc in teapot_stadium sphereflake "$bunny"; do
  run nested --scene "$sc" --accel nested_grid --accel nested_grid:auto --accel grid --rays primary,diffuse
done

# BVH (issue 5): builders, ray sets, packets, threads.
for sc in "$bunny" soup:tris=1000000 teapot_stadium sphereflake; do
  run bvh --scene "$sc" --accel bvh:build=mid --accel bvh:build=median --accel bvh:build=sah \
      --accel bvh:build=binned --accel bvh:build=binned,axes=1 --rays primary,shadow,diffuse
  run packets --scene "$sc" --accel bvh --accel bvh:traverse=packet --accel bvh:traverse=packet,frustum=1 \
      --rays primary,shadow,diffuse
  run threads --scene "$sc" --accel bvh --rays primary,diffuse --threads 2
done

# Counters off: a build without any counter code against the normal build.
make -s BUILD=build-nocount BIN=bin-nocount CFLAGS="-O3 -march=x86-64-v3 -g -DACCEL_COUNTERS=0" bin-nocount/trace
for k in grid bvh nested_grid; do
  for b in bin bin-nocount; do
    echo "== counters $b $k" >&2
    $b/trace --csv --scene "$bunny" --accel $k --rays primary,diffuse --repeat 9 --no-counters \
      | sed "s/^csv,/csv-$b,/" | append "$out/counters.csv"
  done
done
echo "bench: CSV in $out/" >&2
