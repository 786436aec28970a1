#!/bin/sh
# test_bench.sh -- the benchmark program's own checks on short runs
# (correctness only, never timing): the contact-law checks for both
# materials, warm and cold starts reaching the same converged answer, and
# the bodies of DESIGN 8 settling at the analytic sinkage, also on a
# 100x larger bed; then its refusals of bad options (a message naming the
# option and what it allows, a non-zero exit, no run) and its CSV.
#
# make check sets top_srcdir and top_builddir (absolute); by hand:
#   top_srcdir=. top_builddir=. sh tests/test_bench.sh

# The checks are shell expressions in single quotes, expanded by eval.
# shellcheck disable=SC2016,SC2034

top_srcdir=${top_srcdir:-.}
top_builddir=${top_builddir:-.}
# the harness runs $SOILSIM: here the benchmark program
SOILSIM=$top_builddir/benchmarks
TAP_NAME=bench
. "$top_srcdir/tests/tap.sh"
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM HUP

# a short run whose checks (--verify, or the contact law's own) are its
# exit status; its report goes into the log as comments
verified() {
  run --bench deformable_terrain -- "$@"
  check "benchmarks $*" 'rc_is 0'
  sed 's/^/# /' "$tmp/out"
}
verified --contact-law --material=linear --steps=300 --repeats=1
verified --contact-law --material=nonlinear --steps=300 --repeats=1
verified --contact-law --material=nonlinear --start=cold --steps=300 --repeats=1
verified --body=rigid --steps=1500 --repeats=1 --verify
# the sweeps alone (the solver where the Newton phase declines)
verified --body=rigid --solver=sweeps --steps=1500 --repeats=1 --verify
verified --body=articulated --steps=1500 --repeats=1 --verify
verified --body=multilink --steps=1500 --repeats=1 --verify
# the same plate on a 100x larger bed (the step's cost must not notice it),
# timed steps after untimed warm-up ones
verified --body=rigid --warmup=1400 --steps=100 --repeats=1 --bed-scale=10 --verify

# the buggy has no closed-form reference: --verify says so and checks nothing
run --bench deformable_terrain -- --body=buggy --steps=2 --repeats=1 --verify
check 'the buggy with --verify: runs, and says that nothing is checked' \
  'rc_is 0 && out_has "real-time factor" && out_has "verify: none for the buggy"'
check 'a body run splits its step by stage' \
  'out_has "stages (last repeat, us/step and share): kinematics" &&
   out_has ", free velocity " && out_has ", contacts " && out_has ", solve " &&
   out_has ", cache + soil update " && out_has ", integration "'

# bad options: refused before any run (each returns at once), exit 2 for
# usage and 1 for a file that cannot be used
T="--bench deformable_terrain --"
run $T --steps=abc
check '--steps=abc: refused, the range named' \
  'rc_is 2 && err_has "invalid --steps" && err_has "must be an integer from 1 to 100000000"'
run $T --steps=99999999999999
check '--steps beyond its range: refused' 'rc_is 2 && err_has "invalid --steps"'
run $T --warmup -5
check '--warmup -5 (the spaced form): refused' \
  'rc_is 2 && err_has "invalid --warmup" && err_has "from 0 to"'
run $T --body=foo
check '--body=foo: refused, the bodies named' \
  'rc_is 2 && err_has "must be rigid, articulated, pinned, multilink or buggy"'
run $T --csv
check '--csv without a file: refused' 'rc_is 2 && err_has "--csv needs a value"'
run $T --csv="$tmp/no/such/dir/b.csv"
check '--csv in a missing folder: refused before the run' \
  'rc_is 1 && err_has "cannot open --csv file" && ! out_has "ms/step"'
run $T --scene=scene.xml
check '--scene without --body=buggy: refused' 'rc_is 2 && err_has "needs --body=buggy"'
run $T --body=buggy --scene="$tmp/none.xml" --steps=1
check 'a --scene that does not load: an error, not the default buggy' \
  'rc_is 1 && err_has "cannot load --scene" && ! out_has "real-time factor"'
