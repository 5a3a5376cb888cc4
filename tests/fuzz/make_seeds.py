#!/usr/bin/env python3
"""Writes the fuzzers' seed corpus (tests/fuzz/corpus/<name>/): small valid files of every format and
variant the readers accept, and the bad inputs of issue 14 that once crashed, hung or misled them.
Inputs the fuzzers find later are added beside these as crash-<sha1> files by scripts/fuzz.sh.
The .sel and .dmat seeds start with one byte, the mesh's vertex count (fuzz_region.cpp)."""
import os
import struct
import sys

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
TETRA_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def put(folder, name, data):
    os.makedirs(os.path.join(root, folder), exist_ok=True)
    with open(os.path.join(root, folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def off(vs, fs, header="OFF"):
    lines = [header, f"{len(vs)} {len(fs)} 0"] + [" ".join(map(str, v)) for v in vs]
    return "\n".join(lines + [f"{len(f)} " + " ".join(map(str, f)) for f in fs]) + "\n"


# OFF
put("off", "tetra.off", off(TETRA_V, TETRA_F))
put("off", "wound_against.off", "OFF 4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 3 2\n")
put("off", "quad_and_comments.off", "# a comment\nOFF\n4 1 0\n0 0 0 # corner\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
put("off", "glued_modelnet.off", "OFF4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")
put("off", "wrapped.off", "OFF\n4 2 0\n0 0\n0\n1 0 0\n1 1\n0\n0 1 0\n3 0 1\n2\n3 0 2 3\n")
put("off", "cr_only.off", off(TETRA_V, TETRA_F).replace("\n", "\r"))
put("off", "crlf_bom.off", b"\xef\xbb\xbf" + off(TETRA_V, TETRA_F).replace("\n", "\r\n").encode())
put("off", "point_cloud.off", "OFF\n3 0 0\n0 0 0\n1 2 3\n-1e-30 4e30 5\n")
put("off", "duplicate_and_degenerate.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 2 0 1\n3 0 0 1\n3 0 2 3\n")
put("off", "third_face_on_edge.off", "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n")
put("off", "huge_counts.off", "OFF\n2000000000 1000000000 0\n0 0 0\n")
put("off", "huge_corner_count.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n")
put("off", "far_and_tiny.off", off([(1e20, 1e20, 1e20), (1e20 + 1e5, 1e20, 1e20), (1e20, 1e20 + 1e5, 1e20)], [(0, 1, 2)]))
put("off", "index_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
put("off", "nan.off", "OFF\n3 1 0\nnan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")

# OBJ
obj = "# tetra\no tetra\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in TETRA_V)
obj += "vt 0 0\nvn 0 0 1\ng g0\ns off\nusemtl m\n"
obj += "".join(f"f {a + 1}/1/1 {b + 1}//1 {c + 1}\n" for a, b, c in TETRA_F)
put("obj", "tetra.obj", obj)
put("obj", "negative_quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n")
put("obj", "bom_crlf.obj", b"\xef\xbb\xbfv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n")
put("obj", "points.obj", "v 0 0 0 1\nv 1 2 3\nl 1 2\n")
put("obj", "out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
put("obj", "binary_tail.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\x00\x01\xff\xfe")

# PLY, ASCII
def ply_header(fmt, nv, nf, vertex_props="property float x\nproperty float y\nproperty float z\n",
               face_prop="property list uchar int vertex_indices\n"):
    return (f"ply\nformat {fmt} 1.0\ncomment seed\nelement vertex {nv}\n{vertex_props}"
            f"element face {nf}\n{face_prop}end_header\n")

ply = ply_header("ascii", 4, 4) + "".join(f"{x} {y} {z}\n" for x, y, z in TETRA_V)
ply += "".join(f"3 {a} {b} {c}\n" for a, b, c in TETRA_F)
put("ply_ascii", "tetra.ply", ply)
props = ("property double x\nproperty double y\nproperty double z\nproperty float nx\nproperty float ny\n"
         "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n")
ply = ply_header("ascii", 4, 1, props, "property list uint8 uint32 vertex_index\n")
ply += "".join(f"{x} {y} {z} 0 0 1 255 0 0\n" for x, y, z in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
put("ply_ascii", "quad_with_normals_colors.ply", ply + "4 0 1 2 3\n")
put("ply_ascii", "no_properties_huge.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\nend_header\n")
put("ply_ascii", "junk_element.ply", "ply\nformat ascii 1.0\nelement junk 9000000000000000000\nend_header\n")
put("ply_ascii", "count_trailing_junk.ply", "ply\nformat ascii 1.0\nelement vertex 3x\nproperty float x\nend_header\n")
put("ply_ascii", "huge_list_count.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n1.6e35 0 1 2\n")
put("ply_ascii", "nan_list_count.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\nnan 0 1 2\n")
put("ply_ascii", "obj_info_and_other_element.ply",
    "ply\nformat ascii 1.0\nobj_info made by hand\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nelement face 1\n"
    "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 1\n3 0 1 2\n")

# PLY, binary
def ply_binary(endian, vfmt, vtype, ctype, itype):
    e = "<" if endian == "little" else ">"
    props = "".join(f"property {vtype} {c}\n" for c in "xyz")
    head = ply_header(f"binary_{endian}_endian", 4, 4, props, f"property list {ctype} {itype} vertex_indices\n")
    body = b"".join(struct.pack(e + vfmt * 3, *v) for v in TETRA_V)
    cfmt = {"uchar": "B", "uint8": "B", "int": "i", "ushort": "H"}[ctype]
    ifmt = {"int": "i", "uint": "I", "uint32": "I", "int32": "i", "ushort": "H"}[itype]
    body += b"".join(struct.pack(e + cfmt + ifmt * 3, 3, *f) for f in TETRA_F)
    return head.encode() + body

put("ply_binary", "tetra_le_float.ply", ply_binary("little", "f", "float", "uchar", "int"))
put("ply_binary", "tetra_be_double.ply", ply_binary("big", "d", "double", "uint8", "uint32"))
put("ply_binary", "tetra_le_ushort.ply", ply_binary("little", "f", "float32", "int", "ushort"))
put("ply_binary", "truncated.ply", ply_binary("little", "f", "float", "uchar", "int")[:-7])

# STL
stl = "solid tetra\n"
for f in TETRA_F:
    stl += " facet normal 0 0 0\n  outer loop\n" + "".join(
        "   vertex {} {} {}\n".format(*TETRA_V[i]) for i in f) + "  endloop\n endfacet\n"
put("stl", "tetra_ascii.stl", stl + "endsolid tetra\n")

def stl_binary(header):
    body = struct.pack("<I", len(TETRA_F))
    for f in TETRA_F:
        body += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *TETRA_V[i]) for i in f) + b"\0\0"
    return header.ljust(80, b"\0") + body

put("stl", "tetra_binary.stl", stl_binary(b"binary seed"))
put("stl", "binary_says_solid.stl", stl_binary(b"solid but binary"))
put("stl", "empty_solid.stl", "solid empty\nendsolid empty\n")
put("stl", "huge_count.stl", b"x".ljust(80, b"\0") + struct.pack("<I", 0xFFFFFFFF))

# .sel: first byte = #V
put("sel", "handles.sel", b"\x08" + b"# 8 vertices\n0\n0\n1\n1\n2\n2\n3\n3\n")
put("sel", "cr_bom.sel", b"\x04\xef\xbb\xbf0\r1\r2\r1\r")
put("sel", "huge_label.sel", b"\x02" + b"0\n2147483647\n")
# A skipped handle code (0 1 3): read, but write_sel refuses it as validate() does (stop 60's fuzzer found it).
put("sel", "skipped_code.sel", b"\x03" + b"0\n1\n3\n")
put("dmat", "skipped_group.dmat", b"\x03" + b"1 3\n0\n-1\n2\n")
put("sel", "wrong_count.sel", b"\x05" + b"0 1 2\n")
put("sel", "empty.sel", b"\x00")

# .dmat: first byte = #V
put("dmat", "groups.dmat", b"\x06" + b"1 6\n-1\n-1\n0\n0\n1\n1\n")
put("dmat", "wrap_2_32.dmat", b"\x02" + b"1 2\n4294967296\n4294967295\n")
put("dmat", "bad_header.dmat", b"\x03" + b"3 1\n0 0 0\n")

# .def
identity = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
put("def", "identity.def", "# handle 0\n" + identity)
put("def", "two_handles_cr.def", ("# 0\n" + identity + "# 1\n0 -1 0 2.5\n1 0 0 0\n0 0 1 1e-3\n0 0 0 1\n").replace("\n", "\r"))
put("def", "not_affine.def", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n")
put("def", "nan.def", "nan 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n")
put("def", "fifteen.def", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\n")
print("seeds written under", root, file=sys.stderr)
