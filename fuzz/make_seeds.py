#!/usr/bin/env python3
"""Writes the small seed inputs of the reader fuzz targets into seeds/<target>/.

Each seed is one byte choosing the file name (see the NAMES arrays of the targets) followed by
the file's bytes. Sources are tiny hand-made files and cut-down fixtures from
../fixtures/formats (see LICENSES.md there). The weights seeds were written by
`Weights::random(&ModelConfig::tiny(), 1).to_bytes(..)` (tiny_i8: `arps quantize tiny_f32.safetensors
tiny_i8.safetensors --bits 8`).
"""
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
FIX = os.path.join(HERE, "..", "fixtures", "formats")
sys.path.insert(0, FIX)
from derive import lzf_compress  # noqa: E402

PC_NAMES = ["a.ply", "a.pcd", "a.xyz", "a.pts", "a.csv", "a.obj", "a.off", "a.stl", "a.txt", "no_extension", "a.las", "a.laz", "a.e57"]
MESH_NAMES = ["a.ply", "a.obj", "a.off", "a.stl", "no_extension"]

TET = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.5)]
FACES = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]


def ply(enc):
    head = (
        f"ply\nformat {enc} 1.0\ncomment seed\nelement vertex 4\nproperty double x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty list uchar float extra\n"
        "element face 4\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n"
    ).encode()
    if enc == "ascii":
        body = "".join(f"{x} {y} {z} 200 2 0.5 0.25\n" for x, y, z in TET)
        body += "".join(f"3 {a} {b} {c} 1.0\n" for a, b, c in FACES)
        return head + body.encode()
    e = "<" if enc == "binary_little_endian" else ">"
    body = b"".join(struct.pack(f"{e}dffBBff", x, y, z, 200, 2, 0.5, 0.25) for x, y, z in TET)
    body += b"".join(struct.pack(f"{e}B3if", 3, a, b, c, 1.0) for a, b, c in FACES)
    return head + body


def pcd(data):
    head = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 8 4\n"
        "TYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\n"
        f"DATA {data}\n"
    ).encode()
    if data == "ascii":
        return head + "".join(f"{x} {y} {z} 4278190080\n" for x, y, z in TET[:3]).encode() + b"nan nan nan 0\n"
    pts = TET[:3] + [(float("nan"),) * 3]
    if data == "binary":
        return head + b"".join(struct.pack("<ffdI", x, y, z, 7) for x, y, z in pts)
    raw = b"".join(struct.pack("<f", p[0]) for p in pts) + b"".join(struct.pack("<f", p[1]) for p in pts)
    raw += b"".join(struct.pack("<d", p[2]) for p in pts) + struct.pack("<4I", 7, 7, 7, 7)
    packed = lzf_compress(raw)
    return head + struct.pack("<II", len(packed), len(raw)) + packed


def obj():
    s = "# tet\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1.5\nvt 0 0\nvn 0 0 1\n"
    return (s + "f 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf -3 -2 -1\nf 1 4 3\n").encode()


def off():
    s = "COFF\n# tet\n4 4 6\n" + "".join(f"{x} {y} {z} 255 0 0 255\n" for x, y, z in TET)
    return (s + "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES)).encode()


def stl_ascii():
    s = "solid tet\n"
    for f in FACES:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join("   vertex {} {} {}\n".format(*TET[i]) for i in f)
        s += "  endloop\n endfacet\n"
    return (s + "endsolid tet\n").encode()


def stl_binary():
    b = b"solid but binary".ljust(80, b" ") + struct.pack("<I", len(FACES))
    for f in FACES:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *TET[i]) for i in f) + b"\0\0"
    return b


def text(sep, header):
    return (header + "".join(sep.join(str(v) for v in p) + sep + "1\n" for p in TET)).encode()


def fixture_head(name, lines):
    with open(os.path.join(FIX, name), "rb") as f:
        return b"".join(f.readlines()[:lines])


def fixture_whole(name):
    with open(os.path.join(FIX, name), "rb") as f:
        return f.read()


def las_head(name, n):
    """The LAS file's header and records up to the point data, then its first n points."""
    b = bytearray(fixture_whole(name))
    offset = struct.unpack_from("<I", b, 96)[0]
    record = struct.unpack_from("<H", b, 105)[0]
    struct.pack_into("<I", b, 107, n)
    if b[25] >= 4:
        struct.pack_into("<Q", b, 247, n)
    return bytes(b[: offset + n * record])


