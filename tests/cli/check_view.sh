#!/usr/bin/env bash
# The interactive viewer without a person (ctest test view_scripted; issue 17): msdeform view runs a
# script of handle moves in a real window (on a virtual X server, Xvfb, with Mesa's software renderer when
# there is no display) and writes screenshots; the pictures must show the mesh, and the handle must have moved in them
# while the fixed part stayed. Mouse drags go through the gizmo's own picking and dragging, brush and lasso
# through the depth-tested selection. Also the knight painted and dragged from nothing, and bad scripts.
# Usage: check_view.sh MSDEFORM WORK_DIR SHARED_DATA
set -uo pipefail
msdeform="$1"
work="$2"
shared="$3"
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/common.sh"
start_in "$work"

# A display: the user's, else a virtual one with Mesa's software renderer.
# One virtual X server for all runs (xvfb-run per run fails now and then cleaning up its folder under
# load). Every run is bounded: a viewer left open (a script without --screenshot) would wait for a person.
if [ -z "${DISPLAY:-}" ]; then
  command -v Xvfb >/dev/null || fail "no DISPLAY and no Xvfb (apt-get install xvfb)"
  Xvfb -displayfd 9 -screen 0 1600x1000x24 -nolisten tcp 9>display.txt >xvfb.log 2>&1 &
  xvfb_pid=$!
  trap 'kill $xvfb_pid 2>/dev/null' EXIT
  for _ in $(seq 100); do [ -s display.txt ] && break; sleep 0.1; done
  [ -s display.txt ] || fail "Xvfb did not start: $(cat xvfb.log)"
  export DISPLAY=":$(head -1 display.txt)" LIBGL_ALWAYS_SOFTWARE=1
fi
run_view=(timeout 300 "$msdeform" view)
# Under AddressSanitizer (scripts/sanitize.sh): Mesa's driver leaks a few bytes and is unloaded before
# LeakSanitizer reports, so its frames cannot be named in a suppression; memory errors and undefined
# behaviour are still checked here, and leaks in the viewer's geometry by test_view.
[ -n "${ASAN_OPTIONS:-}" ] && export ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0"
regions() { /usr/bin/python3 "$here/png_regions.py" "$1" || fail "reading $1"; }
value() { awk -v k="$2" '$1 == k { print $2, $3 }' <<<"$1"; }
# check EXPR: a Python boolean expression over the numbers given as the remaining arguments (a, b, ...).
check() {
  local expr="$1" message="$2"
  shift 2
  /usr/bin/python3 -c "import sys; a, b, c, d = (list(map(float, sys.argv[1:])) + [0, 0, 0, 0])[:4]; sys.exit(0 if ($expr) else 1)" "$@" ||
    fail "$message ($*)"
}

# 1. The lift scene: the gizmo's z arrow dragged 100 pixels up, ARAP converged, pictures before and after.
cat >drag.txt <<'EOF'
reset                              # the scene's own transform off: start at rest
screenshot rest.png
gizmo translate z 0 -100 10        # a mouse drag on the z arrow
converge
screenshot moved.png
save-mesh moved.off
save-def moved.def
gizmo rotate center 0 80 8         # a sweep around the centre: a turn about the view direction
save-def turned.def
EOF
"${run_view[@]}" lift.off --sel lift.sel --method arap --size 1000 700 --script drag.txt --screenshot final.png \
  >out.txt 2>err.txt || { cat out.txt err.txt; fail "the scripted drag"; }
grep -q "line 3: gizmo translate z 0 -100 10 (10 frames of arap" out.txt || { cat out.txt; fail "no frame times"; }
rest=$(regions rest.png)
moved=$(regions moved.png)
check "a > 0.1 and b > 0.1" "the pictures are nearly blank" $(value "$rest" drawn | cut -d' ' -f1) \
  $(value "$moved" drawn | cut -d' ' -f1)
