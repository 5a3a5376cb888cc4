#!/usr/bin/env bash
# The command line without hand-written files (ctest test cli_regions; issue 16, parts 2 to 4): the
# knight's libigl edit and a y-up armadillo edit as one command each; --write-sel / --write-def reproduce
# the same deformation through files; transforms compose in order, about the handle's centroid; render
# and the camera options; progress on stderr and --quiet; bad specs refused by name.
# Usage: check_regions.sh MSDEFORM WORK_DIR SHARED_DATA CGAL_MESHES
set -uo pipefail
msdeform="$1"
work="$2"
shared="$3"
cgal="$4"
source "$(cd "$(dirname "$0")" && pwd)/common.sh"
start_in "$work"

# The same edit built on the command line and read back from the files it wrote gives the same mesh.
"$msdeform" deform lift.off --fixed halfspace:1,0,0,0.2 --handle box:0.7,-1,-1,2,2,2 --translate 0,0,0.3 \
  --rotate 0,1,0,-20 --method shell -o built.off --write-sel built.sel --write-def built.def >/dev/null ||
  fail "deform with --fixed/--handle"
"$msdeform" deform lift.off --sel built.sel --def built.def --method shell -o from-files.off >/dev/null ||
  fail "deform from the written files"
cmp -s built.off from-files.off || fail "the written .sel/.def do not reproduce the edit"
grep -c "^0$" built.sel >/dev/null || fail "no fixed vertex written"
/usr/bin/python3 - built.off lift.off built.sel built.def <<'EOF' || fail "transforms are not composed about the handle centroid"
import sys
def off(path):
    w = open(path).read().split()
    nv = int(w[1])
    return [tuple(map(float, w[4 + 3 * i:7 + 3 * i])) for i in range(nv)]
out, rest = off(sys.argv[1]), off(sys.argv[2])
codes = [int(t) for t in open(sys.argv[3]).read().split('\n') if t and not t.startswith('#')]
T = [float(t) for line in open(sys.argv[4]) if not line.startswith('#') for t in line.split()]
handle = [v for v, c in enumerate(codes) if c == 2]
c = [sum(rest[v][d] for v in handle) / len(handle) for d in range(3)]
# the rotation is about the centroid where the translation put it: the centroid moves by exactly (0, 0, 0.3)
moved = [sum(T[4 * r + k] * c[k] for k in range(3)) + T[4 * r + 3] for r in range(3)]
assert all(abs(moved[d] - c[d] - (0, 0, 0.3)[d]) < 1e-12 for d in range(3)), (moved, c)
# handle vertices reach T p, fixed ones stay
for v in handle:
    target = [sum(T[4 * r + k] * rest[v][k] for k in range(3)) + T[4 * r + 3] for r in range(3)]
    assert max(abs(out[v][d] - target[d]) for d in range(3)) < 1e-9
assert all(out[v] == rest[v] for v, code in enumerate(codes) if code == 0)
EOF

# A transform before any --handle moves every handle; after --handle k only handle k.
"$msdeform" deform lift.off --translate 0,0,1 --handle vertex:0,1 --handle vertex:10,1 --translate 1,0,0 \
  --method shell -o two.off --write-def two.def >/dev/null || fail "two handles"
expected=$'1 0 0 0\n0 1 0 0\n0 0 1 1\n0 0 0 1\n1 0 0 1\n0 1 0 0\n0 0 1 1\n0 0 0 1'
[ "$(grep -v '^#' two.def)" = "$expected" ] || { cat two.def; fail "transform scopes"; }

# The survey cylinder's bend under the shell loses half its volume: warned, though the .def's rotation is
# written with 6 digits (taken for a scaling edit, which asks for area and volume to change: no warning).
if [ -f "$shared/survey/cylinder.off" ]; then
  survey="$shared/survey"
  "$msdeform" deform "$survey/cylinder.off" --sel "$survey/cylinder.sel" --def "$survey/cylinder.def" --method shell \
    -q -o cylinder.off >out.txt 2>err.txt || { cat err.txt; fail "shell on the survey cylinder"; }
  grep -q "the free region's area changed x0.595, the volume changed by -51.1 %" err.txt ||
    { cat err.txt; fail "the cylinder's lost volume was not warned about"; }
