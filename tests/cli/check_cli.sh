#!/usr/bin/env bash
# The msdeform program with bad paths and outputs, and with seams (ctest test cli_paths_and_outputs;
# issue 14, kinds 5 and 6): clear errors before any work and never a crash (exit 1, not 134), inputs never
# replaced unless --force, read-only outputs kept, a non-zero exit when a comparison run failed, and a
# mesh split along a seam warned about and welded with --weld while the file keeps its vertices.
# Usage: check_cli.sh MSDEFORM WORK_DIR
set -uo pipefail
msdeform="$1"
work="$2"
source "$(cd "$(dirname "$0")" && pwd)/common.sh"
start_in "$work"

# Paths that cannot even be examined: a symlink loop, a name over 255 bytes.
ln -s loop-b.off loop-a.off
ln -s loop-a.off loop-b.off
expect_error 1 "loop-a.off" "$msdeform" info loop-a.off
long=$(printf 'a%.0s' $(seq 300)).off
expect_error 1 "File name too long" "$msdeform" info "$long"
expect_error 1 "Too many levels of symbolic links" "$msdeform" deform loop-a.off --sel lift.sel --def lift.def -o x.off

# Outputs are checked before any work.
expect_error 1 "nothing was computed" "$msdeform" deform --scene lift --method shell -o missing-folder/x.off
cp lift.off input.off
expect_error 1 "is one of the inputs" "$msdeform" deform input.off --sel lift.sel --def lift.def -o input.off --method shell
cmp -s input.off lift.off || fail "the input was changed by a refused run"
"$msdeform" deform input.off --sel lift.sel --def lift.def -o input.off --force --method shell >/dev/null ||
  fail "--force did not let the output replace the input"
cmp -s input.off lift.off && fail "--force ran but the input is unchanged"
cp lift.off readonly.off
chmod a-w readonly.off
expect_error 1 "is read-only" "$msdeform" deform --scene lift --method shell -o readonly.off
cmp -s readonly.off lift.off || fail "a read-only output was replaced"
mkdir folder.off
expect_error 1 "is a folder" "$msdeform" deform --scene lift --method shell -o folder.off
# A legal name of 250 bytes is written (the temporary file used to add a suffix past 255).
name=$(printf 'b%.0s' $(seq 246)).off
"$msdeform" deform --scene lift --resolution 2k --method shell -o "$name" >/dev/null || fail "a 250-byte output name"
[ -s "$name" ] || fail "the 250-byte output was not written"

# A box with its corners the wrong way round said "selects no vertex".
expect_error 1 "--fixed box:1,1,1,-1,-1,-1: the box's x range is empty (1 > -1): give the low corner first" \
  "$msdeform" deform lift.off --fixed box:1,1,1,-1,-1,-1 --handle sphere:0.5,0.5,0,0.1 --translate 0,0,0.1 -o x.off

# The geodesic time factor the error messages suggest can be set.
"$msdeform" deform --scene lift --resolution 2k --method propagate --field geodesic --geodesic-time-factor 4 \
  -o geodesic.off >/dev/null || fail "--geodesic-time-factor"

# Option ranges read as ranges.
# Usage errors exit 2 (CLI11's own codes, 105 and up, before).
expect_error 2 "not in range 1 to 1000000" "$msdeform" deform --scene lift --method arap --iterations 0 -o x.off
expect_error 2 "--bogus" "$msdeform" deform --scene lift --bogus -o x.off
# "--kb=" with nothing after '=': CLI11 would read the next argument as its value and blame that.
expect_error 2 "--kb=: no value after '='" "$msdeform" deform --scene lift --kb= --ks 1 -o x.off
expect_error 2 "unknown subcommand 'foo'; the subcommands are info, scene, deform" "$msdeform" foo
# decompose and render apply no transforms and offer no options for them (decompose's help listed them,
# and a --translate given with a region was ignored).
expect_error 2 "--def is not an option of decompose (deform, compare, view take it)" "$msdeform" decompose lift.off --def lift.def -o b.ply
expect_error 2 "--translate is not an option of render (deform, compare, view take it)" \
  "$msdeform" render lift.off --sel lift.sel --translate=0,0,1 -o b.png