read -r hx0 hy0 <<<"$(value "$rest" handle_centroid)"
read -r hx1 hy1 <<<"$(value "$moved" handle_centroid)"
read -r fx0 fy0 <<<"$(value "$rest" fixed_centroid)"
read -r fx1 fy1 <<<"$(value "$moved" fixed_centroid)"
check "a > 0 and b > 0" "no handle (red) pixels" "$hx0" "$hx1"
check "a - b > 40" "the handle did not move up in the picture" "$hy0" "$hy1"
check "abs(a - b) < 2 and abs(c - d) < 2" "the fixed part moved in the picture" "$fx0" "$fx1" "$fy0" "$fy1"
# The drag moved the handle along z only, upwards; the turn is a rotation.
check "abs(a) < 1e-12 and abs(b) < 1e-12 and c > 0.05" "the z arrow moved the handle off z" \
  $(grep -v '^#' moved.def | awk 'NR == 1 { x = $4 } NR == 2 { y = $4 } NR == 3 { z = $4 } END { print x, y, z }')
check "abs(a - 1) > 1e-3" "the rotation gizmo did not turn the handle" $(grep -v '^#' turned.def | awk 'NR == 1 { print $1 }')
# The fixed vertices are where they were (the .sel's code 0), handle vertices all rose by the same amount.
/usr/bin/python3 - lift.off moved.off lift.sel <<'EOF' || fail "the saved mesh does not match the edit"
import sys
def off(path):
    words = open(path).read().split()
    n = int(words[1])
    return [tuple(map(float, words[4 + 3 * i:7 + 3 * i])) for i in range(n)]
rest, moved = off(sys.argv[1]), off(sys.argv[2])
codes = [int(line) for line in open(sys.argv[3]) if line.strip() and not line.startswith("#")]
assert len(rest) == len(moved) == len(codes)
fixed = [i for i, c in enumerate(codes) if c == 0]
handle = [i for i, c in enumerate(codes) if c == 2]
assert max(max(abs(a - b) for a, b in zip(rest[i], moved[i])) for i in fixed) < 1e-12
rises = [moved[i][2] - rest[i][2] for i in handle]
assert min(rises) > 0.05 and max(rises) - min(rises) < 1e-9, (min(rises), max(rises))
EOF

# 2. The knight from nothing: lasso a handle around the head and the fixed feet, drag the handle in the
# view plane, look: the head moved right and up, the feet stayed.
if [ -f "$shared/decimated-knight.off" ]; then
  cat >knight.txt <<'EOF'
lasso handle 0 0 0 950 0 950 200 0 200
lasso fixed 0 640 950 640 950 800 0 800
screenshot k0.png
gizmo translate center 60 -40 10
converge
screenshot k1.png
save-sel knight.sel
EOF
  "${run_view[@]}" "$shared/decimated-knight.off" --size 1280 800 --script knight.txt --screenshot kf.png \
    >out.txt 2>err.txt || { cat out.txt err.txt; fail "the knight"; }
  grep -q "lasso handle: [1-9][0-9]* vertices" out.txt || { cat out.txt; fail "the lasso selected no handle"; }
  k0=$(regions k0.png)
  k1=$(regions k1.png)
  read -r hx0 hy0 <<<"$(value "$k0" handle_centroid)"
  read -r hx1 hy1 <<<"$(value "$k1" handle_centroid)"
  check "c - a > 20 and b - d > 10" "the knight's head did not follow the drag" "$hx0" "$hy0" "$hx1" "$hy1"
  read -r fx0 fy0 <<<"$(value "$k0" fixed_centroid)"
  read -r fx1 fy1 <<<"$(value "$k1" fixed_centroid)"
  check "abs(a - b) < 2 and abs(c - d) < 2" "the knight's feet moved" "$fx0" "$fx1" "$fy0" "$fy1"
  grep -q "^2" knight.sel || fail "the saved .sel has no handle"
fi

# 3. What the viewer was given is what it shows: --def poses the handles as deform does, and a nonlinear
# method converged in the viewer ends where deform's single run ends (the viewer runs it in pieces).
printf 'save-def posed.def\nconverge\nsave-mesh posed.off\n' >posed.txt
"${run_view[@]}" lift.off --sel lift.sel --def lift.def --method arap --script posed.txt --screenshot posed.png \
  >out.txt 2>err.txt ||
  { cat out.txt err.txt; fail "view with --def"; }
