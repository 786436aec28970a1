#!/bin/sh
# test_faults.sh -- TAP tests of hostile files and faults (issue 8).
#
# make check sets top_srcdir and top_builddir (absolute); by hand:
#   top_srcdir=. top_builddir=build sh tests/test_faults.sh
#
#  1. inputs that need the file system to be bad: unreadable scenes, URDFs,
#     meshes and height maps (chmod 000), unwritable output folders, FIFOs,
#     devices, symlink loops, huge (sparse) files, broken meshes;
#  2. numeric blow-ups (tests/data/blowup/*.xml, first line
#     <!-- expect: STEP: SUBSTRING -->): exit 1 naming the step and the
#     system, no output, existing outputs untouched;
#  3. nothing lost: soilsim killed with SIGKILL in the middle of writing an
#     export, a checkpoint or a CSV leaves the previous file byte for byte;
#     a full disk (a 64 KiB tmpfs) gives a clear error and leaves no file.
#
# Permissions: root reads and writes whatever the mode bits say, so as root
# the permission tests run soilsim as the user nobody (setpriv); when that
# is not possible they are skipped and say why.  The full-disk tests mount
# a tmpfs in a private mount namespace (unshare -m, or a plain mount as
# root); where mounting is not permitted they are skipped and say why.

# The checks are shell expressions in single quotes, expanded by eval.
# shellcheck disable=SC2016

