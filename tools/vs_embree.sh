#!/usr/bin/env bash
# vs_embree.sh - the project's kernels against Embree 3 (bin/embree_ref,
# `make embree`) on the same triangles and the same rays, in interleaved
# fresh processes: ours, Embree, ours, Embree ... (ROUNDS rounds).
#
#   tools/vs_embree.sh SCENE [SPEC ...]
#   MODE=occluded tools/vs_embree.sh ../shared/scenes/bunny.off
#   MODE=packet ROUNDS=1 SIZE=64x48 tools/vs_embree.sh sphereflake:level=1
#
# SCENE is anything bin/trace --scene takes. Once per scene content (in DIR), bin/trace
# writes it as OBJ (--export-obj) and writes the ray sets (--dump-rays):
# SIZE primary rays (default 1024x768, in bin/trace's order: 8x8 tiles) and one diffuse
# and one shadow ray per primary hit. Both tracers then read that OBJ and
# those .rays files, so triangle ids and rays are the same.
#
# MODE (Embree's query, and our default SPEC):
#   single    rtcIntersect1  vs bvh:width=8                  (default)
#   occluded  rtcOccluded1   vs bvh:width=8 --occluded       (any-hit queries)
#   packet    rtcIntersect16 vs bvh:width=8,traverse=packet  (16 consecutive rays)
#   stream    rtcIntersect1M vs bvh:width=8,traverse=stream (ray streams)
#   occluded-stream
#             rtcOccluded1M  vs bvh:width=8,traverse=stream --occluded (any-hit streams;
#             on shadow rays to one light Embree's fastest any-hit mode)
# Other settings: ROUNDS (6), SETS (primary,diffuse,shadow), PASSES (timed
# passes per process, 5, after a warm-up pass), THREADS (1), QUALITY (Embree's
# build quality, medium), DIR (build/vs_embree/<scene>-<hash>-<size>: the
# scene's content hash), BIN (bin), ORDER (the rays' order in
# the files both read: tiles8 as made, or scanline or shuffle: bin/trace's
# --ray-order; DIR then ends in -ORDER),
# FRESH=1 remakes the OBJ and rays, CHECK=0 skips the hit comparison,
# TRACE_OPTS and EMBREE_OPTS add options to every bin/trace or bin/embree_ref
# run (e.g. EMBREE_OPTS="--isa avx2" or "--coherent"). Run it from the top of
# the checkout.
#
# Printed per ray set: the median Mrays/s of each tracer over the rounds,
# each SPEC's ratio to Embree (median over median) with the min-max of the
# per-round ratios, and the ISA each used. Round 1 also writes both tracers'
# hits, compared at the end with `trace compare` (FORMATS.md rules; Embree is
# not watertight, so a few disagreements on edges are expected).
# Timings mean something only on a quiet machine.
set -euo pipefail