cmp -s <(grep -v '^#' posed.def) <(grep -v '^#' lift.def) || fail "--def was not applied (posed.def differs from lift.def)"
"$msdeform" deform lift.off --sel lift.sel --def lift.def --method arap -o deformed.off -q >/dev/null || fail "deform"
printf 'converge\nsave-mesh twisted.off\n' >twist.txt
"${run_view[@]}" --scene twist135 --resolution 2k --method arap --script twist.txt --screenshot twisted.png \
  >out.txt 2>err.txt || { cat out.txt err.txt; fail "ARAP did not converge on the twist in the viewer"; }
"$msdeform" deform --scene twist135 --resolution 2k --method arap -o twisted-deform.off -q >/dev/null || fail "deform"
for pair in "posed.off deformed.off" "twisted.off twisted-deform.off"; do
/usr/bin/python3 - $pair <<'EOF2' || fail "ARAP converged in the viewer differs from deform's ($pair)"
import sys
def off(path):
    words = open(path).read().split()
    return [float(w) for w in words[4:4 + 3 * int(words[1])]]
a, b = off(sys.argv[1]), off(sys.argv[2])
# Both stop when an iteration moves no vertex by 1e-6 of the diagonal, from different starts (the viewer's
# first frame ran 5 iterations): measured 2e-5 apart; the pieces without their acceleration stalled 0.045 away.
assert len(a) == len(b) and max(abs(x - y) for x, y in zip(a, b)) < 1e-3, max(abs(x - y) for x, y in zip(a, b))
EOF2
done

# 4. Outputs: never an input, the right format, nothing to save refused.
printf 'save-mesh lift.off\n' >bad.txt
expect_error 1 "lift.off is one of the files the viewer read" "${run_view[@]}" lift.off --sel lift.sel --script bad.txt
printf 'save-sel lift.sel\n' >bad.txt
expect_error 1 "lift.sel is one of the files the viewer read" "${run_view[@]}" lift.off --sel lift.sel --script bad.txt
printf 'screenshot shot.jpg\n' >bad.txt
expect_error 1 "shot.jpg: this file is written in the .png format" "${run_view[@]}" lift.off --script bad.txt
printf 'save-def none.def\n' >bad.txt
expect_error 1 "there is no handle, so no transform to save" "${run_view[@]}" lift.off --script bad.txt
[ ! -e none.def ] || fail "save-def with no handle wrote a file"

printf 'reset\n' >script.sel
expect_error 1 "--write-sel script.sel is the --script" "${run_view[@]}" lift.off --sel lift.sel --script script.sel \
  --write-sel script.sel
grep -q reset script.sel || fail "--write-sel replaced the script"
printf 'translate 0 0 0.1\nsave-mesh lift.off\n' >bad.txt
expect_error 1 "bad.txt:2: lift.off is one of the files the viewer read" "${run_view[@]}" lift.off --sel lift.sel \
  --script bad.txt
[ ! -e posed-first.off ] || rm posed-first.off

# The shape shown is the shape saved, from the first line on; a handle painted on a deformed shape keeps
# it where it is (its transform is the best rigid fit of where its vertices are shown).
printf 'save-mesh posed-first.off\nconverge\nsave-mesh posed-before-paint.off\npaint handle 1 450 350 30\nconverge\nsave-mesh posed-after-paint.off\n' >paint.txt
"${run_view[@]}" lift.off --sel lift.sel --def lift.def --method arap --size 1000 700 --script paint.txt \
  --screenshot painted.png >out.txt 2>err.txt || { cat out.txt err.txt; fail "painting a posed shape"; }
grep -q "paint handle: [1-9]" out.txt || { cat out.txt; fail "the brush painted nothing"; }
/usr/bin/python3 - lift.off posed-first.off posed-before-paint.off posed-after-paint.off <<'EOF2' ||
import sys
def off(path):
    words = open(path).read().split()
    n = int(words[1])
    return [tuple(map(float, words[4 + 3 * i:7 + 3 * i])) for i in range(n)]