fi
# Real meshes, one command each: libigl's knight with its .dmat groups (group 0 fixed, 1 and 2 handles),
# CGAL's y-up armadillo with its feet fixed and both hands moved.
if [ -f "$shared/decimated-knight.off" ]; then
  groups="$shared/decimated-knight-selection.dmat"
  "$msdeform" deform "$shared/decimated-knight.off" --fixed "file:$groups,0" --handle "file:$groups,1" \
    --rotate 0,1,0,30 --handle "file:$groups,2" --translate 0,0.1,0 --method arap -o knight.off \
    --write-sel knight.sel >out.txt 2>&1 || { cat out.txt; fail "knight"; }
  [ "$(grep -c '^0$' knight.sel) $(grep -c '^2$' knight.sel) $(grep -c '^3$' knight.sel)" = "21 27 25" ] ||
    fail "knight groups were not mapped to fixed and handles"
  grep -q "handle error 0\|handle error [0-9.]*e-1[0-9]" out.txt || { cat out.txt; fail "knight handles missed"; }
  "$msdeform" compare --mesh "$shared/decimated-knight.off" --fixed "file:$groups,0" --handle "file:$groups,1" \
    --rotate 0,1,0,30 --handle "file:$groups,2" --translate 0,0.1,0 --methods shell,arap -o knight-cmp \
    >out.txt 2>&1 || { cat out.txt; fail "compare --mesh with --fixed/--handle"; }
  grep -q "(2 results, 0 failed)" out.txt || { cat out.txt; fail "knight comparison"; }
else
  echo "check_regions: $shared/decimated-knight.off missing: knight skipped"
fi
if [ -f "$cgal/armadillo.off" ]; then
  "$msdeform" deform "$cgal/armadillo.off" --fixed halfspace:0,1,0,-40 --handle sphere:63.5,71.7,-32.6,15 \
    --rotate 0,0,1,40 --about 20,60,-20 --handle sphere:-63.5,60.8,-21.7,15 --translate 0,20,0 --method shell \
    -o armadillo.off --write-sel armadillo.sel >out.txt 2>&1 || { cat out.txt; fail "armadillo"; }
  [ "$(grep -c '^0$' armadillo.sel)" -gt 1000 ] || fail "armadillo: the feet were not fixed"
  grep -q "2 handle(s)" out.txt || { cat out.txt; fail "armadillo: two handles expected"; }
else
  echo "check_regions: $cgal/armadillo.off missing: armadillo skipped"
fi

# render: a selection checked before deforming, on the camera options; deform --render draws the result.
"$msdeform" render lift.off --handle sphere:0.5,0.5,0,0.1 --fixed halfspace:1,0,0,0.2 -o region.png >out.txt 2>&1 ||
  { cat out.txt; fail "render a built region"; }
grep -q "region: [0-9]* fixed, [0-9]* free, 1 handle(s)" out.txt || { cat out.txt; fail "render: region summary"; }
grep -q "up +0 +0 +1" out.txt || { cat out.txt; fail "render: the bumpy plane is z-up"; }
"$msdeform" render lift.off --sel built.sel --focus handle --view 90,20 --color selfint --size 160 120 -o selfint.png \
  >out.txt 2>&1 || { cat out.txt; fail "render --color selfint"; }
grep -q "self-intersecting triangle pairs: 0" out.txt || { cat out.txt; fail "render: self-intersections"; }
"$msdeform" render lift.off --color detail --size 160 120 -o detail.png >/dev/null 2>&1 || fail "render --color detail"
"$msdeform" deform lift.off --sel built.sel --def built.def --method shell -o drawn.off --render drawn.png --up z \
  >/dev/null 2>&1 || fail "deform --render"
"$msdeform" decompose lift.off -o base.ply >/dev/null 2>&1 || fail "decompose"
"$msdeform" render base.ply --color property:detail --size 160 120 -o property.png >out.txt 2>&1 ||
  { cat out.txt; fail "render --color property:detail"; }