expect_error 2 "--translate is not an option of render (deform, compare, view take it)" \
  "$msdeform" render --scene lift --translate 0,0,1 -o b.png  # its value was taken for the mesh
# An output path that is an existing folder without an extension said "unknown format ''".
mkdir -p out-folder
expect_error 1 "out-folder is a folder; give a mesh file name" "$msdeform" deform --scene lift -o out-folder
# NaN passed CLI11's ranges and reached the library (exit 1); every floating-point option refuses it now.
expect_error 2 "--tolerance: 'nan' is not a finite decimal number" "$msdeform" deform --scene lift --method arap --tolerance nan -o x.off
expect_error 2 "'0x1p-3' is not a finite decimal number" "$msdeform" deform --scene lift --method arap --tolerance 0x1p-3 -o x.off
expect_error 2 "resolution '1': expected a vertex count from 16" "$msdeform" scene lift --resolution 1 -o x
expect_error 2 "--encoding: foo not in {vectors,normal,volumes,transfer}" \
  "$msdeform" deform --scene lift --method multiscale --encoding foo -o x.off
# The volumes encoding's relaxation takes --iterations (its warning says to raise the limit); --tolerance,
# a fraction of the diagonal for arap and primo, does not apply to it.
"$msdeform" deform --scene lift --resolution 2k --method multiscale --encoding volumes --iterations 3 -o v.off \
  >out.txt 2>err.txt || { cat err.txt; fail "multiscale volumes with --iterations"; }
grep -qF "frame: 3 iterations" out.txt || { cat out.txt; fail "--iterations 3 did not limit the volumes' sweeps"; }
expect_error 1 "--tolerance applies to --method arap, primo (or multiscale with such a --base-method), not --method multiscale-volumes" \
  "$msdeform" deform --scene lift --method multiscale --encoding volumes --tolerance 0.1 -o x.off
# compare refuses an option that none of its methods reads (it would be ignored), before any work.
expect_error 1 "--iterations applies to --method arap, primo, multiscale-volumes (or multiscale with such a --base-method), not to any of --methods shell, propagate" \
  "$msdeform" compare --scenes lift --methods shell,propagate --iterations 5 -o cmp-unread
expect_error 1 "none of --methods shell, arap has a base to decompose" \
  "$msdeform" compare --scenes lift --methods shell,arap --detail-scale 0.3 -o cmp-unread
grep -q "building scene" err.txt && fail "compare built scenes before refusing an unread option"
# Each method's own settings are refused with a method that does not read them, by either command.
# Scales that cancel in the product lost the handle's centre to rounding, and moved it by minus its centroid.
expect_error 1 "--scale 1e200: handle 0's transform reaches an entry of 1e+200 at this step" \
  "$msdeform" deform lift.off --fixed halfspace:1,0,0,0.2 --handle halfspace:-1,0,0,-0.8 --scale 1e200 --scale 1e-200 --method shell -o x.off
expect_error 1 "--kb applies to --method shell (or multiscale with such a --base-method), not --method arap" \
  "$msdeform" deform --scene lift --method arap --kb 5 -o x.off
expect_error 1 "--blend applies to --method propagate (or multiscale with such a --base-method), not --method multiscale-normal" \
  "$msdeform" deform --scene lift --method multiscale --blend decomposed -o x.off
expect_error 1 "--laplacian-explicit applies to --method laplacian (or multiscale with such a --base-method), not --methods gradient" \
  "$msdeform" compare --scenes lift --methods gradient --laplacian-explicit -o cmp-unread
"$msdeform" deform --scene lift --resolution 2k --method multiscale --base-method propagate --field euclidean \
  -o x.off >/dev/null || fail "--field with a propagate base"
