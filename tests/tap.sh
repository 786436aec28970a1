# tap.sh -- the TAP harness of the shell tests of soilsim, sourced:
#   SOILSIM=...; TAP_NAME=cli; . "$top_srcdir/tests/tap.sh"
# Bails out when $SOILSIM is not built; makes the scratch folder $tmp
# (soilsim-$TAP_NAME.XXXXXX, the caller removes it with a trap); defines
# run, check, skip, the predicates used inside checks and expect_line (the
# expect comment of a catalogue file).  The script ends
# with: echo "1..$n"; [ "$nfail" -eq 0 ]

# The checks are shell expressions in single quotes, expanded by eval.
# shellcheck shell=sh disable=SC2016,SC2034

if [ ! -x "$SOILSIM" ]; then
  echo "Bail out! $SOILSIM is not built"
  exit 1
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/soilsim-$TAP_NAME.XXXXXX") || {
  echo "Bail out! mktemp -d failed"
  exit 1
}

# Every run is bounded so that a hang fails instead of stalling make check.
TIMEOUT=""
if command -v timeout >/dev/null 2>&1; then TIMEOUT="timeout 120"; fi

n=0
nfail=0
last_cmd=""
rc=0

# run ARGS...: soilsim with stdout/stderr in $tmp/out, $tmp/err; sets rc.
# CI is cleared so that nothing depends on the caller's environment.
run() {
  last_cmd="soilsim $*"
  # shellcheck disable=SC2086
  CI='' $TIMEOUT "$SOILSIM" "$@" >"$tmp/out" 2>"$tmp/err"
  rc=$?
}

# check DESC EXPR: one TAP line; EXPR is evaluated by the shell.
check() {
  n=$((n + 1))
  desc=$(printf '%s' "$1" | sed 's/#/\\#/g')
  if eval "$2"; then
    echo "ok $n - $desc"
  else
    echo "not ok $n - $desc"
    nfail=$((nfail + 1))
    echo "#   last command: $last_cmd (exit $rc)"
    sed -n '1,8s/^/#   stderr: /p' "$tmp/err"
    sed -n '1,4s/^/#   stdout: /p' "$tmp/out"
  fi
}

skip() {
  n=$((n + 1))
  echo "ok $n # SKIP $1"
}

rc_is() { [ "$rc" -eq "$1" ]; }
err_has() { grep -qF -- "$1" "$tmp/err"; }
out_has() { grep -qF -- "$1" "$tmp/out"; }
no_file() { [ ! -e "$1" ]; }
# no temporary files of the atomic writer (PATH.tmpPID) left in a folder
no_tmp() {
  for f in "$1"/*.tmp[0-9]* "$1"/.*.tmp[0-9]*; do
    [ -e "$f" ] && return 1
  done
  return 0
}

# expect_line FILE: the first line of FILE, <!-- expect: N: SUBSTRING -->,
# into expect_n and expect_sub (both empty when it is not such a line).
expect_line() {
  first=$(sed -n 1p "$1")
  expect_n=$(printf '%s\n' "$first" |
    sed -n 's/^<!-- *expect: *\([0-9][0-9]*\): .*-->.*$/\1/p')
  expect_sub=$(printf '%s\n' "$first" |
    sed -n 's/^<!-- *expect: *[0-9][0-9]*: *\(.*[^ ]\) *-->.*$/\1/p')
}