run --bench nosuch
check 'an unknown case: refused, the cases listed' \
  'rc_is 2 && err_has "unknown case" && err_has "deformable_terrain" && err_has "render"'

# the CSV in both option forms: one header, then one row per run
run $T --contact-law --steps 20 --repeats 1 --csv "$tmp/b.csv"
check '--csv FILE: written' 'rc_is 0'
run $T --contact-law --steps=20 --repeats=1 --csv="$tmp/b.csv"
check '--csv=FILE: appended' 'rc_is 0'
check 'the CSV: one header and a row per run' \
  '[ "$(wc -l <"$tmp/b.csv")" -eq 3 ] && head -1 "$tmp/b.csv" | grep -q "^case,body,start" &&
   [ "$(grep -c "^contact_law,,warm,nonlinear,20,1," "$tmp/b.csv")" -eq 2 ]'

# a row says what ran: the contact law on no body; a body's material is
# its bed's (the plate soil is linear, n = 1, the buggy's nonlinear, none
# on rigid ground); the scene of --scene in the last column, quoted (each
# once said the default: "rigid" for the law, "nonlinear" for the plate,
# the buggy with no scene)
run $T --body=rigid --steps=2 --repeats=1 --csv="$tmp/c.csv"
run $T --body=buggy --steps=2 --repeats=1 --csv="$tmp/c.csv"
run $T --body=buggy --scene="$top_srcdir/scenes/buggy_rigid.xml" --steps=2 --repeats=1 \
  --csv="$tmp/c.csv"
check 'the CSV: the plate linear, the buggy nonlinear, the rigid-ground scene none, and named' \
  'head -1 "$tmp/c.csv" | grep -q ",newton_per_step,scene\$" &&
   sed -n 2p "$tmp/c.csv" | grep -q "^body,rigid,warm,linear,2,1,.*,\$" &&
   sed -n 3p "$tmp/c.csv" | grep -q "^body,buggy,warm,nonlinear,2,1,.*,\$" &&
   sed -n 4p "$tmp/c.csv" | grep -q "^body,buggy,warm,,2,1,.*,\"$top_srcdir/scenes/buggy_rigid.xml\"\$" &&
   out_has "(${top_srcdir}/scenes/buggy_rigid.xml)"'
echo "case,body,start" >"$tmp/old.csv"
run $T --contact-law --steps=2 --repeats=1 --csv="$tmp/old.csv"
check 'a --csv file with other columns: refused before the run, left as it was' \
  'rc_is 1 && err_has "holds other columns" && ! out_has "ns per contact visit" &&
   [ "$(cat "$tmp/old.csv")" = "case,body,start" ]'

# options the chosen case would not read: refused, not ignored
run $T --body=rigid --material=linear --steps=2 --repeats=1
check '--material without --contact-law: refused (the beds have their own soil)' \
  'rc_is 2 && err_has "--material chooses the contact law" && ! out_has "ms/step"'
for o in --body=buggy --solver=sweeps --bed-scale=3 --warmup=5 --scene=x.xml; do
  run $T --contact-law "$o" --steps=2 --repeats=1
  check "--contact-law with $o: refused" \
    'rc_is 2 && err_has "does not apply to --contact-law" && ! out_has "ns per contact visit"'
done

# engine flags, accepted and ignored by both cases
run $T --mujoco --contact-law --steps=2 --repeats=1
check 'an engine flag (--mujoco) is accepted and ignored' 'rc_is 0 && out_has "ns per contact visit"'
run --bench render --raisim --scene "$tmp/none.xml"
check 'render: an engine flag is accepted; a scene that does not load is named, without a line 0' \
  'rc_is 1 && err_has "none.xml: error:" && ! err_has ":0:"'
run --bench render --csv "$tmp/no/such/dir/r.csv"
check 'render: a --csv in a missing folder is refused before the run' \
  'rc_is 1 && err_has "cannot open --csv file" && ! out_has "render benchmark"'

echo "1..$n"
[ "$nfail" -eq 0 ]