top_srcdir=${top_srcdir:-.}
top_builddir=${top_builddir:-.}
SOILSIM=$top_builddir/soilsim
case $SOILSIM in /*) ;; *) SOILSIM=$(pwd)/$SOILSIM ;; esac
case $top_srcdir in /*) ;; *) top_srcdir=$(cd "$top_srcdir" && pwd) ;; esac
PLATE=$top_srcdir/scenes/plate.xml
ARM_URDF=$top_srcdir/assets/plate_arm/plate_arm.urdf

# the harness: $tmp, run, check, skip, rc_is, err_has, ...
TAP_NAME=faults
. "$top_srcdir/tests/tap.sh"
# other users (nobody, below) must be able to reach the files in it
chmod 755 "$tmp"
cleanup() {
  chmod -R u+rwX "$tmp" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 130' INT TERM HUP

# run_as USER_PREFIX ARGS...: the same, through a prefix such as setpriv
run_as() {
  pre=$1
  shift
  last_cmd="$pre soilsim $*"
  # shellcheck disable=SC2086
  CI='' $TIMEOUT $pre "$SOILSIM" "$@" >"$tmp/out" 2>"$tmp/err"
  rc=$?
}

# a bounded wait: TIMEOUT on its own
bounded() { [ "$rc" -ne 124 ] && [ "$rc" -ne 137 ]; }

# a small scene that loads the lift URDF from $1 (a path)
arm_scene() {
  cat <<EOF
<raisim version="1.0">
  <timeStep value="0.001"/>
  <objects>
    <articulated_system name="carrier" urdf_path="$1">
      <state pos="0 0 0.5"/>
    </articulated_system>
  </objects>
</raisim>
EOF
}

# a URDF with one link whose visual mesh is $1 (a path)
mesh_urdf() {
  cat <<EOF
<robot name="meshy">
  <link name="body">
    <inertial><mass value="1"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <visual><geometry><mesh filename="$1"/></geometry></visual>
  </link>
</robot>
EOF
}

# =====================================================================
# 1. bad inputs that need the file system

# --- permissions ------------------------------------------------------
# Who can be denied a file: an ordinary user always; root only by running
# soilsim as nobody (if nobody can reach the program).
asuser=""
perm_skip=""
if [ "$(id -u)" -ne 0 ]; then
  asuser=" "
elif command -v setpriv >/dev/null 2>&1 &&
     setpriv --reuid=65534 --regid=65534 --clear-groups -- \
       "$SOILSIM" --version >/dev/null 2>&1; then
  asuser="setpriv --reuid=65534 --regid=65534 --clear-groups --"
else
  perm_skip="running as root, where file permissions do not apply, and \
cannot run soilsim as nobody (no setpriv, or nobody cannot reach $SOILSIM)"
fi

mkdir -p "$tmp/perm/meshes" "$tmp/perm/ro"
cp "$PLATE" "$tmp/perm/plate.xml"
cp "$ARM_URDF" "$tmp/perm/arm.urdf"
cp "$top_srcdir/tests/data/urdf/meshes/cube.obj" "$tmp/perm/meshes/cube.obj"
arm_scene "$tmp/perm/arm.urdf" >"$tmp/perm/arm.xml"
mesh_urdf "meshes/cube.obj" >"$tmp/perm/meshy.urdf"
arm_scene "$tmp/perm/meshy.urdf" >"$tmp/perm/meshy.xml"
cp "$top_srcdir/tests/data/hfield_4x3.txt" "$tmp/perm/heights.txt"
cat >"$tmp/perm/text.xml" <<EOF
<raisim version="1.0">
  <objects>
    <heightmap name="h" text="$tmp/perm/heights.txt" x_size="1" y_size="1"/>
  </objects>
</raisim>
EOF
chmod -R a+rX "$tmp/perm"

if [ -n "$perm_skip" ]; then
  for k in 1 2 3 4 5 6 7 8; do skip "$perm_skip"; done
else
  who=nobody
  [ "$asuser" = " " ] && who=$(id -un)
  run_as "$asuser" "$tmp/perm/plate.xml" --steps 1 --quiet
  check "as $who: the copied inputs are readable (control)" 'rc_is 0'

  chmod 000 "$tmp/perm/plate.xml"
  run_as "$asuser" "$tmp/perm/plate.xml" --steps 1
  check "unreadable scene (mode 000): exit 1 naming it, 'Permission denied'" \
    'rc_is 1 && err_has "perm/plate.xml" && err_has "Permission denied"'
  chmod 644 "$tmp/perm/plate.xml"

  chmod 000 "$tmp/perm/arm.urdf"
  run_as "$asuser" "$tmp/perm/arm.xml" --steps 1
  check "unreadable URDF: exit 1 naming the scene line and the URDF" \
    'rc_is 1 && err_has "arm.xml:4:" && err_has "arm.urdf" &&
     err_has "Permission denied"'
  chmod 644 "$tmp/perm/arm.urdf"

  chmod 000 "$tmp/perm/meshes/cube.obj"
  run_as "$asuser" "$tmp/perm/meshy.xml" --steps 1
  check "unreadable mesh: exit 1 naming the URDF line and the mesh" \
    'rc_is 1 && err_has "meshy.urdf:5:" && err_has "cube.obj" &&
     err_has "Permission denied"'
  chmod 644 "$tmp/perm/meshes/cube.obj"

  chmod 000 "$tmp/perm/heights.txt"
  run_as "$asuser" "$tmp/perm/text.xml" --steps 1
  check "unreadable height-map text file: exit 1 naming it" \
    'rc_is 1 && err_has "text.xml:3:" && err_has "heights.txt" &&
     err_has "Permission denied"'
  chmod 644 "$tmp/perm/heights.txt"

  # unwritable output folder: refused before the first step (the run asks
  # for 2e9 steps, so a late failure would time out)
  echo "precious" >"$tmp/perm/ro/keep.xml"
  chmod 555 "$tmp/perm/ro"
  run_as "$asuser" "$tmp/perm/plate.xml" --steps 2000000000 \
    --export "$tmp/perm/ro/keep.xml"
  check "--export into an unwritable folder: exit 1 before stepping, names it" \
    'rc_is 1 && err_has "ro/keep.xml" && err_has "Permission denied" &&
     [ "$(cat "$tmp/perm/ro/keep.xml")" = precious ]'
  run_as "$asuser" "$tmp/perm/plate.xml" --steps 2000000000 \
    --csv "$tmp/perm/ro/run.csv"
  check "--csv into an unwritable folder: exit 1 before stepping" \
    'rc_is 1 && err_has "ro/run.csv" && err_has "Permission denied"'
  run_as "$asuser" "$tmp/perm/plate.xml" --steps 2000000000 \
    --rut-map "$tmp/perm/ro/rut.png"
  check "--rut-map into an unwritable folder: exit 1 before stepping" \
    'rc_is 1 && err_has "ro/rut.png" && err_has "Permission denied" &&
     no_tmp "$tmp/perm/ro"'
  chmod 755 "$tmp/perm/ro"
fi

# --- files that are not regular files, or too large ---------------------
mkdir -p "$tmp/kind/meshes"
if command -v mkfifo >/dev/null 2>&1 && mkfifo "$tmp/kind/fifo"; then
  run "$tmp/kind/fifo" --steps 1
  check "a FIFO as the scene: exit 1 at once, 'not a regular file'" \
    'bounded && rc_is 1 && err_has "not a regular file"'
  arm_scene "$tmp/kind/fifo" >"$tmp/kind/fifo_urdf.xml"
  run "$tmp/kind/fifo_urdf.xml" --steps 1
  check "a FIFO as the URDF: exit 1 at once" \
    'bounded && rc_is 1 && err_has "fifo_urdf.xml:4:" && err_has "not a regular file"'
  mesh_urdf "$tmp/kind/fifo" >"$tmp/kind/fifo_mesh.urdf"
  arm_scene "$tmp/kind/fifo_mesh.urdf" >"$tmp/kind/fifo_mesh.xml"
  run "$tmp/kind/fifo_mesh.xml" --steps 1
  check "a FIFO as a mesh: exit 1 at once" \
    'bounded && rc_is 1 && err_has "fifo_mesh.urdf:5:" && err_has "not a regular file"'
  for form in text png; do
    cat >"$tmp/kind/fifo_$form.xml" <<EOF
<raisim version="1.0">
  <objects>
    <heightmap name="h" $form="$tmp/kind/fifo" x_size="1" y_size="1"/>
  </objects>
</raisim>
EOF
    run "$tmp/kind/fifo_$form.xml" --steps 1
    check "a FIFO as a $form height map: exit 1 at once (no wait for a writer)" \
      'bounded && rc_is 1 && err_has "fifo_$form.xml:3:" && err_has "not a regular file"'
  done
else
  for k in 1 2 3 4 5; do skip "mkfifo is not available"; done
fi

run /dev/zero --steps 1
check "a character device as the scene: exit 1, 'not a regular file'" \
  'bounded && rc_is 1 && err_has "not a regular file"'

ln -s "$tmp/kind/loop" "$tmp/kind/loop"
run "$tmp/kind/loop" --steps 1
check "a symbolic-link loop as the scene: exit 1 naming it" \
  'rc_is 1 && err_has "kind/loop" && err_has "error:"'

: >"$tmp/kind/empty.xml"
run "$tmp/kind/empty.xml" --steps 1
check "an empty scene file: exit 1, 'empty scene'" \
  'rc_is 1 && err_has "empty.xml:1:" && err_has "empty scene"'

# huge files: sparse, so they cost no disk; each limit is checked before
# anything is read
if command -v truncate >/dev/null 2>&1 &&
   truncate -s 600M "$tmp/kind/huge.xml" 2>/dev/null; then
  run "$tmp/kind/huge.xml" --steps 1
  check "a 600 MB scene: exit 1 at once, larger than the 512 MiB limit" \
    'bounded && rc_is 1 && err_has "huge.xml" && err_has "larger than the limit"'
  rm -f "$tmp/kind/huge.xml"
  truncate -s 65M "$tmp/kind/huge.urdf"
  arm_scene "$tmp/kind/huge.urdf" >"$tmp/kind/huge_urdf.xml"
  run "$tmp/kind/huge_urdf.xml" --steps 1
  check "a 65 MB URDF: exit 1, larger than the 64 MiB limit" \
    'bounded && rc_is 1 && err_has "huge_urdf.xml:4:" && err_has "larger than the limit"'
  rm -f "$tmp/kind/huge.urdf"
  truncate -s 600M "$tmp/kind/huge.obj"
  mesh_urdf "$tmp/kind/huge.obj" >"$tmp/kind/huge_mesh.urdf"
  arm_scene "$tmp/kind/huge_mesh.urdf" >"$tmp/kind/huge_mesh.xml"
  run "$tmp/kind/huge_mesh.xml" --steps 1
  check "a 600 MB mesh: exit 1 at once, larger than the limit (not read)" \
    'bounded && rc_is 1 && err_has "huge_mesh.urdf:5:" && err_has "larger than the limit"'
  rm -f "$tmp/kind/huge.obj"
  truncate -s 600M "$tmp/kind/huge.txt"
  cat >"$tmp/kind/huge_text.xml" <<EOF
<raisim version="1.0">
  <objects>
    <heightmap name="h" text="$tmp/kind/huge.txt" x_size="1" y_size="1"/>
  </objects>
</raisim>
EOF
  run "$tmp/kind/huge_text.xml" --steps 1
  check "a 600 MB height-map text file: exit 1, larger than the limit" \
    'bounded && rc_is 1 && err_has "huge_text.xml:3:" && err_has "larger than the limit"'
  rm -f "$tmp/kind/huge.txt"
else
  for k in 1 2 3 4; do skip "cannot make sparse files (truncate)"; done
fi

# meshes that exist but are broken: the error names the URDF line and the
# mesh file
printf 'this is not a mesh\n' >"$tmp/kind/meshes/junk.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n' >"$tmp/kind/meshes/inf.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >"$tmp/kind/meshes/index.obj"
printf 'solid x\nendsolid x\n' >"$tmp/kind/meshes/empty.stl"
for m in junk.obj inf.obj index.obj empty.stl; do
  mesh_urdf "meshes/$m" >"$tmp/kind/m_$m.urdf"
  arm_scene "$tmp/kind/m_$m.urdf" >"$tmp/kind/m_$m.xml"
  run "$tmp/kind/m_$m.xml" --steps 1
  check "a broken mesh ($m): exit 1 naming the URDF line and the mesh" \
    'rc_is 1 && err_has "m_$m.urdf:5:" && err_has "$m" && err_has "error:"'
done

# a missing mesh through a scene: the URDF's line, not the scene's
mesh_urdf "meshes/no_such.obj" >"$tmp/kind/missing_mesh.urdf"
arm_scene "$tmp/kind/missing_mesh.urdf" >"$tmp/kind/missing_mesh.xml"
run "$tmp/kind/missing_mesh.xml" --steps 1
check "a missing mesh: exit 1 naming the URDF line, 'not found'" \
  'rc_is 1 && err_has "missing_mesh.urdf:5:" && err_has "no_such.obj" && err_has "not found"'

# =====================================================================
# 2. numeric blow-ups: the step and the system are named, nothing written

nblow=0
echo "precious export" >"$tmp/keep.xml"
for f in "$top_srcdir"/tests/data/blowup/*.xml; do
  [ -f "$f" ] || continue
  nblow=$((nblow + 1))
  b=$(basename "$f")
  expect_line "$f"
  step=$expect_n
  sub=$expect_sub
  if [ -z "$step" ] || [ -z "$sub" ]; then
    check "blowup/$b has an expect line ('<!-- expect: STEP: SUBSTRING -->')" false
    continue
  fi
  rm -f "$tmp/blow.csv"
  run "$f" --steps 1000 --export "$tmp/keep.xml" --csv "$tmp/blow.csv"
  check "blowup/$b: exit 1 at step $step naming $sub; no CSV; export untouched" \
    'rc_is 1 && err_has "$b: error: step $step (" && err_has "$sub" &&
     no_file "$tmp/blow.csv" && [ "$(cat "$tmp/keep.xml")" = "precious export" ] &&
     no_tmp "$tmp"'
done
[ "$nblow" -gt 0 ] || skip "no files in tests/data/blowup"

# the step counter's limit (<clock step> at most 2^63 - 1; past it the
# count would overflow): --steps that would pass it is refused before the
# first step, nothing written; a run that ends at it exports a clock and
# checkpoints one that read back, and neither steps on
sed 's|<timeStep value="0.001"/>|&<clock time="1" step="9223372036854775800"/>|' \
  "$PLATE" >"$tmp/clock.xml"
rm -f "$tmp/clock.csv"
run "$tmp/clock.xml" --steps 10 --export "$tmp/keep.xml" --csv "$tmp/clock.csv"
check "a clock 7 steps short of the step counter's limit: --steps 10 exits 1 before the first step; no CSV; export untouched" \
  'rc_is 1 && err_has "clock.xml: error: --steps 10:" &&
   err_has "stops at 9223372036854775807" && no_file "$tmp/clock.csv" &&
   [ "$(cat "$tmp/keep.xml")" = "precious export" ] && no_tmp "$tmp"'
run "$tmp/clock.xml" --steps 7 --export "$tmp/clock_end.xml" \
  --checkpoint "$tmp/clock_end.ckpt@7" -q
check "--steps 7 reaches the limit: the export's clock says step 9223372036854775807" \
  'rc_is 0 && grep -q "step=\"9223372036854775807\"" "$tmp/clock_end.xml"'
run "$tmp/clock_end.xml" --steps 0 -q
check "that export reads back" 'rc_is 0'
run "$tmp/clock_end.xml" --steps 1
check "that export refuses one step more, naming the limit" \
  'rc_is 1 && err_has "clock_end.xml: error: --steps 1:" &&
   err_has "stops at 9223372036854775807"'
run "$tmp/clock.xml" --restore "$tmp/clock_end.ckpt" --steps 0 -q
check "the checkpoint at the limit restores" 'rc_is 0'
run "$tmp/clock.xml" --restore "$tmp/clock_end.ckpt" --steps 1
check "the checkpoint at the limit refuses one step more" \
  'rc_is 1 && err_has "clock_end.ckpt: error: --steps 1:"'

# =====================================================================
# 3. nothing lost

# A world whose export and checkpoint take a while to write: a 1201 x 1201
# generated soil bed (an export of about 40 MB, a checkpoint of 35 MB).
mkdir -p "$tmp/kill"
cat >"$tmp/kill/big.xml" <<'EOF'
<raisim version="1.0">
  <timeStep value="0.001"/>
  <objects>
    <heightmap name="bed">
      <terrain_properties x_size="40" y_size="40" x_samples="1201" y_samples="1201" z_scale="0.3"/>
      <soil/>
    </heightmap>
    <box name="b" mass="20"> <dim x="0.4" y="0.6" z="0.05"/> <state pos="0 0 1"/> </box>
  </objects>
</raisim>
EOF

# kill_when_writing TARGET MINBYTES ARGS...: start soilsim ARGS in the
# background, wait until the atomic writer's temporary file for TARGET
# holds at least MINBYTES bytes (the output is being written), then
# SIGKILL it.  Sets killed=1 when that moment was caught, 0 when soilsim
# finished first (or 30 s passed).
kill_when_writing() {
  target=$1
  min=$2
  shift 2
  last_cmd="soilsim $* (SIGKILL while writing $target)"
  CI='' "$SOILSIM" "$@" >"$tmp/out" 2>"$tmp/err" &
  pid=$!
  killed=0
  i=0
  while [ $i -lt 3000 ] && kill -0 "$pid" 2>/dev/null; do
    for t in "$target".tmp[0-9]*; do
      if [ -f "$t" ] && [ "$(wc -c <"$t")" -ge "$min" ]; then
        kill -9 "$pid" 2>/dev/null && killed=1
        break 2
      fi
    done
    sleep 0.01 2>/dev/null || sleep 1
    i=$((i + 1))
  done
  [ "$killed" -eq 1 ] || kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  rc=$?
}

# leftover temporary files of a killed writer (SIGKILL cannot be caught:
# the partial file stays beside the target, never in its place)
leftovers() {
  for t in "$1".tmp[0-9]*; do [ -e "$t" ] && echo "$t"; done
}

# intact FILE OLD NEW: FILE is byte for byte OLD (the kill came first) or
# NEW (the complete output of an uninterrupted run: the kill came after the
# rename); anything else is a partial or damaged file
intact() { cmp -s "$1" "$2" || cmp -s "$1" "$3"; }

# references: what uninterrupted runs write
run "$tmp/kill/big.xml" --steps 0 --export "$tmp/kill/ref.xml" --quiet
ref_ok=$rc
has_ckpt=0
if "$SOILSIM" --help 2>/dev/null | grep -q -- '--checkpoint'; then
  has_ckpt=1
  run "$tmp/kill/big.xml" --steps 1 --checkpoint "$tmp/kill/ref.ckpt@1" --quiet
  ref_ok=$((ref_ok + rc))
fi
check "reference export and checkpoint of the big world are written" \
  '[ "$ref_ok" -eq 0 ] && [ -s "$tmp/kill/ref.xml" ]'

# export: the old file stays, byte for byte, however far the write got
echo "precious export: the previous run's world" >"$tmp/kill/out.xml"
cp "$tmp/kill/out.xml" "$tmp/kill/out.orig"
for min in 1 4000000 20000000; do
  kill_when_writing "$tmp/kill/out.xml" $min "$tmp/kill/big.xml" --steps 0 \
    --export "$tmp/kill/out.xml" --quiet
  left=no
  [ -n "$(leftovers "$tmp/kill/out.xml")" ] && left=yes
  if [ "$killed" -eq 1 ]; then
    check "SIGKILL with $min+ bytes of the export written: the old export is \
intact (partial file left beside it: $left)" \
      'intact "$tmp/kill/out.xml" "$tmp/kill/out.orig" "$tmp/kill/ref.xml"'
  else
    skip "the export finished before $min bytes were seen (machine too fast)"
  fi
  rm -f "$tmp/kill/out.xml".tmp[0-9]*
  cp "$tmp/kill/out.orig" "$tmp/kill/out.xml"
done

# checkpoint (when this soilsim writes them)
if [ "$has_ckpt" -eq 1 ]; then
  echo "precious checkpoint" >"$tmp/kill/c.ckpt"
  cp "$tmp/kill/c.ckpt" "$tmp/kill/c.orig"
  for min in 1 8000000; do
    kill_when_writing "$tmp/kill/c.ckpt" $min "$tmp/kill/big.xml" --steps 1 \
      --checkpoint "$tmp/kill/c.ckpt@1" --quiet
    if [ "$killed" -eq 1 ]; then
      check "SIGKILL with $min+ bytes of a checkpoint written: the old one is intact" \
        'intact "$tmp/kill/c.ckpt" "$tmp/kill/c.orig" "$tmp/kill/ref.ckpt"'
    else
      skip "the checkpoint finished before $min bytes were seen (machine too fast)"
    fi
    rm -f "$tmp/kill/c.ckpt".tmp[0-9]*
    cp "$tmp/kill/c.orig" "$tmp/kill/c.ckpt"
  done
else
  skip "this soilsim has no --checkpoint"
  skip "this soilsim has no --checkpoint"
fi

# CSV: rows stream into the temporary file during the run
printf 'step,time\n1,0.001\n' >"$tmp/kill/run.csv"
cp "$tmp/kill/run.csv" "$tmp/kill/run.orig"
kill_when_writing "$tmp/kill/run.csv" 100000 "$PLATE" --steps 1000000 \
  --csv "$tmp/kill/run.csv" --quiet
if [ "$killed" -eq 1 ]; then
  check "SIGKILL in the middle of a run writing --csv: the old CSV is intact" \
    'cmp -s "$tmp/kill/run.csv" "$tmp/kill/run.orig"'
else
  skip "the CSV was not seen growing within 30 s"
fi
rm -f "$tmp/kill/run.csv".tmp[0-9]*

# a completed run afterwards replaces the file whole (the tests above did
# not just fail to write)
run "$tmp/kill/big.xml" --steps 0 --export "$tmp/kill/out.xml" --quiet
check "an uninterrupted run then replaces the export whole" \
  'rc_is 0 && cmp -s "$tmp/kill/out.xml" "$tmp/kill/ref.xml" && no_tmp "$tmp/kill"'

# --- a full disk --------------------------------------------------------
# Everything runs in one shell inside a private mount namespace, where a
# 64 KiB tmpfs is mounted on $tmp/full; it writes its results to files.
mkdir -p "$tmp/full" "$tmp/fullres"
cat >"$tmp/full.sh" <<'EOF'
full=$1; res=$2; soilsim=$3; plate=$4
mount -t tmpfs -o size=64k soilsim-full "$full" || exit 90
r() { name=$1; shift; CI='' "$soilsim" "$@" >"$res/$name.out" 2>"$res/$name.err"
      echo $? >"$res/$name.rc"; ls -A "$full" >"$res/$name.ls"; }
echo "precious export" >"$full/keep.xml"
r export "$plate" --steps 5 --export "$full/keep.xml" --quiet
cat "$full/keep.xml" >"$res/export.kept"
r csv "$plate" --steps 3000 --csv "$full/run.csv" --quiet
r ckpt "$plate" --steps 5 --checkpoint "$full/c.ckpt@5" --quiet
# fill what is left, then a small rut map
dd if=/dev/zero of="$full/fill" bs=1024 count=64 2>/dev/null
r rut "$plate" --steps 5 --rut-map "$full/rut.png" --size 400x300 --quiet
umount "$full" 2>/dev/null
exit 0
EOF
full_rc=99
if command -v unshare >/dev/null 2>&1; then
  unshare -m sh "$tmp/full.sh" "$tmp/full" "$tmp/fullres" "$SOILSIM" "$PLATE" \
    >/dev/null 2>&1
  full_rc=$?
fi
if [ "$full_rc" -ne 0 ] && [ "$(id -u)" -eq 0 ]; then
  sh "$tmp/full.sh" "$tmp/full" "$tmp/fullres" "$SOILSIM" "$PLATE" >/dev/null 2>&1
  full_rc=$?
fi
fres() { cat "$tmp/fullres/$1.$2" 2>/dev/null; }
if [ "$full_rc" -eq 0 ]; then
  for w in export csv ckpt rut; do
    cp "$tmp/fullres/$w.err" "$tmp/err" 2>/dev/null
    rc=$(fres $w rc)
    rc=${rc:-99}
    last_cmd="(full 64 KiB disk) soilsim ... $w"
    case $w in
      export) what="--export over an existing file"; path="keep.xml" ;;
      csv) what="--csv"; path="run.csv" ;;
      ckpt) what="--checkpoint"; path="c.ckpt" ;;
      rut) what="--rut-map"; path="rut.png" ;;
    esac
    check "full disk, $what: exit 1 naming the path; no file or temporary left" \
      'rc_is 1 && err_has "$path" && err_has "error:" &&
       ! grep -q "tmp[0-9]" "$tmp/fullres/$w.ls" &&
       { [ "$w" = export ] || ! grep -qx "$path" "$tmp/fullres/$w.ls"; }'
    check "full disk, $what: the message gives the reason ('No space left on device')" \
      'err_has "No space left on device"'
  done
  check "full disk: the existing export is left as it was" \
    '[ "$(fres export kept)" = "precious export" ]'
else
  for k in 1 2 3 4 5 6 7 8 9; do
    skip "cannot mount a 64 KiB tmpfs here (not root, or mounting is not permitted)"
  done
fi

echo "1..$n"
[ "$nfail" -eq 0 ]