def main():
    files = {
        "ply_ascii": ("a.ply", ply("ascii")),
        "ply_le": ("a.ply", ply("binary_little_endian")),
        "ply_be": ("a.ply", ply("binary_big_endian")),
        "pcd_ascii": ("a.pcd", pcd("ascii")),
        "pcd_binary": ("a.pcd", pcd("binary")),
        "pcd_compressed": ("a.pcd", pcd("binary_compressed")),
        "obj": ("a.obj", obj()),
        "off": ("a.off", off()),
        "stl_ascii": ("a.stl", stl_ascii()),
        "stl_binary": ("a.stl", stl_binary()),
        "xyz": ("a.xyz", text(" ", "")),
        "pts": ("a.pts", text(" ", "4\n")),
        "csv": ("a.csv", text(",", "x,y,z,i\n")),
        "csv_eth": ("a.csv", fixture_head("eth_car_1000.csv", 12)),
        "txt": ("a.txt", text(";", "# comment\n")),
        "las": ("a.las", las_head("simple.las", 20)),
        "las_1_4": ("a.las", las_head("1_4_w_evlr.las", 20)),
        "laz": ("a.laz", fixture_whole("simple.laz")),
        "laz_layered": ("a.laz", fixture_whole("1_4_w_evlr.laz")),
        "e57_spherical": ("a.e57", fixture_whole("tiny_spherical.e57")),
        "e57_two_scans": ("a.e57", fixture_whole("velodyne_two_scans.e57")),
    }
    for target, names in (("read_point_cloud", PC_NAMES), ("read_mesh", MESH_NAMES)):
        out = os.path.join(HERE, "seeds", target)
        os.makedirs(out, exist_ok=True)
        for key, (name, data) in files.items():
            if name not in names:
                continue
            with open(os.path.join(out, key), "wb") as f:
                f.write(bytes([names.index(name)]) + data)
            # The same bytes with no extension, to exercise sniffing.
            with open(os.path.join(out, key + "_sniffed"), "wb") as f:
                f.write(bytes([names.index("no_extension")]) + data)


def clouds():
    """Seeds of register_clouds: a header of six bytes (see the target's docs), then points."""
    import math

    def i8(v):
        return max(-128, min(127, int(round(v)))) & 0xFF

    def body(points):
        return bytes(i8(c) for p in points for c in p)

    def surface(n):
        """`n` points of a bumpy closed surface, from a low-discrepancy sequence."""
        points = []
        for i in range(n):
            u, v = (i * 0.754877) % 1.0 * 2 * math.pi, math.acos(2 * ((i * 0.569840) % 1.0) - 1)
            r = 90 + 12 * math.sin(3 * u) * math.cos(2 * v)
            points.append((r * math.sin(v) * math.cos(u) * 1.2, r * math.sin(v) * math.sin(u) * 0.8, r * math.cos(v)))
        return points

    bumpy, dense = surface(300), surface(2600)
    plane = [(x * 9, y * 9, 0) for x in range(-8, 9) for y in range(-8, 9)]
    line = [(i, 2 * i, -i) for i in range(-40, 40)]
    box = [(x, y, z) for x in (-60, 60) for y in range(-60, 61, 12) for z in range(-30, 31, 10)]
    seeds = {
        # a turned part of a bumpy surface onto it, adaptive and exhaustive, with determinism
        "bumpy_turned": bytes([0b1010_0000, 0, 0, 0, 255, 0x4B]) + body(bumpy),
        "bumpy_turned_far_up": bytes([0b1110_0001, 0, 0, 0, 255, 0xA7]) + body(bumpy),
        "bumpy_exhaustive": bytes([0b1011_0000, 0, 0, 0, 255, 0x2F]) + body(bumpy),
        # two different clouds, scaled apart
        "bumpy_vs_box": bytes([0, 0, 30, 226, 150, 0]) + body(bumpy[:150] + box),
        # many copies per point: a cloud of thousands of points (the large-cloud paths)
        "bumpy_copies": bytes([0b1010_0000, 0x4F, 0, 0, 255, 0x39]) + body(bumpy),
        # a dense surface, 16 spread copies of each point: ICP's target has coarser copies
        "bumpy_dense": bytes([0b1010_0000, 0xFF, 0, 0, 255, 0x4B]) + body(dense),
        # degenerate: a plane, a line, duplicates
        "plane": bytes([0b0010_0000, 0, 0, 0, 255, 0x33]) + body(plane),
        "line": bytes([0b0010_0000, 0x03, 0, 0, 255, 0x21]) + body(line),
        "duplicates": bytes([0, 0x0F, 0, 0, 128, 0]) + body(bumpy[:20] + bumpy[:20]),
        "plane_and_box": bytes([0b0000_0110, 0, 0, 0, 140, 0]) + body(plane + box),
    }
    out = os.path.join(HERE, "seeds", "register_clouds")
    os.makedirs(out, exist_ok=True)
    for key, data in seeds.items():
        with open(os.path.join(out, key), "wb") as f:
            f.write(data)