grep -q "^detail: values in" out.txt || { cat out.txt; fail "render: the PLY property"; }
"$msdeform" render drawn.off --rest lift.off --color rigidity --size 160 120 -o rigidity.png >out.txt 2>&1 ||
  { cat out.txt; fail "render --color rigidity"; }
grep -q "^rigidity against lift.off: mean" out.txt || { cat out.txt; fail "render: rigidity"; }
expect_error 1 "give --rest REST" "$msdeform" render drawn.off --color rigidity -o x.png
expect_error 1 "has no vertex property 'nosuch' (its vertex properties: x, y, z, detail)" \
  "$msdeform" render base.ply --color nosuch -o x.png
for png in region.png selfint.png detail.png drawn.png property.png rigidity.png; do
  [ "$(head -c 8 "$png" | od -An -tx1 | tr -d ' ')" = "89504e470d0a1a0a" ] || fail "$png is not a PNG"
done
if [ -f "$cgal/armadillo.off" ]; then
  "$msdeform" render "$cgal/armadillo.off" -o armadillo.png --size 160 120 >out.txt 2>&1 || fail "render armadillo"
  grep -q "up +0 +1 +0" out.txt || { cat out.txt; fail "the armadillo is y-up"; }
  # --focus handle never draws the shape smaller than without it: both hands span most of the armadillo,
  # so it frames all of it (it zoomed out before); one hand alone is framed closer than the whole shape.
  hands=(--handle sphere:63.5,71.7,-32.6,15 --handle sphere:-63.5,60.8,-21.7,15 --size 160 120)
  "$msdeform" render "$cgal/armadillo.off" "${hands[@]}" -o hands.png >/dev/null 2>&1 &&
    "$msdeform" render "$cgal/armadillo.off" "${hands[@]}" --focus handle -o hands-focus.png >/dev/null 2>&1 ||
    fail "render --focus handle on the armadillo"
  cmp -s hands.png hands-focus.png || fail "--focus handle on handles spanning the shape changed the framing"
  hand=(--handle sphere:63.5,71.7,-32.6,15 --size 160 120)
  "$msdeform" render "$cgal/armadillo.off" "${hand[@]}" -o hand.png >/dev/null 2>&1 &&
    "$msdeform" render "$cgal/armadillo.off" "${hand[@]}" --focus handle -o hand-focus.png >/dev/null 2>&1 ||
    fail "render --focus handle on one hand"
  cmp -s hand.png hand-focus.png && fail "--focus handle on one hand did not move the camera"
fi
expect_error 1 "--up w: expected auto, x, y, z" "$msdeform" render lift.off --up w -o x.png
expect_error 1 "--view 1: expected auto or AZ,EL" "$msdeform" render lift.off --view 1 -o x.png
expect_error 1 "--view 0x10,10: expected auto or AZ,EL" "$msdeform" render lift.off --view 0x10,10 -o x.png  # hex
expect_error 1 "--focus handle: the region has no handle" "$msdeform" render lift.off --focus handle -o x.png
expect_error 1 "needs a region" "$msdeform" render lift.off --color region -o x.png
expect_error 1 "--color bogus: not a colour mode (auto, region, detail, selfint, rigidity, none)" \
  "$msdeform" render lift.off --color bogus -o x.png
expect_error 1 "the picture is a .png" "$msdeform" render lift.off -o x.jpg

# Progress on stderr while deform and compare work; none with --quiet.
"$msdeform" deform lift.off --sel built.sel --def built.def --method multiscale --base-method arap --iterations 3 \
  --detail-scale 0.3 -o p.off >/dev/null 2>err.txt || { cat err.txt; fail "deform with progress"; }
for text in "preparing on" "decomposing S" "preparing the base deformer (arap)" "arap: iteration 1," "the timed frame"; do
  grep -qF "$text" err.txt || { cat err.txt; fail "deform progress: no '$text'"; }
done
"$msdeform" deform lift.off --sel built.sel --def built.def --method arap --iterations 3 -q -o p.off >/dev/null \
  2>err.txt || fail "deform -q"