# Options of another field or base are refused too.
expect_error 1 "--geodesic-time-factor applies to --field geodesic" \
  "$msdeform" deform --scene lift --method propagate --geodesic-time-factor 50 -o x.off
expect_error 1 "--fairing applies to --base fairing, not --base low-pass" \
  "$msdeform" deform --scene lift --method multiscale --fairing 3 -o x.off
expect_error 1 "--detail-scale applies to --base low-pass or remeshed, not --base fairing" \
  "$msdeform" deform --scene lift --method multiscale --base fairing --detail-scale 0.5 -o x.off
expect_error 1 "--low-pass-solver applies to --base low-pass or remeshed, not --base fairing" \
  "$msdeform" deform --scene lift --method multiscale --base fairing --low-pass-solver factorisation -o x.off
expect_error 2 "--low-pass-solver" "$msdeform" decompose --scene lift --low-pass-solver cholesky -o x.ply
# Either solver gives the base, and decompose says which ran.
"$msdeform" decompose --scene lift --resolution 2000 --detail-scale 0.3 --low-pass-solver conjugate-gradients \
  -o cg.ply | grep -q "solved by conjugate gradients, [0-9]* iterations" || fail "decompose does not say CG ran"
"$msdeform" decompose --scene lift --resolution 2000 --detail-scale 0.3 --low-pass-solver factorisation -o lu.ply |
  grep -q "solved by factorisation" || fail "decompose does not say the factorisation ran"
# A reference that is not compared is refused before the output folder is made.
expect_error 1 "the reference method 'arap' is not among the compared methods" \
  "$msdeform" compare --scenes lift --methods shell --reference arap -o cmp-noref
[ -e cmp-noref ] && fail "a refused compare made its output folder"
# Without a detail layer there is nothing to iterate: no "0 iterations, relative residual -1".
"$msdeform" deform --scene lift --resolution 16 --method multiscale --encoding volumes -o v.off >out.txt 2>&1 ||
  fail "multiscale volumes at 16 vertices"
grep -qF "frame: no iteration was needed" out.txt || { cat out.txt; fail "the frame line of a solve-free frame"; }
# STL output keeps no vertex list: said before the work.
"$msdeform" deform --scene lift --resolution 2k --method shell -o lifted.stl >/dev/null 2>err.txt || fail "deform to STL"
grep -q "STL keeps no vertex list" err.txt || fail "no warning that STL output renumbers the vertices"
# ... nor on input, where a .sel of the OFF file selected other vertices without a word.
"$msdeform" scene lift --resolution 2k -o stl-in >/dev/null
"$msdeform" deform lifted.stl --sel stl-in/lift.sel --def stl-in/lift.def -o from-stl.off >/dev/null 2>err.txt
grep -q "lifted.stl: STL keeps no vertex list, so its vertices are numbered by first appearance" err.txt ||
  { cat err.txt; fail "no warning that an STL input's .sel may not apply"; }
# The report measures the shape: the shell under a 120° bend tears edges (warned), ARAP does not.
"$msdeform" deform --scene bend120 --resolution 2k --method shell -o s.off >out.txt 2>err.txt || fail "shell bend"
grep -q "shape: .* of the free region's edges changed length beyond 1.5x" out.txt || { cat out.txt; fail "no shape line"; }
grep -q "warning: the result does not keep the shape's proportions: an edge at vertex" err.txt ||
  { cat err.txt; fail "the shell's torn bend was not warned about"; }
"$msdeform" deform --scene bend120 --resolution 2k --method arap -o a.off >out.txt 2>err.txt || fail "arap bend"
grep -q "proportions" err.txt && { cat err.txt; fail "ARAP's bend was warned about"; }
# Self-intersections the edit added are counted and warned about (no single run counted them: ARAP added
# 76 pairs to a camel with exit 0 and no word); --no-self-intersections skips the count.
"$msdeform" deform --scene bar-twist135 --resolution 2k --method shell -o twisted.off >out.txt 2>err.txt ||
  fail "shell twist"
