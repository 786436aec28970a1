#!/bin/sh
# test_cli.sh -- TAP tests of the soilsim command line (DESIGN 4.3).
#
# make check sets top_srcdir and top_builddir (absolute); by hand:
#   top_srcdir=. top_builddir=build sh tests/test_cli.sh
# Checks exit statuses (0 ok, 1 bad input or failed run, 2 bad usage), the
# file:line of input errors, that failed runs leave no output and never
# damage an existing one, determinism of exports, the export/reload round
# trip, and the CSV layout.

# The checks are shell expressions in single quotes, expanded by eval.
# shellcheck disable=SC2016

top_srcdir=${top_srcdir:-.}
top_builddir=${top_builddir:-.}
# absolute, as make check gives them: some checks run from other folders
# (a relative top_srcdir failed there when run by hand)
top_srcdir=$(cd "$top_srcdir" && pwd) || exit 1
top_builddir=$(cd "$top_builddir" && pwd) || exit 1
SOILSIM=$top_builddir/soilsim
PLATE=$top_srcdir/scenes/plate.xml

# the harness: $tmp, run, check, skip, rc_is, err_has, ...
TAP_NAME=cli
. "$top_srcdir/tests/tap.sh"
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT TERM HUP

usage_error() { rc_is 2 && err_has "try 'soilsim --help'"; }
is_png() { [ "$(head -c 4 "$1" 2>/dev/null | od -An -c | tr -d ' \n')" = "211PNG" ]; }

# ---------------------------------------------------------------------
# help, version, usage errors (exit 2), no scene needed

run --help
check "--help exits 0 and lists every option" \
  'rc_is 0 && out_has "usage: soilsim" && out_has "--steps" && out_has "--export" &&
   out_has "--csv" && out_has "--remove" && out_has "--render" &&
   out_has "--render-every" && out_has "--size" && out_has "--rut-map" &&
   out_has "--quiet" && out_has "--version"'
run --version
check "--version prints 'soilsim 0.1.0' and exits 0" \
  'rc_is 0 && [ "$(cat "$tmp/out")" = "soilsim 0.1.0" ]'
run
check "no arguments: usage error (exit 2)" 'usage_error && err_has "no scene"'
run ""
check "an empty scene name: usage error (exit 2), as --restore '' is" \
  'usage_error && err_has "scene file name is empty"'
run "" --steps 3 --export "$tmp/empty.xml"
check "an empty scene name with options: exit 2, nothing written" \
  'usage_error && no_file "$tmp/empty.xml"'
run "$PLATE" --bogus
check "unknown option: exit 2 naming it" 'usage_error && err_has "--bogus"'
run "$PLATE" --bogus=3
check "unknown option in --opt=value form: exit 2" 'usage_error && err_has "--bogus"'
run "$PLATE" -x
check "unknown short option: exit 2" 'usage_error && err_has "-x"'
run "$PLATE" --steps
check "missing value at the end: exit 2" 'usage_error && err_has "--steps"'
run "$PLATE" --export --csv "$tmp/a.csv"
check "an option in place of a value: exit 2" \
  'usage_error && err_has "--export" && no_file "$tmp/--csv"'
run "$PLATE" --steps=
check "empty --steps= value: exit 2" 'usage_error'
for v in abc -1 10x 1e3 "" 99999999999999999999999; do
  run "$PLATE" --steps "$v"
  check "--steps '$v' is rejected (exit 2)" 'usage_error'
done
# the largest step count is one less than the largest integer (the loop
# counts to it): the message gives the range, not ">= 0" for a number >= 0
run "$PLATE" --steps 9223372036854775807
check "--steps 9223372036854775807: exit 2 saying the range" \
  'usage_error && err_has "from 0 to 9223372036854775806"'
for v in 0x10 640 x480 640x 640x480x2 -640x480 20000x100 axb; do
  run "$PLATE" --size "$v" --rut-map "$tmp/r.png"
  check "--size '$v' is rejected (exit 2)" 'usage_error && err_has "--size"'
done
# three numbers, one comma (or spaces) between two ("1,,2,3" was read as 1,2,3)
i=0
for v in "1,,2,3" "1,2" ",1,2,3" "1,2,3," "1, ,2,3" "1,2,x"; do
  i=$((i + 1))
  run "$PLATE" --steps 0 --render "$tmp/camv$i" --camera-pos "$v" --camera-look-at 0,0,0
  check "--camera-pos '$v' is rejected (exit 2)" 'usage_error && err_has "--camera-pos" && no_file "$tmp/camv$i"'
done
run "$PLATE" --steps 0 --render "$tmp/camv" --size 32x32 --camera-pos " 1 , 2 3" --camera-look-at=-1,-2,-3 --quiet
check "--camera-pos ' 1 , 2 3' and --camera-look-at=-1,-2,-3 are accepted" 'rc_is 0'
run "$PLATE" --steps 5 --render "$tmp/cam0" --camera-pos 0,0,1 --camera-look-at 0,0,1
check "--camera-pos equal to --camera-look-at: exit 2 (a camera needs a direction)" \
  'usage_error && err_has "distinct points" && no_file "$tmp/cam0"'
# a rut map needs room for its colour bar and scale: refused before any step
run "$PLATE" --steps 5 --size 96x63 --rut-map "$tmp/small.png"
check "--size 96x63 with --rut-map: exit 2 before the run (at least 64 pixels high)" \
  'usage_error && err_has "at least 96 pixels wide and 64 high" && no_file "$tmp/small.png"'
# (80 wide passed this check once, ran every step and then failed: the
# colour bar and its labels need 74 pixels beside the map)
run "$PLATE" --steps 5 --size 80x200 --rut-map "$tmp/small.png" --csv "$tmp/small.csv"
check "--size 80x200 with --rut-map: exit 2 before the run (at least 96 pixels wide)" \
  'usage_error && err_has "at least 96 pixels wide" && no_file "$tmp/small.png" && no_file "$tmp/small.csv"'
run "$PLATE" --steps 5 --size 96x64 --rut-map "$tmp/small.png"
check "--size 96x64 with --rut-map: the smallest rut map is written" \
  'rc_is 0 && is_png "$tmp/small.png"'
for v in plate @5 plate@ plate@x plate@-1 plate@1.5; do
  run "$PLATE" --remove "$v"
  check "--remove '$v' is rejected (exit 2)" 'usage_error && err_has "--remove"'
done
run "$PLATE" --remove plate@5 --remove plate@7
check "--remove naming the same system twice: exit 2" 'usage_error'
run "$PLATE" --steps 10 --remove plate@11
check "--remove after the last step: exit 2" 'usage_error && err_has "plate@11"'
run "$PLATE" --render-every 0 --render "$tmp/f0"
check "--render-every 0 is rejected (exit 2)" 'usage_error && no_file "$tmp/f0"'
run "$PLATE" --render-every 5
check "--render-every without --render: exit 2" 'usage_error'
run "$PLATE" "$PLATE"
check "two scene files: exit 2" 'usage_error'
run "$PLATE" --quiet=1
check "a value given to a flag: exit 2" 'usage_error && err_has "--quiet"'
run "$PLATE" --export "$tmp/same" --csv "$tmp/same"
check "--export and --csv on one path: exit 2" 'usage_error'

