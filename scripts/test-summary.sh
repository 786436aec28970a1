#!/bin/sh
# test-summary.sh -- the closing report of `make test`.
#
# usage: scripts/test-summary.sh TEST...   (run in the build folder)
#
# For every test in the TESTS list, reads the .trs file that automake's TAP
# driver wrote (one ":test-result: RESULT" line per TAP test case) and counts
# the cases: PASS and XFAIL pass; FAIL and XPASS fail; SKIP is skipped; an
# ERROR (bad exit status or plan, "Bail out!") fails when nothing else did.  A test without a .trs file (it did not build or did not run)
# counts as one failure.  Prints one line per test, what failed (from the
# log of every failing test), and ends with exactly one line
#     N passed, N failed[, N skipped]
# Exit status 1 when anything failed or nothing ran.

TAIL_LINES=${TAIL_LINES:-25}

total_pass=0
total_fail=0
total_skip=0
failed_tests=""

# The .trs/.log base name automake uses: TEST_EXTENSIONS (.sh here) and
# $(EXEEXT) are stripped, other names are kept whole.
base_of() {
  case $1 in
    *.sh) printf '%s\n' "${1%.sh}" ;;
    *.exe) printf '%s\n' "${1%.exe}" ;;
    *) printf '%s\n' "$1" ;;
  esac
}

for t in "$@"; do
  b=$(base_of "$t")
  trs=$b.trs
  [ -f "$trs" ] || { [ -f "$t.trs" ] && trs=$t.trs; }
  if [ ! -f "$trs" ]; then
    printf 'FAIL  %s: did not run (no %s; run make check to see why)\n' \
      "$t" "$trs"
    total_fail=$((total_fail + 1))
    failed_tests="$failed_tests $t"
    continue
  fi
  # An ERROR (bad exit status, bad plan, bail out) is a failure of its
  # own only when no case failed: a test with failing cases exits 1 too.
  counts=$(awk '
    /^:test-result:/ {
      r = $2
      if (r == "PASS" || r == "XFAIL") p++
      else if (r == "SKIP") s++
      else if (r == "ERROR") e++
      else f++
    }
    END { printf "%d %d %d\n", p, (f > 0 ? f : e), s }' "$trs")
  read -r p f s <<EOF
$counts
EOF
  total_pass=$((total_pass + p))
  total_fail=$((total_fail + f))
  total_skip=$((total_skip + s))
  if [ "$f" -gt 0 ]; then
    printf 'FAIL  %s: %d of %d cases failed\n' "$t" "$f" $((p + f + s))
    failed_tests="$failed_tests $t"
  elif [ $((p + f + s)) -eq 0 ]; then
    printf 'FAIL  %s: no test cases ran\n' "$t"
    total_fail=$((total_fail + 1))
    failed_tests="$failed_tests $t"
  else
    printf 'ok    %s: %d passed' "$t" "$p"
    [ "$s" -gt 0 ] && printf ', %d skipped' "$s"
    printf '\n'
  fi
done

# What went wrong, from each failing test's log: the failing cases with
# their diagnostics, then the last lines that are not TAP results (crash
# messages, output of a test that never got going).
for t in $failed_tests; do
  log=$(base_of "$t").log
  [ -f "$log" ] || { [ -f "$t.log" ] && log=$t.log; }
  printf '\n--- %s ---\n' "$t"
  if [ -f "$log" ]; then
    awk '
      /^not ok/ { shown++; keep = 1; if (shown <= 40) print; next }
      /^FAIL:|^XPASS:/ && keep { next }
      /^#/ && keep { if (shown <= 40) print; next }
      { keep = 0 }
      /^(Bail out!|ERROR:)/ { print }
      END { if (shown > 40) printf "(%d failing cases in all)\n", shown }
    ' "$log"
    other=$(grep -Ev '^(ok|not ok|PASS:|FAIL:|XFAIL:|XPASS:|SKIP:|ERROR:|#|1\.\.)' "$log" |
      tail -n "$TAIL_LINES")
    if [ -n "$other" ]; then
      printf -- '--- other output (last %s lines) in %s ---\n' "$TAIL_LINES" "$log"
      printf '%s\n' "$other"
    fi
  else
    printf '(no log %s: the test did not build or did not run; run make check)\n' \
      "$log"
  fi
done
[ -n "$failed_tests" ] && printf '\n'

line="$total_pass passed, $total_fail failed"
[ "$total_skip" -gt 0 ] && line="$line, $total_skip skipped"
printf '%s\n' "$line"

[ "$total_fail" -eq 0 ] && [ $((total_pass + total_skip)) -gt 0 ]