grep -q "self-intersections: [1-9][0-9]* face pair(s) added by the edit (0 at rest)" out.txt || { cat out.txt; fail "no count"; }
grep -q "warning: the result intersects itself: .* msdeform render twisted.off --color selfint shows them" err.txt ||
  { cat err.txt; fail "no self-intersection warning"; }
"$msdeform" deform --scene bar-twist135 --resolution 2k --method shell --no-self-intersections -o twisted.off \
  >out.txt 2>err.txt || fail "shell twist without the count"
grep -q "self-intersections" out.txt err.txt && { cat out.txt err.txt; fail "--no-self-intersections counted"; }
# A result too large to count is warned about on stderr with the other checks (third break test: only a
# line on stdout said so).
"$msdeform" deform --scene lift --resolution 600k --method shell -o large.ply >out.txt 2>err.txt || fail "600k lift"
grep -q "warning: the result was not checked for self-intersections (1[0-9]* faces, over 1000000)" err.txt ||
  { cat out.txt err.txt; fail "an uncounted result was not warned about"; }
# With no free vertex the shape line spoke of "100 % of the free region's edges", and the warning blamed
# large rotations rather than the missing free region (which the prepare warning names).
"$msdeform" scene lift --resolution 2k -o nofree >/dev/null
"$msdeform" deform nofree/lift.off --fixed box:-1,-1,-1,0.5,2,2 --handle box:0.5,-1,-1,2,2,2 --translate 0,0,0.1 \
  -o nofree.off >out.txt 2>err.txt || fail "deform without a free vertex"
grep -q "shape: 100 % of the edges between vertices placed by different transforms (no vertex is free)" out.txt ||
  { cat out.txt; fail "the shape line without a free vertex"; }
grep -q "the region has no free vertex" err.txt && ! grep -q "proportions" err.txt ||
  { cat err.txt; fail "the warnings without a free vertex"; }
# decompose: a vertex no face uses has no detail (its height was the distance to some other part of B).
printf 'OFF\n9 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n5 5 5\n3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 1 2 6\n3 1 6 5\n3 2 3 7\n3 2 7 6\n3 3 0 4\n3 3 4 7\n' >cube-stray.off
"$msdeform" decompose cube-stray.off -o cube-stray.ply >out.txt 2>err.txt || { cat err.txt; fail "decompose with an unused vertex"; }
grep -q "1 vertices no face uses: height 0" out.txt || { cat out.txt; fail "decompose did not set the unused vertex's height to 0"; }
[ "$(awk '/end_header/ { on = 1; next } on && NR > 0 { n++; if (n == 9) print $4 }' cube-stray.ply)" = 0 ] ||
  fail "the unused vertex's detail in the PLY is not 0"
# decompose reports the automatic scale's candidates as progress, and -q silences them as in deform.
"$msdeform" decompose lift.off -o lift-base.ply >out.txt 2>err.txt || { cat err.txt; fail "decompose lift"; }
grep -q "detail scale candidate 1 of at most" err.txt || { cat err.txt; fail "decompose printed no candidates"; }
# The candidates after the first come within half a second: the last of them is printed all the same.
[ "$(grep -c "detail scale candidate" err.txt)" -ge 2 ] || { cat err.txt; fail "decompose printed only its first candidate"; }
"$msdeform" decompose lift.off -q -o lift-base.ply >out.txt 2>err.txt || { cat err.txt; fail "decompose -q"; }
[ -s err.txt ] && { cat err.txt; fail "decompose -q printed progress"; }
# A --mesh named like a built-in scene is kept apart (the two edits were merged into one row of verdicts
# and one's meshes overwritten).
"$msdeform" compare -q --scenes lift --resolution 300 --mesh lift.off --sel lift.sel --def lift.def --methods shell \
  -o cmp-clash >out.txt 2>err.txt || { cat err.txt; fail "compare with a --mesh named like a scene"; }
