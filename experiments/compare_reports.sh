#!/usr/bin/env bash
# Compares the verdict words of two report runs (issue 38: "two full runs of
# the same commit print the same verdict word on every row that is not on
# the line").
# Usage: experiments/compare_reports.sh DIR_A DIR_B
#   DIR_A, DIR_B: report directories (report/, build/quick-report/, or a
#   copy of one), or REPORT.md files (their directory is used). It reads
#   every <section>.verdicts.csv there, not REPORT.md's summary table
#   (whose layout mkreport may change): one row per verdict, keyed by
#   section, claim, scenes and the row's order among equal keys.
# Prints every row whose word differs, or that one run lacks, marking rows
# "on the line" in either run as ignored; exits 0 when no other row flips,
# 1 when one does, 2 on a usage error.
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 DIR_A DIR_B (report directories, or REPORT.md files beside them)" >&2
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
a=$(dir_of "$1")
b=$(dir_of "$2")
for d in "$a" "$b"; do
  if ! ls "$d"/*.verdicts.csv > /dev/null 2>&1; then
    echo "$0: no *.verdicts.csv in $d" >&2
    exit 2
  fi
done
# Each run as lines "key<TAB>verdict". RFC 4180 fields (quotes, doubled
# quotes, commas inside quotes) parsed character by character: one record
# per line, as experiments/harness.c writes them.
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
      NR == 1 { next }
      {
        n = parse($0)
        section = n >= 5 ? F[5] : file
        key = section " | " F[1] " | " F[4]
        seen[key]++
        printf "%s #%d\t%s\n", key, seen[key], F[2]
      }' "$f"
  done | sort
}
rows "$a" > "${TMPDIR:-/tmp}/cmp_a.$$"
rows "$b" > "${TMPDIR:-/tmp}/cmp_b.$$"
trap 'rm -f "${TMPDIR:-/tmp}/cmp_a.$$" "${TMPDIR:-/tmp}/cmp_b.$$"' EXIT
awk -F '\t' -v A="$a" -v B="$b" '
  FNR == NR { va[$1] = $2; next }
  { vb[$1] = $2 }
  END {
    flips = 0; lines = 0; same = 0
    for (k in va) keys[k] = 1
    for (k in vb) keys[k] = 1
    for (k in keys) {
      x = (k in va) ? va[k] : "(absent)"; y = (k in vb) ? vb[k] : "(absent)"
      if (x == y) { same++; continue }
      if (x == "on the line" || y == "on the line") {
        printf "ignored (on the line): %s: %s -> %s\n", k, x, y; lines++
      } else {
        printf "FLIP: %s: %s -> %s\n", k, x, y; flips++
      }
    }
    printf "%d rows the same, %d differ only through \"on the line\", %d flip (%s against %s)\n", same, lines, flips, A, B
    exit flips ? 1 : 0
  }' "${TMPDIR:-/tmp}/cmp_a.$$" "${TMPDIR:-/tmp}/cmp_b.$$"
