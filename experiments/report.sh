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
if [ -n "$dir" ]; then dir="${dir%/}"; out="$dir"; report="$dir/REPORT.md"; links=""; fi
extra=()
[ -n "${KINDS:-}" ] && extra+=(--kinds "$KINDS")
for spec in ${ACCEL:-}; do extra+=(--accel "$spec"); done
for scene in ${SCENES:-}; do extra+=(--scene "$scene"); done
# Experiments in the order the report reads them.
order="exp_step_cost exp_grid_resolution exp_sah exp_binning exp_grids exp_nested_grid exp_packets exp_wide exp_threads exp_twolevel exp_scaling exp_error_time exp_time_to_image exp_stability"
if [ -n "$only" ] && ! printf ' %s ' $order | grep -q " $only "; then
  echo "report.sh: --only $only: not an experiment; known: $order" >&2; exit 2
fi
# Every experiment checks the choices before any work (--check: its options
# and its limits on --scene and --mesh, no output): an unknown kind in KINDS,
# a bad ACCEL spec or more scenes than an experiment measures is a usage
# error (exit 2) before the first experiment starts, never a failure twenty
# minutes in nor a green report without them.
for e in $order; do
  [ -x "$bin/$e" ] || continue
  if [ -n "$only" ] && [ "$only" != "$e" ]; then continue; fi
  st=0
  "$bin/$e" $flag --check "${extra[@]}" || st=$?
  if [ "$st" != 0 ]; then
    echo "report.sh: $e refuses these choices (above): nothing was run; the previous report is as it was" >&2
    exit "$st"
  fi
done
# The run writes into a fresh folder and replaces the previous report (the
# sections folder $out and $report) only when every experiment has finished:
# a failed or interrupted run leaves the previous one byte for byte as it was
# and says where its partial output is. The folder is replaced whole, so no
# file of an earlier run survives (an old plot no section names); --only
# starts from a copy of the previous sections. Never a source folder.
out="${out%/}"
if [ -e "$out/Makefile" ] || [ -e "$out/.git" ] || [ -e "$out/sources.mk" ]; then
  echo "report.sh: $out holds sources: the report replaces its folder whole; give a folder of its own" >&2
  exit 2
fi
if [ "$report" = "$out/REPORT.md" ]; then
  stage="$out.partial"; stage_out="$stage"; stage_report="$stage/REPORT.md"
else
  mkdir -p build
  stage="build/$(basename "$out").partial"; stage_out="$stage/$(basename "$out")"; stage_report="$stage/$(basename "$report")"
fi
rm -rf "$stage"
mkdir -p "$stage_out"
if [ -n "$only" ] && [ -d "$out" ]; then cp -pR "$out"/. "$stage_out"/; rm -f "$stage_out/$only".*; fi
published=0
unfinished() {
  [ "$published" = 1 ] && return
  local prev="the previous report ($out/) is as it was"
  [ "$report" = "$out/REPORT.md" ] || prev="the previous report ($report and $out/) is as it was"
  [ -e "$out" ] || [ -e "$report" ] || prev="there was no previous report"
  echo "report.sh: the run did not finish: $prev; the partial output is in $stage_out/" >&2
}
trap unfinished EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
read -r load_start _ < /proc/loadavg || load_start="?"
start=$(date +%s)
ran=()
times=""   # each experiment's own wall time, for the run record
sum=0
for e in $order; do
  [ -x "$bin/$e" ] || continue
  if [ -n "$only" ] && [ "$only" != "$e" ]; then continue; fi
  echo "== $e" >&2
  t0=$(date +%s)
  if ! "$bin/$e" $flag --out "$stage_out" "${extra[@]}"; then
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
  for e in $order; do [ -f "$stage_out/$e.md" ] && ran+=("$e"); done
  note="; --only $only: the other sections are kept from an earlier run"
fi
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
dirty=$(git status --porcelain --untracked-files=no 2>/dev/null | grep -v -e ' REPORT.md' -e ' report/' | head -1 || true)
[ -n "$dirty" ] && commit="$commit (with uncommitted changes)"
commit="$commit, $(git log -1 --format='%cd' --date=format:'%Y-%m-%d %H:%M' 2>/dev/null || true)"
cc_version=$(${CC:-cc} --version 2>/dev/null | head -1)
"$bin/mkreport" --out "$stage_out" --report "$stage_report" --links "$links" --budget "$budget" \
  --commit "$commit" --flags "${GRIDBVH_CFLAGS:-see Makefile} (driver: $cc_version)" \
  --run "$((end - start)) s; per experiment: $times (sum $sum s)$note${KINDS:+; KINDS=$KINDS}${ACCEL:+; ACCEL=$ACCEL}${SCENES:+; SCENES=$SCENES}" \
  --load "$load_start (1 minute) before the first experiment, $load_end after the last" \
  "${ran[@]}"
# Every experiment finished and the report is assembled: the new report
# replaces the previous one (renames; the previous folder goes last).
old="$stage.previous"
rm -rf "$old"
[ -e "$out" ] && mv "$out" "$old"
mkdir -p "$(dirname "$out")"
mv "$stage_out" "$out"
[ "$stage_report" = "$stage_out/REPORT.md" ] || mv "$stage_report" "$report"
published=1
rm -rf "$old" "$stage"
echo "report.sh: wrote $report in $((end - start)) s" >&2