grep -q "note: two edits are named lift; the --mesh is called lift-2 here" err.txt || { cat err.txt; fail "no rename note"; }
[ -f cmp-clash/meshes/lift--shell.ply ] && [ -f cmp-clash/meshes/lift-2--shell.ply ] ||
  { ls cmp-clash/meshes; fail "the clashing edits do not have their own mesh files"; }
# Faces the loader drops are said: the output lists fewer faces than the file (it was silent).
printf 'OFF\n5 5 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0\n3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n3 2 4 1\n' >dup.off
"$msdeform" deform dup.off --fixed vertex:0,0 --fixed vertex:1,0 --handle vertex:2,0 --translate 0,0,0.1 \
  -o dup-out.off >out.txt 2>err.txt || { cat err.txt; fail "deform with a duplicate face"; }
grep -q "note: dup.off: 1 duplicate face dropped; the meshes written list the faces as loaded" err.txt ||
  { cat err.txt; fail "deform did not say the loader dropped a duplicate face"; }
# The same note for the files of compare --survey (it was silent there).
mkdir survey-dup
for name in plane cylinder bar cactus; do
  cp lift.off "survey-dup/$name.off"; cp lift.sel "survey-dup/$name.sel"; cp lift.def "survey-dup/$name.def"
done
tail -n 1 lift.off >>survey-dup/bar.off  # the last face again
sed -i "2s/^\([0-9]*\) \([0-9]*\)/\1 $(($(sed -n 2p lift.off | cut -d' ' -f2) + 1))/" survey-dup/bar.off
"$msdeform" compare -q --survey survey-dup --methods propagate -o cmp-survey-dup >out.txt 2>err.txt ||
  { cat err.txt; fail "compare --survey with a duplicate face"; }
grep -q "note: survey-dup/bar.off: 1 duplicate face dropped" err.txt ||
  { cat err.txt; fail "compare --survey did not say the loader dropped a duplicate face"; }
# A region without a handle and a .def: the region is named (the message blamed the empty .def).
printf '0\n0\n1\n1\n1\n' >nohandle.sel
printf '# none\n' >nohandle.def
expect_error 1 "nohandle.sel defines no handle (every vertex fixed or free): there is nothing for nohandle.def to move" \
  "$msdeform" deform dup.off --sel nohandle.sel --def nohandle.def -o nohandle.off
# render refuses a mesh at one point, as deform does (it wrote a blank picture).
printf 'OFF\n3 1 0\n1 1 1\n1 1 1\n1 1 1\n3 0 1 2\n' >point.off
expect_error 1 "render: point.off: the input has no extent" "$msdeform" render point.off -o point.png
[ -e point.png ] && fail "render wrote a picture of a mesh with no extent"
# compare --methods multiscale, as deform's --method takes it, runs every encoding (it was an unknown method).
"$msdeform" compare -q --resolution 300 --mesh lift.off --sel lift.sel --def lift.def --methods multiscale,shell \
  -o cmp-multiscale >out.txt 2>err.txt || { cat err.txt; fail "compare --methods multiscale"; }
for m in multiscale-vectors multiscale-normal multiscale-volumes multiscale-transfer shell; do
  [ -f "cmp-multiscale/methods/$m.html" ] || { ls cmp-multiscale/methods; fail "compare --methods multiscale ran no $m"; }
done
# compare -o naming a file fails before any scene is built.
touch not-a-folder
expect_error 1 "is a file; compare writes a folder" "$msdeform" compare --scenes lift -o not-a-folder
grep -q "building scene" err.txt && fail "compare built scenes before refusing -o"
# A resolution is decimal (0x10 was read as hexadecimal 16).
expect_error 2 "resolution '0x10'" "$msdeform" scene lift --resolution 0x10 -o .
expect_error 2 "resolution ' 100'" "$msdeform" scene lift --resolution " 100" -o .
# Integers are decimal: 010 was read as octal 8, 0x10 as 16, and 2.5 called "not in range".
expect_error 2 "--lattice-cells: '0x10' is not a whole decimal number" \
  "$msdeform" deform --scene lift --method lattice --lattice-cells 0x10 -o x.off