# Outputs that are not new plain files, and one file under two spellings.
# A character device or FIFO is written in place: the atomic writer's
# rename put a regular file in its place (as root, /dev/null itself).  A
# symbolic link is followed (its target replaced, the link kept), and a
# replaced file keeps its mode (a 0600 file came back 0644).  Two outputs
# on one file (./, a link, the --render folder or one of its frame names)
# are refused before the first step and create nothing.
if [ "$(id -u)" -eq 0 ]; then
  mkdir "$tmp/dev"
  for d in csv xml png ckpt; do mknod "$tmp/dev/null.$d" c 1 3; done
  run "$PLATE" --steps 3 --csv "$tmp/dev/null.csv" --export "$tmp/dev/null.xml" \
    --rut-map "$tmp/dev/null.png" --checkpoint "$tmp/dev/null.ckpt@2" --quiet
  check "outputs to copies of /dev/null (mknod c 1 3): written in place, still devices" \
    'rc_is 0 && [ -c "$tmp/dev/null.csv" ] && [ -c "$tmp/dev/null.xml" ] &&
     [ -c "$tmp/dev/null.png" ] && [ -c "$tmp/dev/null.ckpt" ] && no_tmp "$tmp/dev"'
  # the export goes to a FIFO: checked before the first step without being
  # opened (the reader would see an end of file), then written in place
  mkfifo "$tmp/dev/fifo"
  cat "$tmp/dev/fifo" >"$tmp/dev/fifo.xml" &
  reader=$!
  run "$PLATE" --steps 3 --export "$tmp/dev/fifo" --quiet
  i=0
  while [ $i -lt 50 ] && kill -0 "$reader" 2>/dev/null; do
    sleep 0.1 2>/dev/null || sleep 1
    i=$((i + 1))
  done
  kill "$reader" 2>/dev/null
  wait "$reader" 2>/dev/null
  rc1=$rc
  run "$PLATE" --steps 3 --export "$tmp/dev/plain.xml" --quiet
  check "--export to a FIFO: its reader gets the whole export, the FIFO stays" \
    '[ "$rc1" -eq 0 ] && [ -p "$tmp/dev/fifo" ] && [ -s "$tmp/dev/plain.xml" ] &&
     cmp -s "$tmp/dev/fifo.xml" "$tmp/dev/plain.xml" && no_tmp "$tmp/dev"'
else
  skip "not root: no device node (mknod) for the output tests"
  skip "not root: the FIFO output test is run as root only"
fi
# /dev/stdout is a link to /proc/self/fd/1; a link of our own to it is
# the same output, and a writer that renamed over it would replace only
# that link, never the system's /dev/stdout
if [ -e /proc/self/fd/1 ] && ln -s /proc/self/fd/1 "$tmp/stdout"; then
  last_cmd="soilsim --steps 3 --csv $tmp/stdout | cat"
  CI='' $TIMEOUT "$SOILSIM" "$PLATE" --steps 3 --csv "$tmp/stdout" 2>"$tmp/err" |
    cat >"$tmp/piped.csv"
  rc=$?
  check "--csv /dev/stdout (a link to /proc/self/fd/1) into a pipe: the CSV alone, the summary on stderr" \
    'rc_is 0 && [ -L "$tmp/stdout" ] && [ "$(wc -l <"$tmp/piped.csv")" -eq 4 ] &&
     head -n 1 "$tmp/piped.csv" | grep -q "^step,time," && err_has "csv         $tmp/stdout"'
else
  skip "no /proc/self/fd/1 to stand for /dev/stdout"
fi
mkdir "$tmp/linked"
echo "old" >"$tmp/linked/target.csv"
ln -s linked/target.csv "$tmp/link.csv"
run "$PLATE" --steps 3 --csv "$tmp/link.csv" --quiet
check "--csv to a symbolic link: the file it points to is replaced, the link stays" \
  'rc_is 0 && [ -L "$tmp/link.csv" ] && [ "$(wc -l <"$tmp/linked/target.csv")" -eq 4 ] &&
   no_tmp "$tmp" && no_tmp "$tmp/linked"'
echo "old" >"$tmp/private.xml"
chmod 600 "$tmp/private.xml"
run "$PLATE" --steps 3 --export "$tmp/private.xml" --quiet
check "a replaced 0600 file stays 0600" \
  'rc_is 0 && grep -q "<raisim" "$tmp/private.xml" &&
   [ "$(ls -l "$tmp/private.xml" | cut -c1-10)" = "-rw-------" ]'
run "$PLATE" --steps 5 --export "$tmp/same.xml" --csv "$tmp/./same.xml"
check "--export F and --csv ./F: exit 2 naming both, nothing written" \
  'usage_error && err_has "--export" && err_has "--csv" && no_file "$tmp/same.xml"'
run "$PLATE" --steps 5 --export "$tmp/same.xml" --checkpoint "$tmp/./same.xml@1"
check "--export F and --checkpoint ./F@1: exit 2 naming both" \
  'usage_error && err_has "--export" && err_has "--checkpoint" && no_file "$tmp/same.xml"'
run "$PLATE" --steps 5 --checkpoint "$tmp/k@1" --checkpoint "$tmp/./k@0"
check "--checkpoint K@1 and --checkpoint ./K@0: exit 2" \
  'usage_error && err_has "--checkpoint" && no_file "$tmp/k"'
run "$PLATE" --steps 5 --export "$tmp/linked/target.csv" --csv "$tmp/link.csv"
check "--export F and --csv LINK-TO-F: exit 2 naming both" \
  'usage_error && err_has "--export" && err_has "--csv"'
for o in --rut-map --export --csv; do
  run "$PLATE" --steps 5 --render "$tmp/D" "$o" "$tmp/D"
  check "--render D and $o D: exit 2 before the first step, no folder D" \
    'usage_error && err_has "--render" && err_has "$o" && no_file "$tmp/D"'
done
run "$PLATE" --steps 5 --render "$tmp/D" --checkpoint "$tmp/D@2"
check "--render D and --checkpoint D@2: exit 2, no folder D" \
  'usage_error && err_has "--render" && err_has "--checkpoint" && no_file "$tmp/D"'
run "$PLATE" --steps 1 --render "$tmp/fr" --rut-map "$tmp/fr/frame_000001.png"
check "--render fr and --rut-map fr/frame_000001.png (a frame): exit 2, no folder" \
  'usage_error && err_has "--render" && err_has "--rut-map" && no_file "$tmp/fr"'

