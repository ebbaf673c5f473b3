#!/usr/bin/env bash
# Runs every experiment binary, then bin/mkreport assembles the report.
# Usage (from the repository root, after `make`):
#   experiments/report.sh            full budget: REPORT.md + report/ (committed)
#   experiments/report.sh --quick    smoke budget: build/quick-report/REPORT.md
#   experiments/report.sh --only exp_sah [--quick]   one experiment
#   experiments/report.sh --dir D    the report into D/REPORT.md, sections in D/
#                                    (the lab's `make lab-report`)
# The environment passes choices through to every experiment:
#   BIN=bin-lab             the binaries of another build (default bin)
#   KINDS=grid,bvh          only these kinds (--kinds)
#   ACCEL="spec spec ..."   more configurations (--accel SPEC, each)
#   SCENES="spec file ..."  exactly these scenes (--scene, each; .scene files too)
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
only=""
dir=""
bin="${BIN:-bin}"
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --only) only="$2"; shift ;;
    --dir) dir="$2"; shift ;;
    *) echo "report.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ "$quick" = 1 ]; then
  out=build/quick-report; report=build/quick-report/REPORT.md; flag=--quick; budget="quick (smoke test)"; links=""
else
  out=report; report=REPORT.md; flag=""; budget="full"; links="report/"
fi
if [ -n "$dir" ]; then out="$dir"; report="$dir/REPORT.md"; links=""; fi
extra=()
[ -n "${KINDS:-}" ] && extra+=(--kinds "$KINDS")
for spec in ${ACCEL:-}; do extra+=(--accel "$spec"); done
for scene in ${SCENES:-}; do extra+=(--scene "$scene"); done
# The choices are checked before anything is removed or run: an unknown kind
# in KINDS or a bad ACCEL spec is a usage error (exit 2), never a green
# report without them. An experiment checks every option before --help.
for e in exp_step_cost exp_sah; do
  if [ -x "$bin/$e" ]; then
    st=0
    "$bin/$e" $flag "${extra[@]}" --help > /dev/null || st=$?
    [ "$st" = 0 ] || exit "$st"
    break
  fi
done
mkdir -p "$out"
# A whole run owns $out: it starts clean (no section of an earlier run
# survives), and what the run did not write is removed at its end (an old
# plot no section names); --only keeps the others. Never a source folder.
owned=1
[ -e "$out/Makefile" ] || [ -e "$out/.git" ] || [ -e "$out/sources.mk" ] && owned=0
stamp="$out/.report-start"
if [ -z "$only" ] && [ "$owned" = 1 ]; then
  rm -f "$out"/*.md "$out"/*.csv "$out"/*.svg "$out"/*.gp
  touch "$stamp"
fi
read -r load_start _ < /proc/loadavg || load_start="?"
# Experiments in the order the report reads them.
order="exp_step_cost exp_grid_resolution exp_sah exp_binning exp_grids exp_nested_grid exp_packets exp_wide exp_threads exp_twolevel exp_scaling exp_error_time exp_time_to_image exp_stability"
start=$(date +%s)
ran=()
times=""   # each experiment's own wall time, for the run record
sum=0
for e in $order; do
  [ -x "$bin/$e" ] || continue
  if [ -n "$only" ] && [ "$only" != "$e" ]; then continue; fi
  echo "== $e" >&2
  t0=$(date +%s)
  if ! "$bin/$e" $flag --out "$out" "${extra[@]}"; then
    echo "report.sh: $e failed" >&2
    exit 1
  fi
  t=$(( $(date +%s) - t0 ))
  sum=$((sum + t))
  times="${times:+$times, }$e $t s"
  ran+=("$e")
done
end=$(date +%s)
read -r load_end _ < /proc/loadavg || load_end="?"
note=""
if [ -n "$only" ]; then
  # One section rerun: the report is assembled from every section in $out,
  # the others as an earlier run left them (their verdicts still count).
  ran=()
  for e in $order; do [ -f "$out/$e.md" ] && ran+=("$e"); done
  note="; --only $only: the other sections are kept from an earlier run"
fi
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
dirty=$(git status --porcelain --untracked-files=no 2>/dev/null | grep -v -e ' REPORT.md' -e ' report/' | head -1 || true)
[ -n "$dirty" ] && commit="$commit (with uncommitted changes)"
commit="$commit, $(git log -1 --format='%cd' --date=format:'%Y-%m-%d %H:%M' 2>/dev/null || true)"
cc_version=$(${CC:-cc} --version 2>/dev/null | head -1)
"$bin/mkreport" --out "$out" --report "$report" --links "$links" --budget "$budget" \
  --commit "$commit" --flags "${GRIDBVH_CFLAGS:-see Makefile} (driver: $cc_version)" \
  --run "$((end - start)) s; per experiment: $times (sum $sum s)$note${KINDS:+; KINDS=$KINDS}${ACCEL:+; ACCEL=$ACCEL}${SCENES:+; SCENES=$SCENES}" \
  --load "$load_start (1 minute) before the first experiment, $load_end after the last" \
  "${ran[@]}"
if [ -f "$stamp" ]; then
  # Files older than the run's start were not written by it.
  find "$out" -maxdepth 1 -type f ! -newer "$stamp" ! -name .report-start -print |
    while read -r f; do echo "report.sh: removed $f (not written by this run)" >&2; rm -f "$f"; done
  rm -f "$stamp"
fi
echo "report.sh: wrote $report in $((end - start)) s" >&2