def glb(json_obj, bin_bytes):
    """A GLB file of a JSON object and a binary chunk (both padded to 4 bytes)."""
    import json

    text = json.dumps(json_obj, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    bin_bytes += b"\0" * (-len(bin_bytes) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(bin_bytes), b"BIN\0") + bin_bytes
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def gltf_seeds():
    """Seeds of read_gltf: the tetrahedron as GLB (floats under a parent and a TRS child; int16
    normalised positions, a strip, a sparse accessor, GPU instances) and as .gltf with an embedded
    buffer; the Draco fixture whole (refused)."""
    import base64

    floats = b"".join(struct.pack("<3f", *p) for p in TET)
    shorts = b"".join(struct.pack("<3h", *(round(c / 1.5 * 32767) for c in p)) + b"\0\0" for p in TET)
    idx = b"".join(struct.pack("<3H", *f) for f in FACES)
    strip = struct.pack("<6H", 0, 1, 2, 3, 0, 1)
    sparse = struct.pack("<H", 2) + b"\0\0" + struct.pack("<3f", 0.0, 2.0, 0.0)
    inst = b"".join(struct.pack("<3f", x, 0, 0) for x in (0, 3, 6))

    def doc(position, indices, mode=4, node=None, views=()):
        views = [
            {"buffer": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32, "byteStride": 8},
            {"buffer": 0, "byteOffset": 80, "byteLength": 24},
            {"buffer": 0, "byteOffset": 104, "byteLength": 12},
            {"buffer": 0, "byteOffset": 116, "byteLength": 16},
            {"buffer": 0, "byteOffset": 132, "byteLength": 36},
        ]
        accessors = [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5122, "normalized": True, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 12, "type": "SCALAR"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "sparse": {"count": 1, "indices": {"bufferView": 4, "componentType": 5123}, "values": {"bufferView": 4, "byteOffset": 4}}},
            {"bufferView": 5, "componentType": 5126, "count": 3, "type": "VEC3"},
        ]
        prim = {"attributes": {"POSITION": position}, "mode": mode}
        if indices is not None:
            prim["indices"] = indices
        child = node or {"mesh": 0, "rotation": [0, 0.3826834, 0, 0.9238795], "scale": [1, 1.5, 1]}
        return {
            "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"translation": [1, 2, 3], "children": [1]}, child],
            "meshes": [{"primitives": [prim]}], "accessors": accessors, "bufferViews": views,
            "buffers": [{"byteLength": 168}],
        }

    data = floats + shorts + idx + strip + sparse + inst
    assert len(data) == 168, len(data)
    seeds = {
        "floats": glb(doc(0, 2), data),
        "int16_normalised": glb(doc(1, 2), data),
        "strip": glb(doc(0, 3, mode=5), data),
        "sparse": glb(doc(4, 2), data),
        "instanced": glb(doc(0, 2, node={"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 5}}}}), data),
        "draco": fixture_whole("fuze_draco.glb"),
    }
    embedded = doc(0, 2)
    embedded["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    import json

    seeds["embedded_gltf"] = json.dumps(embedded, indent=1).encode()
    out = os.path.join(HERE, "seeds", "read_gltf")
    os.makedirs(out, exist_ok=True)
    for key, data in seeds.items():
        with open(os.path.join(out, key), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
    clouds()
    gltf_seeds()