# ---------------------------------------------------------------------
# bad input (exit 1): the message names the file and the line

run "$tmp/no-such-scene.xml" --steps 1
check "missing scene file: exit 1 naming the file" \
  'rc_is 1 && err_has "no-such-scene.xml" && err_has "error:"'

# Every file in tests/data/bad starts with <!-- expect: LINE: SUBSTRING -->.
nbad=0
for f in "$top_srcdir"/tests/data/bad/*.xml; do
  [ -f "$f" ] || continue
  nbad=$((nbad + 1))
  b=$(basename "$f")
  expect_line "$f"
  line=$expect_n
  sub=$expect_sub
  if [ -z "$line" ] || [ -z "$sub" ]; then
    check "bad/$b has an expect line ('<!-- expect: LINE: SUBSTRING -->')" false
    continue
  fi
  if [ "$line" -gt 0 ]; then where="$b:$line:"; else where="$b: "; fi
  rm -f "$tmp/bad.xml" "$tmp/bad.csv"
  run "$f" --steps 5 --export "$tmp/bad.xml" --csv "$tmp/bad.csv"
  check "bad/$b: exit 1, '$where', '$sub', no output files" \
    'rc_is 1 && err_has "$where" && err_has "$sub" && err_has "error:" &&
     no_file "$tmp/bad.xml" && no_file "$tmp/bad.csv" && no_tmp "$tmp"'
done
[ "$nbad" -gt 0 ] || skip "no files in tests/data/bad"

run "$PLATE" --steps 2000000000 --csv "$tmp/u.csv" --remove nosuchbody@0
check "--remove of an unknown name: exit 1 before stepping, lists the systems" \
  'rc_is 1 && err_has "nosuchbody" && err_has "plate" && no_file "$tmp/u.csv" &&
   no_tmp "$tmp"'

run "$PLATE" --steps 2000000000 --export /nonexistent/dir/x.xml
check "unwritable --export path: exit 1 before stepping, names the path" \
  'rc_is 1 && err_has "/nonexistent/dir/x.xml" && no_file /nonexistent/dir/x.xml'
run "$PLATE" --steps 2000000000 --csv /nonexistent/dir/x.csv
check "unwritable --csv path: exit 1 before stepping, naming the option" \
  'rc_is 1 && err_has "/nonexistent/dir/x.csv" && err_has "error: --csv: cannot write"'
run "$PLATE" --steps 2000000000 --csv "$tmp"
check "--csv naming a directory: exit 1 before stepping" \
  'rc_is 1 && err_has "--csv: cannot write: is a directory"'
# a name of the longest legal length (255 bytes): its temporary file's name
# is cut to stay legal too (it failed, "File name too long")
long=$(printf '%0255d' 0)
mkdir -p "$tmp/long"
run "$PLATE" --steps 2 --csv "$tmp/long/$long" --export "$tmp/long/x$(printf '%0254d' 0)" --quiet
check "outputs named with 255 characters are written, no temporary file left" \
  'rc_is 0 && [ -s "$tmp/long/$long" ] && [ -s "$tmp/long/x$(printf "%0254d" 0)" ] && no_tmp "$tmp/long"'
run "$PLATE" --steps 2000000000 --export "$tmp"
check "--export naming a directory: exit 1 before stepping" \
  'rc_is 1 && err_has "directory"'
: >"$tmp/plainfile"
run "$PLATE" --steps 2000000000 --render "$tmp/plainfile/frames"
check "--render folder that cannot be created: exit 1 before stepping" \
  'rc_is 1 && err_has "plainfile" && no_tmp "$tmp"'

# the --render folder is tried with the name of the first frame, which is
# written: a folder named like a made-up probe file does not stop the run
mkdir -p "$tmp/probe/frame_probe.png"
run "$PLATE" --steps 2 --render "$tmp/probe" --size 16x16 --quiet
check "--render folder holding a folder frame_probe.png: frames written" \
  'rc_is 0 && [ -s "$tmp/probe/frame_000002.png" ] && no_tmp "$tmp/probe"'
mkdir -p "$tmp/probe2/frame_000000.png"
run "$PLATE" --steps 2000000000 --render "$tmp/probe2" --size 16x16
check "--render folder whose frame_000000.png is a folder: exit 1 before stepping, naming it" \
  'rc_is 1 && err_has "probe2/frame_000000.png" && err_has "directory"'

# The final outputs appear together or not at all: an export that fails
# at the end (a copy of /dev/full: every write fails) leaves no rut map
# and no CSV (the rut map was committed before the export was written)
if [ "$(id -u)" -eq 0 ]; then
  mkdir -p "$tmp/full"
  mknod "$tmp/full/e.xml" c 1 7
  run "$PLATE" --steps 3 --rut-map "$tmp/full/r.png" --csv "$tmp/full/c.csv" \
    --export "$tmp/full/e.xml"
  check "an export that fails at the end: exit 1, no rut map, no CSV, no temporary file" \
    'rc_is 1 && err_has "e.xml" && no_file "$tmp/full/r.png" && no_file "$tmp/full/c.csv" &&
     no_tmp "$tmp/full"'
  echo old >"$tmp/full/r2.png"
  run "$PLATE" --steps 3 --rut-map "$tmp/full/r2.png" --export "$tmp/full/e.xml"
  check "an export that fails at the end: an existing rut map stays as it was" \
    'rc_is 1 && [ "$(cat "$tmp/full/r2.png")" = old ] && no_tmp "$tmp/full"'
  # a summary that cannot be written fails the run (it exited 0)
  mknod "$tmp/full/stdout" c 1 7
  last_cmd="soilsim $PLATE --steps 3 --csv $tmp/full/s.csv >(a copy of /dev/full)"
  CI='' $TIMEOUT "$SOILSIM" "$PLATE" --steps 3 --csv "$tmp/full/s.csv" \
    >"$tmp/full/stdout" 2>"$tmp/err"
  rc=$?
  check "standard output full: exit 1, the summary not written, the CSV complete" \
    'rc_is 1 && err_has "summary could not be written to standard output" &&
     [ "$(wc -l <"$tmp/full/s.csv")" -eq 4 ]'
else
  skip "an export that fails at the end (mknod needs root)"
  skip "an export that fails at the end: an existing rut map (mknod needs root)"
  skip "standard output full (mknod needs root)"
fi

# A failed run never touches an existing output file.
cat >"$tmp/broken.xml" <<'EOF'
<raisim version="1.0">
  <timeStep value="0.001"/>
  <objects>
    <box name="b" mass="1"> <dim x="1" y="1" z="1"/>
</raisim>
EOF
echo "precious export" >"$tmp/keep.xml"
echo "precious csv" >"$tmp/keep.csv"
run "$tmp/broken.xml" --steps 5 --export "$tmp/keep.xml" --csv "$tmp/keep.csv"
check "failed run: exit 1 and the existing --export/--csv files stay intact" \
  'rc_is 1 && err_has "broken.xml" && [ "$(cat "$tmp/keep.xml")" = "precious export" ] &&
   [ "$(cat "$tmp/keep.csv")" = "precious csv" ] && no_tmp "$tmp"'

# A step that fails (the state becomes non-finite) ends the run: exit 1,
# no outputs, existing files untouched.
cat >"$tmp/blowup.xml" <<'EOF'
<raisim version="1.0">
  <timeStep value="0.001"/>
  <gravity value="0 0 -1e306"/>
  <objects>
    <box name="b" mass="1"> <dim x="0.1" y="0.1" z="0.1"/>
      <state pos="0 0 1" lin_vel="0 0 -1.7e308"/> </box>
  </objects>
</raisim>
EOF
rm -f "$tmp/blow.csv"
run "$tmp/blowup.xml" --steps 10 --export "$tmp/keep.xml" --csv "$tmp/blow.csv"
check "failed step: exit 1 naming the step, no CSV, existing export intact" \
  'rc_is 1 && err_has "blowup.xml" && err_has "step" && no_file "$tmp/blow.csv" &&
   [ "$(cat "$tmp/keep.xml")" = "precious export" ] && no_tmp "$tmp"'

# ---------------------------------------------------------------------
# successful runs

N=300
run "$PLATE" --steps $N --export "$tmp/a.xml" --csv "$tmp/a.csv"
check "plate.xml, $N steps with --export and --csv: exit 0, quiet stderr" \
  'rc_is 0 && [ -s "$tmp/a.xml" ] && [ -s "$tmp/a.csv" ] && [ ! -s "$tmp/err" ] &&
   no_tmp "$tmp"'
check "the summary names the outputs written" \
  'out_has "$tmp/a.xml" && out_has "$tmp/a.csv" && out_has "steps"'
run "$PLATE" --steps=$N --export="$tmp/b.xml" --quiet
check "--opt=value forms and --quiet: exit 0, nothing on stdout or stderr" \
  'rc_is 0 && [ ! -s "$tmp/out" ] && [ ! -s "$tmp/err" ]'
check "two runs give byte-identical exports" 'cmp -s "$tmp/a.xml" "$tmp/b.xml"'

run "$tmp/a.xml" --steps 0 --export "$tmp/c.xml" --quiet
check "export, reload with --steps 0, export again: identical files" \
  'rc_is 0 && cmp -s "$tmp/a.xml" "$tmp/c.xml"'

# an articulated system (URDF with a pin closure, a coil-over and a PD) on
# soil: runs, exports its state, reloads and continues identically
run "$top_srcdir/scenes/plate_arm.xml" --steps 20 --export "$tmp/arm1.xml" --quiet
check "articulated scene on soil runs and exports" \
  'rc_is 0 && grep -q "<articulated_system name=\"carrier\"" "$tmp/arm1.xml" && grep -q "<pd joint=\"arm_a_joint\"" "$tmp/arm1.xml"'
run "$tmp/arm1.xml" --steps 0 --export "$tmp/arm2.xml" --quiet
check "articulated export, reload, export again: identical files" \
  'rc_is 0 && cmp -s "$tmp/arm1.xml" "$tmp/arm2.xml"'

# the URDF and resource folder of an export are named from the export's own
# folder, where the reader looks for them: an export written into another
# folder (a subfolder, through "..", from another working folder) loads
# again, nothing depends on the working folder, and a copy of the whole
# tree loads its own assets
w=$tmp/paths
mkdir -p "$w/scenes" "$w/assets" "$w/sub" "$w/other"
cp -R "$top_srcdir/assets/plate_arm" "$w/assets/"
sed 's|urdf_path="[^"]*"|& res_dir="[THIS_DIR]/../assets/plate_arm"|' \
  "$top_srcdir/scenes/plate_arm.xml" >"$w/scenes/plate_arm.xml"
urdf_rel='urdf_path="../assets/plate_arm/plate_arm.urdf" res_dir="../assets/plate_arm"'
here=$(pwd)
SOILSIM_REL=$SOILSIM
SOILSIM=$(cd "$(dirname "$SOILSIM")" && pwd)/soilsim
cd "$w" || exit 1
run scenes/plate_arm.xml --steps 10 --export sub/pa.xml --quiet
check "export into a subfolder: the URDF and res_dir are named from there" \
  'rc_is 0 && grep -qF "$urdf_rel" sub/pa.xml'
run sub/pa.xml --steps 1 --export sub/pa1.xml --quiet
check "an export in a subfolder loads again and steps" 'rc_is 0 && [ -s sub/pa1.xml ]'
run sub/pa.xml --steps 0 --export sub/../scenes/./../other/pa.xml --quiet
check "export through '..' into another folder: the same paths, loads from elsewhere" \
  'rc_is 0 && grep -qF "$urdf_rel" other/pa.xml &&
   (cd / && "$SOILSIM" "$w/other/pa.xml" --steps 1 --quiet)'
run scenes/plate_arm.xml --steps 10 --export ./here.xml --quiet
run ./here.xml --steps 0 --export ./here2.xml --quiet
check "export into the working folder: no './' prefix, export -> reload -> export identical" \
  'rc_is 0 && grep -qF "urdf_path=\"assets/plate_arm/plate_arm.urdf\"" here.xml &&
   cmp -s here.xml here2.xml'
cd "$w/sub" || exit 1
run pa.xml --steps 0 --export pa2.xml --quiet
check "export, reload from inside its folder, export again: identical files" \
  'rc_is 0 && cmp -s pa.xml pa2.xml'
cd "$tmp" || exit 1
run paths/sub/pa.xml --steps 0 --export paths/sub/pa3.xml --quiet
check "export, reload from another working folder, export again: identical files" \
  'rc_is 0 && cmp -s paths/sub/pa.xml paths/sub/pa3.xml'
cp -R "$w" "$tmp/moved"
rm -rf "$w/assets"
run moved/sub/pa.xml --steps 1 --quiet
check "a copy of the folder with the export and its assets loads on its own" 'rc_is 0'
cd "$here" || exit 1
SOILSIM=$SOILSIM_REL
# an XML export holds the whole state (with the reference configuration the
# closures were derived from) but not the solver's warm-start cache, which
# checkpoints carry; with warm starts off a reloaded export continues bit
# for bit
sed 's|<objects>|<contact_solver terrain_warm_start="false"/><objects>|' \
  "$top_srcdir/scenes/plate_arm.xml" | sed "s|\\[THIS_DIR\\]|$top_srcdir/scenes|" >"$tmp/arm_cold.xml"
run "$tmp/arm_cold.xml" --steps 30 --export "$tmp/arm3.xml" --quiet
run "$tmp/arm_cold.xml" --steps 20 --export "$tmp/arm5.xml" --quiet
run "$tmp/arm5.xml" --steps 10 --export "$tmp/arm4.xml" --quiet
check "cold start: 20 steps, export, reload, 10 more = 30 steps straight (articulated)" \
  'rc_is 0 && cmp -s "$tmp/arm3.xml" "$tmp/arm4.xml"'

head -n 1 "$tmp/a.csv" >"$tmp/header"
check "CSV header: the statistics columns, then plate.x,plate.y,plate.z" \
  '[ "$(cat "$tmp/header")" = "step,time,soil_contacts,soil_contact_area,soil_normal_force,sweeps,newton,residual,converged,plate.x,plate.y,plate.z" ]'
check "CSV has one row per step ($N rows)" \
  '[ "$(sed 1d "$tmp/a.csv" | wc -l)" -eq $N ]'
check "CSV rows are numbered 1..$N and have as many fields as the header" \
  'awk -F, -v n=$N "NR == 1 { nf = NF; next }
     NF != nf || \$1 != NR - 1 { bad = 1 }
     END { exit bad || NR != n + 1 }" "$tmp/a.csv"'
check "CSV: the plate has sunk into the soil (z below 0.025 at the end)" \
  'tail -n 1 "$tmp/a.csv" | awk -F, "{ exit !(\$12 < 0.025 && \$12 > 0) }"'
check "CSV: the solver columns (newton, residual, converged): every plate step converged" \
  'awk -F, "NR == 1 { next } !(\$7 >= 0 && \$8 >= 0 && \$8 <= 1e-9 && \$9 == 1) { bad = 1 }
     END { exit bad }" "$tmp/a.csv"'

# An articulated system's columns are its base link's frame, where its
# <state pos> puts it (-6.2 0 0.3611 on rigid ground, still there after a
# step), not the link's centre of mass (0.25 m behind and 0.2 m above it)
run "$top_srcdir/scenes/buggy_rigid.xml" --steps 1 --csv "$tmp/frame.csv" --quiet
check "CSV: the buggy's position is its base frame's (x -6.2, z 0.3611 after a step)" \
  'rc_is 0 && [ "$(head -n 1 "$tmp/frame.csv" | cut -d, -f10-)" = "buggy.x,buggy.y,buggy.z" ] &&
   tail -n 1 "$tmp/frame.csv" | awk -F, "{ exit !(\$10 > -6.201 && \$10 < -6.199 &&
     \$12 > 0.360 && \$12 < 0.362) }"'

# A removed system keeps its columns, empty from the row after its step.
run "$PLATE" --steps 20 --csv "$tmp/r.csv" --remove plate@10 --quiet
check "--remove plate@10: exit 0; rows 1..10 have positions, 11..20 are empty" \
  'rc_is 0 && awk -F, "NR == 1 { next }
     NR <= 11 && \$10 == \"\" { bad = 1 }
     NR > 11 && (\$10 != \"\" || \$11 != \"\" || \$12 != \"\") { bad = 1 }
     END { exit bad || NR != 21 }" "$tmp/r.csv"'
run "$PLATE" --steps 5 --csv "$tmp/r0.csv" --remove plate@0 --quiet
check "--remove plate@0 applies before the first step" \
  'rc_is 0 && awk -F, "NR > 1 && \$10 != \"\" { bad = 1 } END { exit bad }" "$tmp/r0.csv"'

run "$PLATE" --steps 0 --export "$tmp/zero.xml" --csv "$tmp/zero.csv" --quiet
check "--steps 0: exit 0, export written, CSV has only its header" \
  'rc_is 0 && [ -s "$tmp/zero.xml" ] && [ "$(wc -l <"$tmp/zero.csv")" -eq 1 ]'

# The progress line: only on a terminal, not with --quiet, not under CI.
# script(1) gives the program a pseudo-terminal.
if command -v script >/dev/null 2>&1 &&
   script -qec true /dev/null >/dev/null 2>&1; then
  tty_run() {
    last_cmd="(on a terminal) $2 soilsim $1"
    # shellcheck disable=SC2086
    env $2 $TIMEOUT script -qec "'$SOILSIM' '$PLATE' --steps 50 $1" /dev/null \
      >"$tmp/out" 2>"$tmp/err" </dev/null
    rc=$?
  }
  tty_run "" "CI="
  check "on a terminal: a progress line with %, steps/s and ETA, then erased" \
    'rc_is 0 && out_has "100%" && out_has "steps/s" && out_has "ETA" &&
     out_has "$(printf "\r\033[K")"'
  tty_run "" "CI=true"
  check "on a terminal with CI set: no progress line, the summary stays" \
    'rc_is 0 && ! out_has "steps/s" && out_has "wall time"'
  tty_run "--quiet" "CI="
  check "on a terminal with --quiet: nothing at all" \
    'rc_is 0 && ! out_has "steps/s" && ! out_has "wall time"'
else
  skip "script(1) cannot make a terminal here"
  skip "script(1) cannot make a terminal here"
  skip "script(1) cannot make a terminal here"
fi

# The summary names the last step's sweeps and Newton iterations (the
# settling plate: the Newton phase solves it and leaves no sweeps).
run "$PLATE" --steps 50
check "the summary reports the last step's sweeps and Newton iterations" \
  'rc_is 0 && out_has "sweeps      0 after 1 Newton iteration (last step)"'

# ... and, where the creeping solve ran, its passes apart (drag.xml's
# step 1159: its plate comes to rest rocking, stick and slip mixed).
run "$top_srcdir/scenes/drag.xml" --steps 1159
check "the summary reports the creeping solve's passes apart from Newton's iterations" \
  'rc_is 0 && out_has "Newton iterations and " && out_has " creeping passes (last step)"'

# An existing output file is replaced whole.
echo "old" >"$tmp/old.xml"
run "$PLATE" --steps 10 --export "$tmp/old.xml" --quiet
check "an existing --export file is replaced" \
  'rc_is 0 && ! grep -q "^old$" "$tmp/old.xml" && grep -q "<raisim" "$tmp/old.xml"'

# ---------------------------------------------------------------------
# images: --render frames and --rut-map (PNG signature checked)


run "$PLATE" --steps 10 --rut-map "$tmp/rut.png" --size 200x150 --quiet
check "--rut-map writes a PNG" 'rc_is 0 && is_png "$tmp/rut.png"'
# the rut map's font is loaded before the first step: a missing one was
# found only when the map was drawn, after every step had run
export SOILSIM_FONT="$tmp/no-such-font.ttf"
run "$PLATE" --steps 2000000000 --rut-map "$tmp/nofont.png" --csv "$tmp/nofont.csv"
check "SOILSIM_FONT naming no file, --rut-map: exit 1 before stepping, naming it" \
  'rc_is 1 && err_has "no-such-font.ttf" && err_has "SOILSIM_FONT" &&
   no_file "$tmp/nofont.png" && no_file "$tmp/nofont.csv"'
FONT_FILE=/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf
export SOILSIM_FONT="$FONT_FILE"
run "$PLATE" --steps 3 --rut-map "$tmp/font.png" --size 200x150 --quiet
if [ -r "$FONT_FILE" ]; then
  check "SOILSIM_FONT naming a font: the rut map is written with it" \
    'rc_is 0 && is_png "$tmp/font.png"'
else
  skip "SOILSIM_FONT naming a font (no $FONT_FILE here)"
fi
unset SOILSIM_FONT
# the frames' folder is made before the other outputs are checked, so an
# output may lie in it (it failed, "No such file or directory"); a run that
# fails before its first frame takes the folders it made away again
run "$PLATE" --steps 5 --render "$tmp/newdir/D" --checkpoint "$tmp/newdir/D/k@3" --quiet
check "--render D --checkpoint D/k@3 with D not there yet: both written" \
  'rc_is 0 && [ -s "$tmp/newdir/D/k" ] && is_png "$tmp/newdir/D/frame_000005.png"'
run "$PLATE" --steps 5 --render "$tmp/gone/a/b" --export "$tmp/no/such/x.xml" --quiet
check "a run refused before its first frame leaves no folder it made" \
  'rc_is 1 && err_has "--export" && no_file "$tmp/gone"'
run "$PLATE" --steps 10 --render "$tmp/frames/sub" --render-every 4 \
  --size 160x120 --quiet
check "--render creates the folder; frames 0, 4, 8 and the last step (10)" \
  'rc_is 0 && is_png "$tmp/frames/sub/frame_000000.png" &&
   is_png "$tmp/frames/sub/frame_000004.png" &&
   is_png "$tmp/frames/sub/frame_000008.png" &&
   is_png "$tmp/frames/sub/frame_000010.png" &&
   [ "$(ls "$tmp/frames/sub" | wc -l)" -eq 4 ]'
run "$PLATE" --steps 2 --render "$tmp/frames/slash/" --size 160x120
check "--render DIR/: the summary names DIR/frame_*.png, not DIR//frame_*.png" \
  'rc_is 0 && is_png "$tmp/frames/slash/frame_000002.png" &&
   out_has "$tmp/frames/slash/frame_*.png (2)" && ! out_has "//frame"'

cat >"$tmp/nosoil.xml" <<'EOF'
<raisim version="1.0">
  <timeStep value="0.001"/>
  <objects>
    <ground name="ground" height="0"/>
    <box name="b" mass="1"> <dim x="0.1" y="0.1" z="0.1"/>
      <state pos="0 0 0.05"/> </box>
  </objects>
</raisim>
EOF
run "$tmp/nosoil.xml" --steps 2000000000 --rut-map "$tmp/none.png"
check "--rut-map on a scene without a soil bed: exit 1 before stepping" \
  'rc_is 1 && err_has "soil" && no_file "$tmp/none.png"'

# ---------------------------------------------------------------------
# checkpoints (DESIGN 5) and solver options from the command line

run --help
check "--help lists --checkpoint, --restore and the solver options" \
  'rc_is 0 && out_has "--checkpoint" && out_has "--restore" &&
   out_has "--solver-tolerance" && out_has "--max-sweeps" && out_has "--warm-start"'

for v in x @5 x@ x@-1 x@1.5 x@y "x@ 5"; do
  run "$PLATE" --steps 10 --checkpoint "$v"
  check "--checkpoint '$v' is rejected (exit 2)" 'usage_error && err_has "--checkpoint"'
done
run "$PLATE" --steps 10 --checkpoint "$tmp/k.ckpt@11"
check "--checkpoint after the last step: exit 2" \
  'usage_error && err_has "k.ckpt@11" && no_file "$tmp/k.ckpt"'
run "$PLATE" --steps 10 --checkpoint "$tmp/k.ckpt@3" --checkpoint "$tmp/k.ckpt@5"
check "--checkpoint writing one file twice: exit 2" 'usage_error && no_file "$tmp/k.ckpt"'
run "$PLATE" --steps 10 --checkpoint "$tmp/k.xml@3" --export "$tmp/k.xml"
check "--checkpoint and --export on one path: exit 2" 'usage_error && no_file "$tmp/k.xml"'
run "$PLATE" --steps 10 --restore
check "--restore without a value: exit 2" 'usage_error && err_has "--restore"'
run --restore "$tmp/k.ckpt" --steps 10
check "--restore without a scene: exit 2, the scene is needed" \
  'usage_error && err_has "needs the scene"'
for v in 0 1 -0.1 1e0 abc nan inf 0x1p-3 1e-3x ""; do
  run "$PLATE" --steps 10 --solver-tolerance "$v"
  check "--solver-tolerance '$v' is rejected (exit 2)" 'usage_error && err_has "--solver-tolerance"'
done
for v in 0 -1 1000001 2.5 x; do
  run "$PLATE" --steps 10 --max-sweeps "$v"
  check "--max-sweeps '$v' is rejected (exit 2)" 'usage_error && err_has "--max-sweeps"'
done
for v in yes 1 ON true ""; do
  run "$PLATE" --steps 10 --warm-start "$v"
  check "--warm-start '$v' is rejected (exit 2)" 'usage_error && err_has "--warm-start"'
done
run "$PLATE" --steps 2000000000 --checkpoint /nonexistent/dir/k.ckpt@5
check "unwritable --checkpoint path: exit 1 before stepping, names the path" \
  'rc_is 1 && err_has "/nonexistent/dir/k.ckpt"'

# the solver options from the command line reach the export
run "$PLATE" --steps 5 --max-sweeps 7 --solver-tolerance 1e-6 --warm-start off \
  --export "$tmp/opt.xml" --quiet
check "--max-sweeps, --solver-tolerance, --warm-start override <contact_solver> in the export" \
  'rc_is 0 && grep -q "<contact_solver max_sweeps=\"7\" tolerance=\"1e-06\"" "$tmp/opt.xml" &&
   grep -q "terrain_warm_start=\"false\"" "$tmp/opt.xml"'

# N steps straight = K steps, checkpoint, restore, N - K steps: identical
# exports, identical final checkpoints, identical CSV rows
roundtrip() { # SCENE N K NAME [EXTRA OPTIONS...]
  rt_scene=$1 rt_n=$2 rt_k=$3 rt_name=$4
  shift 4
  rm -f "$tmp/$rt_name".*
  run "$rt_scene" --steps "$rt_n" --export "$tmp/$rt_name.a.xml" --csv "$tmp/$rt_name.a.csv" \
    --checkpoint "$tmp/$rt_name.k.ckpt@$rt_k" --checkpoint "$tmp/$rt_name.n.ckpt@$rt_n" --quiet "$@"
  rt_rc1=$rc
  run "$rt_scene" --steps $((rt_n - rt_k)) --restore "$tmp/$rt_name.k.ckpt" \
    --export "$tmp/$rt_name.b.xml" --csv "$tmp/$rt_name.b.csv" \
    --checkpoint "$tmp/$rt_name.m.ckpt@$((rt_n - rt_k))" --quiet "$@"
  [ "$rt_rc1" -eq 0 ] && rc_is 0 && cmp -s "$tmp/$rt_name.a.xml" "$tmp/$rt_name.b.xml"
}
csv_tail_same() { # NAME K: rows after step K of the straight run = the restored run's rows
  sed "1,$(($2 + 1))d" "$tmp/$1.a.csv" | cut -d, -f2- >"$tmp/$1.ta"
  sed 1d "$tmp/$1.b.csv" | cut -d, -f2- >"$tmp/$1.tb"
  [ -s "$tmp/$1.ta" ] && cmp -s "$tmp/$1.ta" "$tmp/$1.tb"
}
check "plate: 100 steps = 40, --checkpoint, --restore, 60: byte-identical exports" \
  'roundtrip "$PLATE" 100 40 plate'
check "plate: the final checkpoints of both runs are byte-identical" \
  'cmp -s "$tmp/plate.n.ckpt" "$tmp/plate.m.ckpt"'
check "plate: the restored run's CSV rows (time continuing from 0.04 s) equal rows 41..100" \
  'csv_tail_same plate 40 && sed -n 2p "$tmp/plate.b.csv" | grep -q "^1,0\.041"'
check "plate with --warm-start off: byte-identical exports after a restore" \
  'roundtrip "$PLATE" 80 30 platecold --warm-start off && csv_tail_same platecold 30'
check "plate_arm (articulated, PD, closure): 40 steps = 15 + restore + 25, identical exports" \
  'roundtrip "$top_srcdir/scenes/plate_arm.xml" 40 15 arm && csv_tail_same arm 15'
check "plate_arm with --warm-start off: identical exports after a restore" \
  'roundtrip "$top_srcdir/scenes/plate_arm.xml" 30 10 armcold --warm-start off'
# a plate dragged by a horizontal force through the soil
sed -e 's|<state pos="0 0 0.025" quat="1 0 0 0" lin_vel="0 0 0" ang_vel="0 0 0"/>|&<external_force force="120 0 0" torque="0 0 0" start="0.02"/>|' \
  "$PLATE" >"$tmp/dragged.xml"
check "dragged plate: 120 steps = 70 + restore + 50, identical exports" \
  'grep -q external_force "$tmp/dragged.xml" && roundtrip "$tmp/dragged.xml" 120 70 drag &&
   csv_tail_same drag 70'
check "the buggy (closures, coil-overs, PD drive on soil): 60 steps = 25 + restore + 35" \
  'roundtrip "$top_srcdir/scenes/buggy.xml" 60 25 buggy && csv_tail_same buggy 25'
# the same world as an export: a checkpoint restores into it
run "$top_srcdir/scenes/plate_arm.xml" --steps 10 --export "$tmp/armx.xml" \
  --checkpoint "$tmp/armx.ckpt@10" --quiet
run "$tmp/armx.xml" --steps 5 --restore "$tmp/armx.ckpt" --export "$tmp/armx1.xml" --quiet
rc1=$rc
run "$top_srcdir/scenes/plate_arm.xml" --steps 15 --export "$tmp/armx2.xml" --quiet
check "a checkpoint restores into an export of its world (plate_arm): identical to 15 steps straight" \
  '[ "$rc1" -eq 0 ] && rc_is 0 && cmp -s "$tmp/armx1.xml" "$tmp/armx2.xml"'
# every scene: export -> reload -> export gives the same bytes, and a
# checkpoint restores into the export.  The reader numbers the contact
# materials as it meets their names; buggy_rigid.xml names the buggy's
# rubber before the ground's concrete, which an export listing grounds
# first turned round (its pair_prop's names swapped, its checkpoints
# refused as "a different world")
# round_trip SCENE NAME STEPS WHAT: run, export and checkpoint at STEPS;
# export the export again; restore the checkpoint into the export
# (check evaluates its condition later: the name goes in rt_name)
round_trip() {
  rt_name=$2
  run "$1" --steps "$3" --export "$tmp/rt_$2.xml" --checkpoint "$tmp/rt_$2.ckpt@$3" --quiet
  rc1=$rc
  run "$tmp/rt_$2.xml" --steps 0 --export "$tmp/rt2_$2.xml" --quiet
  rc2=$rc
  run "$tmp/rt_$2.xml" --steps 1 --restore "$tmp/rt_$2.ckpt" --quiet
  check "$4: export, reload, export again: identical; its checkpoint restores into the export" \
    '[ "$rc1" -eq 0 ] && [ "$rc2" -eq 0 ] && rc_is 0 &&
     cmp -s "$tmp/rt_$rt_name.xml" "$tmp/rt2_$rt_name.xml"'
}
for s in "$top_srcdir"/scenes/*.xml; do
  b=$(basename "$s" .xml)
  round_trip "$s" "$b" 20 "$b.xml"
done
# a <material> before <objects> (as RaiSim's examples have it) names its
# pairs' materials first: with one naming materials no object has, the
# export writes its <material> first too; with the bed's material before
# the plate's, the bed is written first
mat_first='<material><default friction="0.8"/><pair_prop name1="steel" name2="wood" friction="0.5"/></material><objects>'
sed -e "s|<objects>|$mat_first|" -e 's|<box name="plate"|& material="rubber"|' \
  "$PLATE" >"$tmp/mat1.xml"
mat_pair='<material><default friction="0.8"/><pair_prop name1="wood" name2="rubber" friction="0.5"/></material><objects>'
sed -e "s|<objects>|$mat_pair|" -e 's|<box name="plate"|& material="rubber"|' \
  -e 's|<heightmap name="soil"|& material="wood"|' "$PLATE" >"$tmp/mat2.xml"
for b in mat1 mat2; do
  round_trip "$tmp/$b.xml" "$b" 5 "<material> before <objects> ($b)"
done
run "$PLATE" --steps 0 --checkpoint "$tmp/zero.ckpt@0" --export "$tmp/zero0.xml" --quiet
run "$PLATE" --steps 0 --restore "$tmp/zero.ckpt" --export "$tmp/zero1.xml" --quiet
check "--checkpoint FILE@0 holds the initial state; restoring it changes nothing" \
  'rc_is 0 && cmp -s "$tmp/zero0.xml" "$tmp/zero1.xml"'

# the checkpoint carries the solver configuration; the command line still wins
run "$PLATE" --steps 10 --max-sweeps 7 --checkpoint "$tmp/opt.ckpt@10" --quiet
run "$PLATE" --steps 5 --restore "$tmp/opt.ckpt" --export "$tmp/opt1.xml" --quiet
check "restoring applies the checkpoint's solver options (max_sweeps 7 in the export)" \
  'rc_is 0 && grep -q "max_sweeps=\"7\"" "$tmp/opt1.xml"'
run "$PLATE" --steps 5 --restore "$tmp/opt.ckpt" --max-sweeps 9 --export "$tmp/opt2.xml" --quiet
check "--max-sweeps given with --restore overrides the checkpoint's" \
  'rc_is 0 && grep -q "max_sweeps=\"9\"" "$tmp/opt2.xml"'

# damaged, foreign and mismatched checkpoints: exit 1, a clear message, no outputs
ck="$tmp/plate.k.ckpt"
corrupt_at() { # OFFSET OUT: a copy of $ck with one byte changed
  cp "$ck" "$2" && printf 'Z' | dd of="$2" bs=1 seek="$1" conv=notrunc 2>/dev/null
}
size=$(wc -c <"$ck" | tr -d ' ')
for off in 0 9 17 40 100 5000 $((size / 2)) $((size - 6)) $((size - 2)); do
  corrupt_at "$off" "$tmp/bad.ckpt"
  rm -f "$tmp/bad.xml"
  run "$PLATE" --steps 5 --restore "$tmp/bad.ckpt" --export "$tmp/bad.xml"
  check "a checkpoint with byte $off of $size changed: exit 1, clear message, no export" \
    'rc_is 1 && err_has "bad.ckpt" && err_has "error:" &&
     { err_has "corrupted" || err_has "not a soilsim checkpoint" || err_has "version"; } &&
     no_file "$tmp/bad.xml" && no_tmp "$tmp"'
done
head -c $((size - 100)) "$ck" >"$tmp/short.ckpt"
run "$PLATE" --steps 5 --restore "$tmp/short.ckpt" --export "$tmp/bad.xml"
check "a truncated checkpoint: exit 1, 'truncated'" \
  'rc_is 1 && err_has "short.ckpt" && err_has "truncated" && no_file "$tmp/bad.xml"'
run "$PLATE" --steps 5 --restore "$PLATE"
check "a scene file given to --restore: exit 1, 'not a soilsim checkpoint'" \
  'rc_is 1 && err_has "not a soilsim checkpoint"'
run "$top_srcdir/scenes/plate_arm.xml" --steps 5 --restore "$ck" --export "$tmp/bad.xml"
check "a checkpoint of another scene: exit 1, 'written for a different world'" \
  'rc_is 1 && err_has "written for a different world" && no_file "$tmp/bad.xml"'
run "$PLATE" --steps 5 --restore "$tmp/no-such.ckpt"
check "a missing checkpoint: exit 1 naming it" 'rc_is 1 && err_has "no-such.ckpt"'


# a camera from the command line (DESIGN 6): replaces the scene's view
run "$PLATE" --steps 0 --render "$tmp/camA" --size 160x90 --quiet
run "$PLATE" --steps 0 --render "$tmp/camB" --size 160x90 --camera-pos 0,0,3 \
  --camera-look-at 0,0.001,0 --camera-fov 30 --color soil --quiet
check "--camera-pos/--camera-look-at/--camera-fov/--color render a different view" \
  'rc_is 0 && [ -s "$tmp/camB/frame_000000.png" ] && ! cmp -s "$tmp/camA/frame_000000.png" "$tmp/camB/frame_000000.png"'
# --camera-fov alone: the automatic overview (plate.xml has no <camera>)
# and the scene's <camera> (buggy.xml) through another field of view; the
# whole documented range (0, 180) counts (the automatic view ignored the
# option, and a field of view under 1 or over 179 degrees became 45)
run "$PLATE" --steps 0 --render "$tmp/camF" --size 160x90 --camera-fov 20 --quiet
check "--camera-fov 20 changes the automatic view" \
  'rc_is 0 && [ -s "$tmp/camF/frame_000000.png" ] && ! cmp -s "$tmp/camA/frame_000000.png" "$tmp/camF/frame_000000.png"'
run "$top_srcdir/scenes/buggy.xml" --steps 0 --render "$tmp/camG" --size 160x90 --quiet
run "$top_srcdir/scenes/buggy.xml" --steps 0 --render "$tmp/camH" --size 160x90 \
  --camera-fov 0.5 --quiet
check "--camera-fov 0.5 narrows the scene's camera (not taken as 45)" \
  'rc_is 0 && [ -s "$tmp/camH/frame_000000.png" ] && ! cmp -s "$tmp/camG/frame_000000.png" "$tmp/camH/frame_000000.png"'
run "$PLATE" --steps 0 --render "$tmp/camC" --camera-pos 0,0,3
check "--camera-pos without --camera-look-at: exit 2" 'usage_error'
run "$PLATE" --steps 0 --camera-fov 30
check "--camera-fov without --render: exit 2" 'usage_error'
run "$PLATE" --steps 5 --render "$tmp/camD" --camera-pos 0,0,3 --camera-look-at 0,0.001,0 \
  --camera-follow nobody
check "--camera-follow of an unknown body: exit 1 before stepping, naming the option and the scene" \
  'rc_is 1 && [ ! -e "$tmp/camD/frame_000005.png" ] && err_has "plate.xml: error: --camera-follow" && err_has "nobody"'
run "$PLATE" --steps 5 --render "$tmp/camI" --camera-follow plate
check "--camera-follow without --camera-pos or a scene <camera>: exit 1 before stepping, saying what it needs" \
  'rc_is 1 && err_has "--camera-follow needs a camera" && no_file "$tmp/camI"'
run --help
check "--help gives --camera-fov's range and what --camera-follow needs" \
  'rc_is 0 && out_has "0 < DEG < 180" && out_has "needs --camera-pos or the scene'"'"'s <camera>"'
run "$PLATE" --steps 0 --render "$tmp/camE" --color rainbow
check "--color with an unknown mode: exit 2" 'usage_error && err_has "rainbow"'

# SIGINT in the middle of a run: exit by the signal, no final outputs, and
# a message that counts what stays, the frames drawn so far (it said "no
# output files written" with the frames there)
sig=$tmp/sig
mkdir -p "$sig"
last_cmd="soilsim $PLATE --steps 100000000 --render $sig/fr --render-every 1 --size 16x16 --export $sig/e.xml (SIGINT)"
CI='' "$SOILSIM" "$PLATE" --steps 100000000 --render "$sig/fr" --render-every 1 \
  --size 16x16 --export "$sig/e.xml" --quiet >"$tmp/out" 2>"$tmp/err" &
pid=$!
k=0
while [ ! -e "$sig/fr/frame_000002.png" ] && [ $k -lt 600 ]; do
  sleep 0.1
  k=$((k + 1))
done
kill -INT "$pid" 2>"$tmp/kill_err"
wait "$pid"
rc=$?
check "SIGINT: exit by the signal, no export, the message counts the frames that stay" \
  'rc_is 130 && no_file "$sig/e.xml" && no_tmp "$sig" && err_has "interrupted after step" &&
   err_has "frames drawn so far written" && ! err_has "no output files"'

echo "1..$n"
[ "$nfail" -eq 0 ]
