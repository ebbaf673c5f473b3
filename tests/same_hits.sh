#!/bin/sh
# same_hits.sh - are two builds' answers bit for bit the same?
#
#   tests/same_hits.sh OLD_BIN NEW_BIN [WORKDIR]
#
# Traces every kind in its main modes on the built-in scenes (small sizes)
# and the scanned meshes of ../shared/scenes with OLD_BIN/trace and
# NEW_BIN/trace, dumps the closest hits of the primary and diffuse rays
# (FORMATS.md .hits) and compares the files byte for byte. For reshaping
# commits that must not change behaviour: build the commit before into one
# bin folder (make BIN=bin-old BUILD=build-old after a checkout), the new
# one into bin/, run this. Prints one line per difference and a final
# `N same, N differ`; exits 1 when anything differs or fails.
set -u
old=${1:?usage: same_hits.sh OLD_BIN NEW_BIN [WORKDIR]}
new=${2:?usage: same_hits.sh OLD_BIN NEW_BIN [WORKDIR]}
dir=${3:-$(mktemp -d)}
mkdir -p "$dir"
here=$(dirname "$0")/..

specs="brute bvh bvh:build=sah bvh:build=median,term=none,leaf=4 bvh:build=sbvh
bvh:traverse=packet bvh:traverse=packet,frustum=1 bvh:first=left bvh:pairs=split
bvh:width=4 bvh:width=8 bvh:width=4,order=dist bvh:width=8,order=branchy bvh:width=8,quant=1
bvh:width=4,traverse=packet bvh:width=8,traverse=packet bvh:width=8,block=4
bvh:width=8,collapse=greedy bvh:width=8,traverse=packet,hybrid=0
grid grid:mailbox=0 grid:overlap=bbox grid:skip=cloud grid:skip=macro grid:traverse=packet
grid:tri=naive nested_grid nested_grid:auto nested_grid:layout=compact nested_grid:traverse=packet
nested_grid:traverse=packet,layout=compact irregular_grid irregular_grid:mailbox=0
irregular_grid:subdivide=0,merge=0,expand=0 instanced instanced:top=grid
instanced:bottom=grid instanced:top=grid,bottom=nested_grid instanced:bottom=bvh:width=8"
scenes="cube:n=8 sphere:segments=12 sphereflake:level=2 sphereflake:level=2,spheres=0 tetra:level=5
mount:level=4 soup:tris=20000 teapot_stadium:n=4,stadium=32,tiers=4 slivers:tris=5000,slivers=100
field:instances=20,detail=2 animated:instances=6,detail=2,frame=7"
for f in "$here"/../shared/scenes/*.off; do [ -f "$f" ] && scenes="$scenes $f"; done

same=0
differ=0
for scene in $scenes; do
    case $scene in *.off) size=160x120 ;; *) size=96x72 ;; esac
    # Both builds trace the old build's default view of the scene, given
    # explicitly, so that a change of default camera is not a change of hits.
    cam=$("$old/trace" --scene "$scene" --accel brute --size 8x6 --repeat 1 --warmup 0 \
          --build-repeat 1 --no-counters --quiet 2>/dev/null |
          sed -n 's/^ *camera eye (\([^)]*\)) look (\([^)]*\)) up (\([^)]*\)) fov \([^ ]*\) deg.*/--eye \1 --look \2 --up \3 --fov \4/p' |
          tr -d ' ' | sed 's/--/ --/g; s/\(--[a-z]*\)/\1 /g')
    for spec in $specs; do
        tag=$(printf '%s__%s' "$(basename "$scene")" "$spec" | tr ':,=/' '____')
        for side in old new; do
            eval bin=\$$side
            # shellcheck disable=SC2086
            "$bin/trace" --scene "$scene" --accel "$spec" --rays primary,diffuse --size $size $cam \
                --repeat 1 --warmup 0 --build-repeat 1 --no-counters --quiet \
                --dump-hits "$dir/$tag.$side" > "$dir/$tag.$side.log" 2>&1 ||
                echo "FAILED ($side): $scene $spec (see $dir/$tag.$side.log)"
        done
        for set in primary diffuse; do
            if cmp -s "$dir/$tag.old.$set.hits" "$dir/$tag.new.$set.hits" &&
               [ -s "$dir/$tag.old.$set.hits" ]; then
                same=$((same + 1))
            else
                differ=$((differ + 1))
                echo "DIFFER: $scene $spec $set"
            fi
        done
    done
done
echo "$same same, $differ differ"
[ "$differ" -eq 0 ]