expect_error 2 "--lattice-cells: '2.5' is not a whole decimal number" \
  "$msdeform" deform --scene lift --method lattice --lattice-cells 2.5 -o x.off
"$msdeform" deform --scene lift --method arap --iterations 010 -o x.off >out.txt 2>&1 || { cat out.txt; fail "--iterations 010"; }
grep -q "frame: 10 iterations" out.txt || { cat out.txt; fail "--iterations 010 was not read as 10"; }
# A length out of range is named, not compared against a bound printed with 300 digits.
expect_error 2 "'inf' must be a finite length >= 0" "$msdeform" render --scene lift --color detail --detail-scale inf -o x.png
[ "$(wc -c <err.txt)" -lt 300 ] || { cat err.txt; fail "the --detail-scale message is too long"; }

# compare: a run that fails makes the exit status non-zero (the pages are still written).
expect_error 1 "1 of 2 runs failed" "$msdeform" compare --mesh lift.off --sel lift.sel --def lift.def \
  --methods shell,multiscale-normal --detail-scale 1e9 -o cmp
[ -s cmp/index.html ] || fail "compare wrote no index.html"
# Surface methods on a point cloud are not run, as the input asks: not a failure (exit 1 before).
printf 'OFF\n4 0 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n' >cloud.off
printf '0\n1\n1\n2\n' >cloud.sel
printf '1 0 0 0\n0 1 0 0\n0 0 1 0.1\n0 0 0 1\n' >cloud.def
"$msdeform" compare --mesh cloud.off --sel cloud.sel --def cloud.def --methods shell,rbf -o cmp-cloud >out.txt 2>&1 ||
  { cat out.txt; fail "compare on a point cloud"; }
grep -q "not run (surface methods; the input is not a surface): shell" out.txt || { cat out.txt; fail "compare: shell on a cloud"; }
grep -q "(2 results, 0 failed, 1 surface method not run" out.txt || { cat out.txt; fail "compare: cloud summary"; }
expect_error 1 "compare: no method ran: the input is not a surface" \
  "$msdeform" compare --mesh cloud.off --sel cloud.sel --def cloud.def --methods shell,arap -o cmp-cloud2
# render needs a surface for self-intersections, and does not take a --method.
expect_error 1 "render --color selfint needs a surface" "$msdeform" render cloud.off --color selfint -o c.png
grep -q -- "--method" err.txt && { cat err.txt; fail "render advised a --method"; }
# compare: a stray vertex is the input's fault: warned about once, not by every method.
python3 - <<'PY' || fail "could not write the plane with a stray vertex"
lines = open("lift.off").read().split("\n")
x = lines[2].split()
x[2] = str(float(x[2]) + 1e6)
lines[2] = " ".join(x)
open("stray.off", "w").write("\n".join(lines))
PY
"$msdeform" compare --mesh stray.off --sel lift.sel --def lift.def --methods shell,gradient -o cmp-stray >/dev/null 2>err.txt
[ "$(grep -c "a few outlying vertices" err.txt)" = 1 ] || { cat err.txt; fail "compare did not warn of the stray vertex once"; }
# render: the stray vertex frames the picture (the shape a dot in it, exit 0 without a word): said.
"$msdeform" render stray.off -o stray.png >/dev/null 2>err.txt || fail "render of the plane with a stray vertex"
grep -q "warning: render: a few outlying vertices.*the shape may be too small to see" err.txt ||
  { cat err.txt; fail "render did not warn that a stray vertex frames the picture"; }