rest, first, before, after = (off(p) for p in sys.argv[1:])
moved = max(abs(a[2] - b[2]) for a, b in zip(rest, first))
assert moved > 0.1, f"line 1 saved the rest shape (largest move {moved})"
change = max(max(abs(x - y) for x, y in zip(a, b)) for a, b in zip(before, after))
assert change < 0.02, f"painting a handle moved the shape by {change}"
EOF2
  fail "the saved shape is not the one shown"

# Painting prepares the method again on the same mesh: the multi-scale base is computed once.
printf 'translate 0 0 0.1\npaint handle 1 450 350 30\ntranslate 0 0 0.1\n' >paint-ms.txt
"${run_view[@]}" lift.off --sel lift.sel --method multiscale --size 1000 700 --script paint-ms.txt \
  --screenshot painted-ms.png >out.txt 2>err.txt || { cat out.txt err.txt; fail "painting with multiscale"; }
[ "$(grep -c "prepared multiscale-normal" out.txt)" = 2 ] || { cat out.txt; fail "multiscale was not prepared twice"; }
grep -q "prepared multiscale-normal in [0-9]* ms (the multi-scale base computed before)" out.txt ||
  { cat out.txt; fail "the second preparation computed the base again"; }

# 5. Bad scripts and inputs: refused by name before a window opens, or at the command that fails.
expect_error 1 "/dev/zero: cannot open the script (not a file)" "${run_view[@]}" lift.off --script /dev/zero
printf 'translate 0 0 1 0\n' >bad.txt
expect_error 1 "bad.txt:1: STEPS is a whole number from 1 to 10000, not 0" "${run_view[@]}" lift.off --script bad.txt
printf 'rotate 0 0 0 45\n' >bad.txt
expect_error 1 "bad.txt:1: the rotation axis is zero" "${run_view[@]}" lift.off --script bad.txt
expect_error 1 "--tolerance 0 asks for a fixed number of iterations" "${run_view[@]}" lift.off --sel lift.sel \
  --method arap --tolerance 0
expect_error 1 "ks" "${run_view[@]}" lift.off --sel lift.sel --method shell --ks -1
awk 'NR <= 2 { print; next } { print ($0 == "2" ? "5" : $0) }' lift.sel >gap.sel
expect_error 1 "consecutive" "${run_view[@]}" lift.off --sel gap.sel
# Two turns of 100° would pass half a turn (shown as 200°, saved as the -160° matrix): the second stops it.
printf 'rotate 1 0 0 100 10\nrotate 1 0 0 100 10\nsave-def never.def\n' >bad.txt
expect_error 1 "bad.txt:2: rotate: handle 0 stops at 170 degrees from rest: half a turn is as far as a handle turns" \
  "${run_view[@]}" lift.off --sel lift.sel --script bad.txt
[ ! -e never.def ] || fail "a script stopped at half a turn still saved its .def"
printf 'translate 0 0 1\nwiggle 3\n' >bad.txt
expect_error 1 "bad.txt:2: unknown command 'wiggle'" "${run_view[@]}" lift.off --script bad.txt
printf 'translate 0 zero 1\n' >bad.txt
expect_error 1 "bad.txt:1: 'translate' expects a number, found 'zero'" "${run_view[@]}" lift.off --script bad.txt
printf 'screenshot a.png\ntranslate 0 0 1\n' >bad.txt
expect_error 1 "bad.txt:2: translate: there is no handle to move" "${run_view[@]}" lift.off --script bad.txt \
  --screenshot never.png
[ ! -e never.png ] || fail "a failed script still wrote its --screenshot"
printf 'method nonsense\n' >bad.txt
expect_error 1 "nonsense" "${run_view[@]}" lift.off --sel lift.sel --script bad.txt
printf 'OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n' >cloud.off
expect_error 1 "has no faces" "${run_view[@]}" cloud.off
expect_error 1 "--screenshot shot.txt: the picture is a .png" "${run_view[@]}" lift.off --screenshot shot.txt
echo "check_view: all checks passed"