grep -q "^\[" err.txt && { cat err.txt; fail "deform -q printed progress"; }
grep -q "^warning: arap: stopped after 3 iterations" err.txt || { cat err.txt; fail "deform -q hid a warning"; }
# Over an ARAP base the non-convergence is said once, for the multi-scale frame (it was said by the base
# too), its residual in 3 digits (1.01e-06 read "0.000001", as if at the 1e-6 tolerance).
"$msdeform" deform lift.off --sel built.sel --def built.def --method multiscale --base-method arap --iterations 3 -q \
  -o p.off >/dev/null 2>err.txt || fail "multiscale over arap"
[ "$(grep -c "stopped after" err.txt)" = 1 ] || { cat err.txt; fail "the non-convergence was not said exactly once"; }
grep -Eq "^warning: multiscale-normal: stopped after 3 iterations with relative residual [0-9.]+(e-[0-9]+)?;" err.txt ||
  { cat err.txt; fail "the multi-scale non-convergence warning"; }
"$msdeform" compare --scenes lift --resolution 2k --methods shell,propagate -o progress-cmp >/dev/null 2>err.txt ||
  fail "compare with progress"
grep -q "\[2/2, [0-9]* s, about 0 s left\] lift / propagate" err.txt || { cat err.txt; fail "compare progress"; }

# Bad specs are refused by name, before any work.
expect_error 1 "--handle sphere:1,2,3: 3 numbers given, expected X,Y,Z,R" \
  "$msdeform" deform lift.off --handle sphere:1,2,3 --translate 0,0,1 -o x.off
expect_error 1 "selects no vertex" "$msdeform" deform lift.off --handle sphere:9,9,9,0.01 --translate 0,0,1 -o x.off
expect_error 1 "the vertex id must be an integer in [0," \
  "$msdeform" deform lift.off --handle vertex:99999999,1 --translate 0,0,1 -o x.off
expect_error 1 "unknown selection 'cube'" "$msdeform" deform lift.off --handle cube:1 --translate 0,0,1 -o x.off
# A handle's transform keeps a rotation only up to whole turns: more than half a turn per handle is refused
# (190 degrees gave the -170 degree transform, and methods that blend rotations twisted the other way).
# +180 and -180 are one matrix too, and a scale by two negative factors is a half turn, by three a half turn
# and a mirror (-1 was accepted, -1,-1,1 refused).
expect_error 1 "add up to 1e+80 degrees, half a turn or more" \
  "$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,1,0,1e80 -o x.off
expect_error 1 "the turns of handle 0 add up to 190 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,1,0,-190 -o x.off
expect_error 1 "the turns of handle 0 add up to 180 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,1,0,-180 -o x.off
expect_error 1 "--rotate 1,0,0,100: the turns of handle 1 add up to 200 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --handle vertex:40,1 --rotate 0,1,0,100 --rotate 1,0,0,100 -o x.off
expect_error 1 "--scale -1,-1,1: the turns of handle 0 add up to 180 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --scale -1,-1,1 --rotate 0,0,1,90 -o x.off
expect_error 1 "--scale -1: the turns of handle 0 add up to 180 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --scale -1 -o x.off
# Two mirrors across perpendicular planes are the half turn -1,-1,1 is (they passed, one step at a time).
expect_error 1 "--scale 1,-1,1: the transform of handle 0 turns it by half a turn here" \
  "$msdeform" deform lift.off --handle vertex:0,1 --scale -1,1,1 --scale 1,-1,1 -o x.off
expect_error 1 "add up to 180.0001 degrees" \
  "$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,0,1,179.9999 --rotate 0,0,1,0.0002 -o x.off
"$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,1,0,179 --method shell -o turned.off >/dev/null 2>&1 ||
  fail "--rotate of 179 degrees"
expect_error 1 "'0x10' is not a finite decimal number" \
  "$msdeform" deform lift.off --handle vertex:0,1 --translate 0x10,0,0 -o x.off
expect_error 2 "--handle has no value before --translate" \
  "$msdeform" deform lift.off --fixed vertex:5,1 --handle --translate 0,0.1,0 -o x.off
