#!/bin/sh
# same_speed.sh - is a new build as fast as an old one, on the same rays?
#
#   tests/same_speed.sh OLD_BIN NEW_BIN [ROUNDS]
#   SAME_SPEED_ENV_A="GRIDBVH_ISA=avx2" tests/same_speed.sh bin bin   # one build, two ISAs
#
# For each kind below, on the same scene, camera and seed, runs
# OLD_BIN/trace and NEW_BIN/trace in alternation (A B, then B A, ...) in
# fresh processes, ROUNDS times (default 5), one thread, and takes each
# process's median Mrays/s of 5 timed passes per ray set. Prints, per kind
# and ray set, the median of the per-round ratios new/old with their
# minimum and maximum: a ratio whose min-max range holds 1.00 is a tie.
# SAME_SPEED_ENV_A and SAME_SPEED_ENV_B (NAME=value words) are set in the
# environment of OLD_BIN's and NEW_BIN's processes: the same binary with
# two settings. Run it on a quiet machine (no build or test running).
set -u
old=${1:?usage: same_speed.sh OLD_BIN NEW_BIN [ROUNDS]}
new=${2:?usage: same_speed.sh OLD_BIN NEW_BIN [ROUNDS]}
rounds=${3:-5}
env_a=${SAME_SPEED_ENV_A:-}
env_b=${SAME_SPEED_ENV_B:-}
here=$(dirname "$0")/..
mesh=$here/../shared/scenes/bunny.off
# The mesh's camera is given, so that a change of the default view (which
# changes the rays) cannot pass for a change of speed.
view="--eye 0.437193,0.564953,1.6116 --look -0.0429531,0.00478223,0.0111076"
runs="bvh|$mesh|400x300|$view
bvh:width=8|$mesh|400x300|$view
bvh:width=8,traverse=packet|$mesh|400x300|$view
grid|$mesh|400x300|$view
nested_grid|$mesh|400x300|$view
irregular_grid|$mesh|400x300|$view
instanced|field:instances=60,detail=3|400x300|"
tmp=$(mktemp -d)
# One process's Mrays/s per set, as "set value" lines.
mrays() {
    # $5: camera options, $6: NAME=value words for env, both word-split on purpose
    # shellcheck disable=SC2086
    env $6 "$1/trace" --scene "$2" --accel "$3" --size "$4" $5 --rays primary,shadow,diffuse --repeat 5 \
        --warmup 1 --build-repeat 1 --no-counters --quiet 2>/dev/null |
        awk '/Mrays\/s/ { for (i = 1; i < NF; i++) if ($(i + 1) == "Mrays/s") print $1, $i }'
}
printf '%-30s %-8s %8s %8s %8s %s\n' kind set old new ratio "(min-max)"
echo "$runs" | while IFS='|' read -r spec scene size cam; do
    : > "$tmp/r"
    r=0
    while [ $r -lt "$rounds" ]; do
        if [ $((r % 2)) -eq 0 ]; then
            mrays "$old" "$scene" "$spec" "$size" "$cam" "$env_a" > "$tmp/o"
            mrays "$new" "$scene" "$spec" "$size" "$cam" "$env_b" > "$tmp/n"
        else
            mrays "$new" "$scene" "$spec" "$size" "$cam" "$env_b" > "$tmp/n"
            mrays "$old" "$scene" "$spec" "$size" "$cam" "$env_a" > "$tmp/o"
        fi
        paste -d" " "$tmp/o" "$tmp/n" | awk '$1 == $3 { print $1, $2, $4 }' >> "$tmp/r"
        r=$((r + 1))
    done
    for set in primary shadow diffuse; do
        grep "^$set " "$tmp/r" | awk -v k="$spec" -v s="$set" '
            { o[NR] = $2; n[NR] = $3; q[NR] = $3 / $2 }
            function med(a, m,   i, j, t) { for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++)
                    if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
                return m % 2 ? a[(m + 1) / 2] : (a[m / 2] + a[m / 2 + 1]) / 2 }
            END { if (!NR) exit; mo = med(o, NR); mn = med(n, NR); lo = q[1]; hi = q[1]
                  for (i = 2; i <= NR; i++) { if (q[i] < lo) lo = q[i]; if (q[i] > hi) hi = q[i] }
                  mq = med(q, NR)
                  printf "%-30s %-8s %8.2f %8.2f %8.3f (%.3f-%.3f)%s\n", k, s, mo, mn, mq, lo, hi,
                         (lo <= 1 && hi >= 1) ? " tie" : "" }'
    done
done
rm -rf "$tmp"
