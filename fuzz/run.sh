#!/bin/sh
# run.sh -- a bounded run of every fuzz target (what `make fuzz-run` does).
#
# usage: fuzz/run.sh SRCDIR BUILDDIR SECONDS [NAME...]
#
# For each target BUILDDIR/fuzz/fuzz_NAME (all that are built when no NAME
# is given): gathers the seeds (fuzz/seed-corpus.sh), then runs libFuzzer
# for SECONDS seconds on
#   BUILDDIR/fuzz/corpus/NAME   its own corpus (kept between runs; new
#                               inputs are written here)
#   BUILDDIR/fuzz/seeds/NAME    the project's inputs
#   SRCDIR/fuzz/regress/NAME    inputs that once crashed (fixed since),
#                               replayed first on every run
# with the dictionary SRCDIR/fuzz/NAME.dict, a per-input time limit of
# FUZZ_TIMEOUT seconds (default 10), a memory limit of FUZZ_RSS_MB
# (default 2048) and the leak suppressions in SRCDIR/fuzz/lsan.supp
# (leaks inside assimp, Mesa and LLVM, which we cannot fix, are not
# reported; leaks of our own are).  A crash, a sanitizer report, a leak, a
# timeout or running out of memory fails the run; the input that did it is
# kept as BUILDDIR/fuzz/artifacts/NAME-crash-... (or -leak-, -timeout-,
# -oom-) and the log tail is shown.  Reproduce with
#   BUILDDIR/fuzz/fuzz_NAME ARTIFACT
# The last line is `fuzz: N targets clean` or `fuzz: N of M targets failed`;
# the exit status is 1 when any failed.
set -u

[ $# -ge 3 ] || { echo "usage: $0 SRCDIR BUILDDIR SECONDS [NAME...]" >&2; exit 2; }
src=$1
build=$2
seconds=$3
shift 3

names=$*
if [ -z "$names" ]; then
  for t in "$build"/fuzz/fuzz_*; do
    [ -x "$t" ] && [ -f "$t" ] || continue
    case $t in *.o|*.d|*.c|*.log) continue ;; esac
    names="$names ${t##*/fuzz_}"
  done
fi
[ -n "$names" ] || { echo "fuzz: no targets built (run make fuzz)" >&2; exit 1; }

ckpt=""
[ -x "$build/fuzz/fuzz_checkpoint" ] && ckpt=$build/fuzz/fuzz_checkpoint
sh "$src/fuzz/seed-corpus.sh" "$src" "$build/fuzz/seeds" $ckpt

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1:abort_on_error=0}"
export LSAN_OPTIONS="suppressions=$src/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

ntotal=0
nfail=0
for n in $names; do
  bin=$build/fuzz/fuzz_$n
  ntotal=$((ntotal + 1))
  if [ ! -x "$bin" ]; then
    echo "FAIL  fuzz_$n: not built (run make fuzz)"
    nfail=$((nfail + 1))
    continue
  fi
  corpus=$build/fuzz/corpus/$n
  mkdir -p "$corpus" "$build/fuzz/artifacts"
  dirs="$corpus $build/fuzz/seeds/$n"
  [ -d "$src/fuzz/regress/$n" ] && dirs="$dirs $src/fuzz/regress/$n"
  dict=""
  [ -f "$src/fuzz/$n.dict" ] && dict="-dict=$src/fuzz/$n.dict"
  log=$build/fuzz/fuzz_$n.log
  start=$(date +%s)
  # shellcheck disable=SC2086
  "$bin" -max_total_time="$seconds" -timeout="${FUZZ_TIMEOUT:-10}" \
    -rss_limit_mb="${FUZZ_RSS_MB:-2048}" -max_len="${FUZZ_MAX_LEN:-65536}" \
    -print_final_stats=1 -artifact_prefix="$build/fuzz/artifacts/$n-" \
    $dict $dirs >"$log" 2>&1
  rc=$?
  took=$(( $(date +%s) - start ))
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  units=$(ls "$corpus" | wc -l)
  if [ "$rc" -eq 0 ]; then
    printf 'ok    fuzz_%s: %s s, %s runs, corpus %s inputs, clean\n' \
      "$n" "$took" "${runs:-?}" "$units"
  else
    nfail=$((nfail + 1))
    printf 'FAIL  fuzz_%s: exit %s after %s s; log %s\n' "$n" "$rc" "$took" "$log"
    grep -E 'ERROR:|SUMMARY:|runtime error|Test unit written|artifact_prefix' "$log" |
      head -n 12 | sed 's/^/      /'
    tail -n 25 "$log" | sed 's/^/      | /'
  fi
done

if [ "$nfail" -eq 0 ]; then
  echo "fuzz: $ntotal targets clean"
else
  echo "fuzz: $nfail of $ntotal targets failed"
  exit 1
fi