# One edit's contact sheet fills rows (it was one column, 656 x 5188 pixels for 10 pictures).
/usr/bin/python3 -c "import struct, sys; w, h = struct.unpack('>II', open(sys.argv[1], 'rb').read()[16:24]); sys.exit(0 if w > h else 1)" \
  cmp-stray/contact_sheet.png || fail "one edit's contact sheet is taller than wide"

# Seams: the plane with its right half on its own copies of the cut's vertices.
python3 - <<'PY' || fail "could not write the split plane"
lines = open("lift.off").read().split("\n")
nv, nf = map(int, lines[1].split()[:2])
verts = [list(map(float, l.split()[:3])) for l in lines[2:2 + nv]]
faces = [list(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]]
copy = {}
for f in faces:
    if sum(verts[v][0] for v in f) / 3 < 0.5:
        continue
    for k, v in enumerate(f):
        if abs(verts[v][0] - 0.5) < 1e-3:
            if v not in copy:
                copy[v] = len(verts)
                verts.append(verts[v])
            f[k] = copy[v]
labels = [l.split("#")[0].strip() for l in open("lift.sel")]
labels = [l for l in labels if l]
labels += [labels[v] for v in sorted(copy, key=copy.get)]
with open("split.off", "w") as out:
    out.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
    out.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in verts)
    out.writelines(f"3 {a} {b} {c}\n" for a, b, c in faces)
open("split.sel", "w").write("\n".join(labels) + "\n")
PY
"$msdeform" info split.off | grep -q "seam vertices  *[1-9]" || fail "info does not count the seam"
# Sizes beyond msdeform's range are named by info too (it stopped in the seam count with an internal message).
printf 'OFF\n4 2 0\n0 0 0\n1e200 0 0\n0 1e200 0\n1e200 1e200 0\n3 0 1 2\n3 1 3 2\n' > huge.off
"$msdeform" info huge.off > out.txt 2>&1 || fail "info on coordinates of 1e200"
grep -q "sizes  *coordinates too large" out.txt || fail "info does not name the sizes beyond 1e70"
# An OBJ's texture coordinates and normals are read past; the written result says it does not keep them.
printf 'mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf 2/1/1 4/1/1 3/1/1\n' > uv.obj
"$msdeform" deform uv.obj --handle vertex:3,0 --translate 0,0,0.1 --method rbf -o uv-out.obj >out.txt 2>&1 ||
  { cat out.txt; fail "deform of an OBJ with texture coordinates"; }
grep -q "uv.obj line 1: its colours, normals, texture coordinates, materials or other data are not kept" out.txt ||
  { cat out.txt; fail "no warning that the OBJ's attributes are lost"; }
"$msdeform" deform split.off --sel split.sel --def lift.def --method shell -o apart.off >/dev/null 2>err.txt ||
  fail "deform of the split plane"
grep -q "split along seams" err.txt || fail "no seam warning"
"$msdeform" deform split.off --sel split.sel --def lift.def --method shell --weld 0 -o welded.off >out.txt 2>err.txt ||
  { cat err.txt; fail "deform --weld 0"; }
grep -q "welded" out.txt || fail "--weld printed nothing"
expect_error 2 "--weld: 'nan' is not a finite decimal number" "$msdeform" deform split.off --sel split.sel \
  --def lift.def --method shell --weld nan -o nan.off
grep -q "split along seams" err.txt && fail "a seam warning after welding"
# A weld so wide it would merge the whole mesh is refused naming an edge it would collapse (it said the weld
# left a point cloud; before that, it collapsed the boundary loops with exit 0).
expect_error 1 "the two ends of an edge of length" "$msdeform" deform split.off --handle box:-9,-9,-9,9,9,9 --translate 0.1,0,0 \
  --weld 10 --method arap -o x.off
[ "$(sed -n 2p welded.off | cut -d' ' -f1)" = "$(sed -n 2p split.off | cut -d' ' -f1)" ] ||
  fail "--weld changed the vertex count of the output"
