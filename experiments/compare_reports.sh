#!/usr/bin/env bash
# Compares the verdict words of report runs (issue 52: "every relative
# verdict prints the same word in all three (on the line included), except
# a row whose interval ends within 2% of its threshold in one of the runs").
# Usage: experiments/compare_reports.sh DIR_A DIR_B [DIR_C ...]
#   DIR_*: report directories (report/, build/quick-report/, or a copy of
#   one), or REPORT.md files (their directory is used). It reads every
#   <section>.verdicts.csv there, not REPORT.md's summary table (whose
#   layout mkreport may change): one row per verdict, keyed by section,
#   claim and the row's order among equal keys (not by the scenes: a row
#   whose deciding scene moves is the same row, its word compared).
# Every later run is compared with the first. Any change of word is a
# change, "on the line" included. Printed apart, and not counted: a row
# whose interval (lo or hi) ends within 2% of its threshold in either run
# ("near"), and a row that becomes "not testable here" in one run (an
# absolute threshold judged on a loaded machine: the evidence says why).
# Exits 0 when nothing else changes, 1 when a row changes, 2 on a usage
# error.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 DIR_A DIR_B [DIR_C ...] (report directories, or REPORT.md files beside them)" >&2
  exit 2
fi
dir_of() {
  if [ -d "$1" ]; then
    echo "$1"
  elif [ -f "$1" ]; then
    # REPORT.md at the root sits beside report/; elsewhere beside its sections.
    d=$(dirname "$1")
    if [ -d "$d/report" ] && ls "$d"/report/*.verdicts.csv > /dev/null 2>&1; then echo "$d/report"; else echo "$d"; fi
  else
    echo "$0: $1: no such file or directory" >&2
    exit 2
  fi
}
dirs=()
for arg in "$@"; do dirs+=("$(dir_of "$arg")"); done
for d in "${dirs[@]}"; do
  if ! ls "$d"/*.verdicts.csv > /dev/null 2>&1; then
    echo "$0: no *.verdicts.csv in $d" >&2
    exit 2
  fi
done
# Each run as lines "key<TAB>verdict<TAB>near" (near: 1 when lo or hi is
# within 2% of the threshold). RFC 4180 fields (quotes, doubled quotes,
# commas inside quotes) parsed character by character: one record per
# line, as experiments/engine/harness.c writes them.
rows() {
  for f in "$1"/*.verdicts.csv; do
    awk -v file="$(basename "$f")" '
      function parse(line,   i, c, n, q, field) {
        n = 0; field = ""; q = 0
        for (i = 1; i <= length(line); i++) {
          c = substr(line, i, 1)
          if (q) {
            if (c == "\"" && substr(line, i + 1, 1) == "\"") { field = field "\""; i++ }
            else if (c == "\"") q = 0
            else field = field c
          } else if (c == "\"") q = 1
          else if (c == ",") { F[++n] = field; field = "" }
          else if (c != "\r") field = field c
        }
        F[++n] = field
        return n
      }
      function near(x, t) { return t != 0 && x != "" && (x / t - 1 <= 0.02) && (x / t - 1 >= -0.02) }
      NR == 1 { next }
      {
        n = parse($0)
        section = n >= 5 ? F[5] : file
        key = section " | " F[1]
        seen[key]++
        nr = n >= 10 && F[10] != "" && (near(F[8], F[10]) || near(F[9], F[10]))
        printf "%s #%d\t%s\t%d\n", key, seen[key], F[2], nr
      }' "$f"
  done | sort
}
tmp="${TMPDIR:-/tmp}/cmp.$$"
trap 'rm -f "$tmp".*' EXIT
rows "${dirs[0]}" > "$tmp.0"
status=0
for ((i = 1; i < ${#dirs[@]}; i++)); do
  rows "${dirs[$i]}" > "$tmp.$i"
  awk -F '\t' -v A="${dirs[0]}" -v B="${dirs[$i]}" '
    FNR == NR { va[$1] = $2; na[$1] = $3; next }
    { vb[$1] = $2; nb[$1] = $3 }
    END {
      changes = 0; near = 0; unt = 0; same = 0
      for (k in va) keys[k] = 1
      for (k in vb) keys[k] = 1
      for (k in keys) {
        x = (k in va) ? va[k] : "(absent)"; y = (k in vb) ? vb[k] : "(absent)"
        if (x == y) { same++; continue }
        if (na[k] == 1 || nb[k] == 1) {
          printf "near the threshold (interval end within 2%%): %s: %s -> %s\n", k, x, y; near++
        } else if (x == "not testable here" || y == "not testable here") {
          printf "not testable in one run: %s: %s -> %s\n", k, x, y; unt++
        } else {
          printf "CHANGE: %s: %s -> %s\n", k, x, y; changes++
        }
      }
      printf "%s against %s: %d rows the same, %d change, %d near the threshold, %d not testable in one run\n", B, A, same, changes, near, unt
      exit changes ? 1 : 0
    }' "$tmp.0" "$tmp.$i" || status=1
done
exit $status