expect_error 1 "--rotate 0,0,0,30: the axis is zero" "$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,0,0,30 -o x.off
# A tiny axis has a direction (its square underflowed: "the axis is zero"); same result as a unit axis.
"$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,0,1e-300,30 --method shell --write-def tiny.def -o tiny.off >/dev/null 2>&1 ||
  fail "--rotate about a tiny axis"
"$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,0,1,30 --method shell --write-def unit.def -o unit.off >/dev/null 2>&1 ||
  fail "--rotate about a unit axis"
cmp -s tiny.def unit.def || fail "a tiny axis gave another rotation than the unit axis"
expect_error 1 "'nan' is not a finite decimal number" "$msdeform" deform lift.off --handle vertex:0,1 --translate nan,0,0 -o x.off
expect_error 1 "not both" "$msdeform" deform lift.off --sel lift.sel --handle vertex:0,1 --translate 0,0,1 -o x.off
expect_error 1 "not both" "$msdeform" deform lift.off --sel lift.sel --def lift.def --translate 0,0,1 -o x.off
expect_error 1 "needs handle transforms" "$msdeform" deform lift.off --handle vertex:0,1 -o x.off
expect_error 1 "give the group" "$msdeform" deform lift.off --handle file:groups.dmat --translate 0,0,1 -o x.off
expect_error 1 "is one of the inputs" "$msdeform" deform lift.off --sel lift.sel --def lift.def --write-sel lift.sel -o x.off
expect_error 1 "the radius is negative" "$msdeform" deform lift.off --handle sphere:0.5,0.5,0,-1 --translate 0,0,1 -o x.off
expect_error 1 "--about 0,0,0 follows no --rotate or --scale" \
  "$msdeform" deform lift.off --about 0,0,0 --handle vertex:0,1 --rotate 0,0,1,90 -o x.off
# --about names the centre of the rotation it follows: the point stays where it is.
"$msdeform" deform lift.off --handle vertex:0,1 --rotate 0,0,1,90 --about 1,0,0 --write-def about.def \
  --method shell -o about.off >/dev/null 2>&1 || fail "--rotate ... --about"
[ "$(grep -v '^#' about.def | head -2 | awk '{printf "%.6f ", $4}')" = "1.000000 -1.000000 " ] ||
  { cat about.def; fail "--about: the rotation is not about (1, 0, 0)"; }
expect_error 1 "every fixed vertex was taken by a later --handle" \
  "$msdeform" deform lift.off --fixed vertex:0,1 --handle vertex:0,2 --translate 0,0,1 -o x.off
expect_error 1 "name it NAME.sel" "$msdeform" deform lift.off --sel lift.sel --def lift.def --write-sel out.dmat -o x.off
cp lift.sel mine.sel
expect_error 1 "is one of the inputs" \
  "$msdeform" deform lift.off --handle file:mine.sel --translate 0,0,1 --write-sel mine.sel -o x.off
cmp -s mine.sel lift.sel || fail "a file: input was replaced"
expect_error 1 "is not an integer" "$msdeform" deform lift.off --handle file:lift.sel,abc --translate 0,0,1 -o x.off
# --write-sel / --write-def are written once the command has succeeded: a run refused after the region is
# built (here: --controls-output with a method without control points) leaves the files as they were.
echo "mine" >keep.sel
echo "mine" >keep.def
expect_error 1 "--controls-output applies to methods with control points" \
  "$msdeform" deform lift.off --handle vertex:0,1 --translate 0,0,1 --method shell --controls-output c.off \
  --write-sel keep.sel --write-def keep.def -o x.off
[ "$(cat keep.sel keep.def)" = "$(printf 'mine\nmine')" ] || fail "a failed run replaced --write-sel / --write-def"
expect_error 1 "a built-in scene has no vertex properties" \
  "$msdeform" render --scene lift --color property:detail --write-sel keep.sel -o x.png
[ "$(cat keep.sel)" = "mine" ] || fail "a failed render replaced --write-sel"
[ -e x.off ] && fail "a refused run wrote its output"
echo "check_regions: all passed"