# A singular handle transform is named by what it does to the handle: a plane, a line or a point (its rank to
# 1e-12 of its largest singular value and to 1e-6: a uniform scale by 1e-13, or a reflection by 1e-300,
# collapses the handle as surely; by 1e-3 it does not). A half turn (a .def holds one) is said to turn
# either way; 179 degrees is not one.
for rank in "plane:1 0 0 0\n0 1 0 0\n0 0 0 0.1\n0 0 0 1" "line:1 0 0 0\n0 0 0 0\n0 0 0 0.1\n0 0 0 1" \
  "point:0 0 0 0\n0 0 0 0\n0 0 0 0.1\n0 0 0 1" "plane:1 0 0 0\n0 1 0 0\n0 0 1e-13 0.1\n0 0 0 1" \
  "point:1e-13 0 0 0\n0 1e-13 0 0\n0 0 1e-13 0.1\n0 0 0 1" "point:1e-300 0 0 0\n0 1e-300 0 0\n0 0 -1e-300 0.1\n0 0 0 1" \
  "none:1e-3 0 0 0\n0 1e-3 0 0\n0 0 1e-3 0.1\n0 0 0 1" "reflection:1e-3 0 0 0\n0 1e-3 0 0\n0 0 -1e-3 0.1\n0 0 0 1" \
  "half:-1 0 0 0\n0 -1 0 0\n0 0 1 0.1\n0 0 0 1" "none:-0.999848 -0.017452 0 0\n0.017452 -0.999848 0 0\n0 0 1 0.1\n0 0 0 1"; do
  printf -- "${rank#*:}\n" >singular.def
  "$msdeform" deform lift.off --sel lift.sel --def singular.def --method shell -o singular.off >/dev/null 2>err.txt ||
    { cat err.txt; fail "deform with a singular handle transform"; }
  case "${rank%%:*}" in
    plane) grep -q "flattens the handle onto a plane" err.txt ;;
    line) grep -q "collapses the handle onto a line" err.txt ;;
    point) grep -q "collapses the handle to a point" err.txt ;;
    none) ! grep -q "transform of handle" err.txt ;;
    reflection) grep -q "a reflection" err.txt ;;
    half) grep -q "transform of handle 0 is a half turn (180 degrees): which way round" err.txt ;;
  esac || { cat err.txt; fail "the warning for a transform of rank ${rank%%:*}"; }
done
# Under an address-space limit (ulimit -v) OpenBLAS's worker retried its 128 MB buffer forever: every run
# hung, `--version` at exit, a prepare in its factorisation (300–700 MB, the 10k lift). Now each finishes
# or says what limit it needs. (Not under AddressSanitizer, whose shadow memory needs no limit.)
if ! ldd "$msdeform" | grep -q libasan; then
  for limit in 150000 250000 350000 600000; do
    (ulimit -v $limit && timeout 60 "$msdeform" --version >/dev/null) || fail "--version under ulimit -v $limit"
    (ulimit -v $limit && timeout 120 "$msdeform" deform --scene lift --resolution 10k --method shell -o limited.off \
      >/dev/null 2>err.txt)
    got=$?
    [ $got = 0 ] || { [ $got = 1 ] && grep -q "raise the limit to at least" err.txt; } ||
      { cat err.txt; fail "deform under ulimit -v $limit exited $got"; }
  done
  # Out of memory under such a limit says so (it said "out of memory", or Embree's "error 4").
  for run in "deform --scene lift --resolution 100k --method laplacian -o limited.off" \
             "compare --resolution 2k -o limited"; do
    (ulimit -v 250000 && timeout 120 "$msdeform" $run >/dev/null 2>err.txt)
    got=$?
    [ $got = 1 ] && grep -q "out of memory.* under the address-space limit (ulimit -v) of 244 MB: raise the limit" err.txt ||
      { cat err.txt; fail "$run under ulimit -v 250000 exited $got without naming the limit"; }
  done
fi
echo "check_cli: passed"
