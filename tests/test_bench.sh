#!/bin/sh
# test_bench.sh -- the benchmark program's own checks on short runs
# (correctness only, never timing): the contact-law checks for both
# materials, warm and cold starts reaching the same converged answer, and
# the bodies of DESIGN 8 settling at the analytic sinkage, also on a
# 100x larger bed.
top_builddir=${top_builddir:-.}
BENCH="$top_builddir/benchmarks"
n=0
nfail=0
check() {
  n=$((n + 1))
  if out=$("$BENCH" --bench deformable_terrain -- "$@" 2>&1); then
    echo "ok $n - benchmarks $*"
  else
    echo "not ok $n - benchmarks $*"
    nfail=$((nfail + 1))
  fi
  printf '%s\n' "$out" | sed 's/^/# /'
}
check --contact-law --material=linear --steps=300 --repeats=1
check --contact-law --material=nonlinear --steps=300 --repeats=1
check --contact-law --material=nonlinear --start=cold --steps=300 --repeats=1
check --body=rigid --steps=1500 --repeats=1 --verify
# the sweeps alone (the solver where the Newton phase declines)
check --body=rigid --solver=sweeps --steps=1500 --repeats=1 --verify
check --body=articulated --steps=1500 --repeats=1 --verify
check --body=multilink --steps=1500 --repeats=1 --verify
# the same plate on a 100x larger bed (the step's cost must not notice it),
# timed steps after untimed warm-up ones
check --body=rigid --warmup=1400 --steps=100 --repeats=1 --bed-scale=10 --verify
echo "1..$n"
[ "$nfail" -eq 0 ]