usage() { sed -n '2,/^set -euo/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'; exit "${1:-0}"; }
[ $# -ge 1 ] || usage 2
[ "$1" = -h ] || [ "$1" = --help ] && usage 0
scene=$1; shift

BIN=${BIN:-bin}
MODE=${MODE:-single}
ROUNDS=${ROUNDS:-6}
SETS=${SETS:-primary,diffuse,shadow}
PASSES=${PASSES:-5}
THREADS=${THREADS:-1}
SIZE=${SIZE:-1024x768}
QUALITY=${QUALITY:-medium}
CHECK=${CHECK:-1}
read -r -a trace_opts <<< "${TRACE_OPTS:-}"
read -r -a embree_opts <<< "${EMBREE_OPTS:-}"
occl=()
case $MODE in
single) emode=single; defspec=bvh:width=8 ;;
occluded) emode=single; defspec=bvh:width=8; occl=(--occluded) ;;
packet) emode=packet16; defspec=bvh:width=8,traverse=packet ;;
stream) emode=stream; defspec=bvh:width=8,traverse=stream ;;
occluded-stream) emode=stream; defspec=bvh:width=8,traverse=stream; occl=(--occluded) ;;
*) echo "vs_embree: MODE=$MODE: expected single, occluded, packet, stream or occluded-stream" >&2; exit 2 ;;
esac
specs=("$@")
[ ${#specs[@]} -gt 0 ] || specs=("$defspec")
for b in trace embree_ref; do
    [ -x "$BIN/$b" ] || { echo "vs_embree: no $BIN/$b (make${b#trace}; embree_ref: make embree)" >&2; exit 2; }
done

name=$(printf '%s' "$(basename -- "$scene")" | tr -c 'A-Za-z0-9_.=-' '_')
ORDER=${ORDER:-}
order_opt=()
[ -n "$ORDER" ] && order_opt=(--ray-order "$ORDER")
# The cache's key: the scene's content, not its name: the spec as given and,
# for a file, its bytes (for a .scene file also those of the mesh files it
# names), so that another file of the same name or an edited mesh gets its
# own OBJ and rays.
hash() { if command -v sha256sum > /dev/null; then sha256sum | cut -c1-16; else cksum | tr ' ' -; fi; }
scene_key() {
    printf 'spec %s\n' "$scene"
    [ -f "$scene" ] || return 0
    cat -- "$scene"
    case $scene in
    *.scene)
        local dir src
        dir=$(dirname -- "$scene")
        awk '$1 == "mesh" && NF >= 3 { print $3 }' "$scene" | while read -r src; do
            [ -f "$dir/$src" ] && { printf '\nmesh %s\n' "$src"; cat -- "$dir/$src"; }
        done ;;
    esac
}
key=$(scene_key | hash)
DIR=${DIR:-build/vs_embree/$name-$key-$SIZE${ORDER:+-$ORDER}}
mkdir -p "$DIR"
obj=$DIR/scene.obj
if [ "${FRESH:-0}" = 1 ] || [ ! -s "$obj" ] || [ ! -s "$DIR/rays.shadow.rays" ]; then
    echo "vs_embree: making $obj and the rays of $scene ($SIZE) in $DIR"
    "$BIN/trace" --scene "$scene" --size "$SIZE" --rays primary,diffuse,shadow \
        --export-obj "$obj" --dump-rays "$DIR/rays" --repeat 1 --warmup 0 --build-repeat 1 \
        "${order_opt[@]}" --no-counters --quiet > "$DIR/make.log"
fi

# One field of bin/trace's --csv output (header names it), RFC 4180 quotes.
csv_field() {
    awk -v want="$1" '
    function split_csv(line, f,   n, i, c, q, cur) {
        n = 0; cur = ""; q = 0
        for (i = 1; i <= length(line); i++) {
            c = substr(line, i, 1)
            if (q) {
                if (c == "\"") { if (substr(line, i + 1, 1) == "\"") { cur = cur c; i++ } else q = 0 }
                else cur = cur c
            } else if (c == "\"") q = 1
            else if (c == ",") { f[++n] = cur; cur = "" }
            else cur = cur c
        }
        f[++n] = cur; return n
    }
    /^csv,/ { n = split_csv($0, f)
              if (!col) { for (i = 1; i <= n; i++) if (f[i] == want) col = i; next }
              if (col) print f[col] }'
}

# Our ISA: the one bin/trace picked at run time for the spec (its CSV's isa
# column: avx512 or avx2 for the wide BVH, GRIDBVH_ISA=avx2 forcing the
# baseline); empty for a kind with one set of kernels, the build's baseline.
our_isa() {
    local isa
    isa=$(printf '%s\n' "$1" | csv_field isa | head -n 1)
    printf '%s' "${isa:-baseline (one set of kernels: no run-time choice)}"
}

res=$DIR/results.$MODE.txt
: > "$res"
IFS=, read -r -a sets <<< "$SETS"
ours_isa=() embree_isa=unknown
for ((r = 1; r <= ROUNDS; r++)); do
    for set in "${sets[@]}"; do
        rays=$DIR/rays.$set.rays
        [ -s "$rays" ] || { echo "vs_embree: no $rays (SETS: primary,diffuse,shadow)" >&2; exit 2; }
        for k in "${!specs[@]}"; do
            dump=()
            [ "$r" = 1 ] && [ "$k" = 0 ] && [ "$CHECK" = 1 ] && dump=(--dump-hits "$DIR/ours.$MODE.$set.hits")
            out=$("$BIN/trace" --scene "$obj" --rays "$rays" "${occl[@]}" --accel "${specs[$k]}" \
                --threads "$THREADS" --repeat "$PASSES" --warmup 1 --build-repeat 1 --no-counters \
                --csv --quiet "${dump[@]}" "${trace_opts[@]}")
            mr=$(printf '%s\n' "$out" | csv_field mrays_median | head -n 1)
            [ -n "$mr" ] || { echo "vs_embree: no Mrays/s from bin/trace:"; echo "$out"; exit 1; } >&2
            [ "$r" = 1 ] && [ "$set" = "${sets[0]}" ] && ours_isa[$k]="${specs[$k]} $(our_isa "$out")"
            echo "$set $r ours$k $mr" >> "$res"
            hits=()
            [ "$r" = 1 ] && [ "$k" = 0 ] && [ "$CHECK" = 1 ] && hits=(--hits "$DIR/embree.$MODE.$set.hits")
            out=$("$BIN/embree_ref" --obj "$obj" --rays "$rays" --mode "$emode" "${occl[@]}" --threads "$THREADS" \
                --passes "$PASSES" --builds 1 --quality "$QUALITY" "${hits[@]}" "${embree_opts[@]}")
            mr=$(printf '%s\n' "$out" | sed -n 's/.* mrays=\([0-9.]*\) .*/\1/p')
            embree_isa=$(printf '%s\n' "$out" | sed -n 's/.* isa=\([^ ]*\) .*/\1/p')
            echo "$set $r embree$k $mr" >> "$res"
        done
    done
    echo "vs_embree: round $r of $ROUNDS done" >&2
done

echo "scene $scene, $MODE, $ROUNDS rounds of fresh processes, $THREADS thread(s), $PASSES passes each"
isas=$(printf '%s, ' "${ours_isa[@]}")
echo "ISA: ours ${isas%, } (what bin/trace picked); Embree $embree_isa (quality $QUALITY)"
for k in "${!specs[@]}"; do
    printf '%-9s %12s %12s %8s %15s   %s\n' "ray set" "ours Mrays/s" "Embree" "ratio" "min-max/round" "ours = ${specs[$k]}"
    for set in "${sets[@]}"; do
        awk -v set="$set" -v k="$k" '
        $1 == set && $3 == "ours" k   { o[$2] = $4 }
        $1 == set && $3 == "embree" k { e[$2] = $4 }
        function med(a,   n, i, j, t, v) {
            n = 0; for (i in a) v[++n] = a[i] + 0
            for (i = 2; i <= n; i++) { t = v[i]; for (j = i - 1; j >= 1 && v[j] > t; j--) v[j + 1] = v[j]; v[j + 1] = t }
            return n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
        }
        END {
            lo = 1e30; hi = 0
            for (r in o) if (r in e && e[r] > 0) { q = o[r] / e[r]; if (q < lo) lo = q; if (q > hi) hi = q }
            mo = med(o); me = med(e)
            printf "%-9s %12.3f %12.3f %8.3f %7.3f-%-7.3f\n", set, mo, me, (me > 0 ? mo / me : 0), lo, hi
        }' "$res"
    done
done

if [ "$CHECK" = 1 ]; then
    cmp_opt=("${occl[@]}") # any-hit answers compare by the any-hit rule
    echo "hits of round 1, ours (${specs[0]}) against Embree's (trace compare${cmp_opt:+ --occluded}):"
    for set in "${sets[@]}"; do
        printf '%-9s ' "$set"
        "$BIN/trace" compare "${cmp_opt[@]}" "$DIR/ours.$MODE.$set.hits" "$DIR/embree.$MODE.$set.hits" \
            | head -n 1 || true
    done
fi
