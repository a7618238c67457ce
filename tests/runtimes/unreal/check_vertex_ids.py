#!/usr/bin/env python3
"""check_vertex_ids.py MESH.glb SET SKIN.txt - reads a `crowdbake mesh --vertex-id-uv SET` .glb with
Python's own parsing (struct, json) and checks: every primitive has TEXCOORD_0..SET, TEXCOORD_SET
holds (vertex id, 0) running 0, 1, ... over the primitives in order, and the skin texture's lines
(reader_check skin: id, four joints, four weights) equal each vertex's JOINTS_0 and WEIGHTS_0 (weights
dequantized as glTF defines normalized integers). Prints one summary line; exits 1 on a difference."""
import json
import struct
import sys

SIZES = {5120: ("b", 1), 5121: ("B", 1), 5122: ("h", 2), 5123: ("H", 2), 5125: ("I", 4), 5126: ("f", 4)}
COUNTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
NORM = {5121: 255.0, 5123: 65535.0}


def read_accessor(doc, binary, index):
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    fmt, size = SIZES[acc["componentType"]]
    n = COUNTS[acc["type"]]
    stride = view.get("byteStride", size * n)
    base = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    out = []
    for i in range(acc["count"]):
        vals = struct.unpack_from("<" + fmt * n, binary, base + i * stride)
        if acc.get("normalized"):
            vals = tuple(v / NORM[acc["componentType"]] for v in vals)
        out.append(vals)
    return out


def main(glb, uv_set, skin_lines):
    data = open(glb, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + length])
    binary = data[20 + length + 8:]
    skin = [line.split() for line in open(skin_lines)]
    vid = 0
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            attrs = prim["attributes"]
            for k in range(uv_set + 1):
                if "TEXCOORD_%d" % k not in attrs:
                    sys.exit("TEXCOORD_%d missing" % k)
            ids = read_accessor(doc, binary, attrs["TEXCOORD_%d" % uv_set])
            joints = read_accessor(doc, binary, attrs["JOINTS_0"])
            weights = read_accessor(doc, binary, attrs["WEIGHTS_0"])
            for i, (u, v) in enumerate(ids):
                if u != vid + i or v != 0:
                    sys.exit("vertex %d: TEXCOORD_%d is (%r, %r)" % (vid + i, uv_set, u, v))
                line = skin[vid + i]
                if [float(x) for x in line[1:5]] != [float(j) for j in joints[i]]:
                    sys.exit("vertex %d: skin joints %s, the mesh's %s" % (vid + i, line[1:5], joints[i]))
                if any(abs(float(a) - b) > 1e-6 for a, b in zip(line[5:9], weights[i])):
                    sys.exit("vertex %d: skin weights %s, the mesh's %s" % (vid + i, line[5:9], weights[i]))
            vid += len(ids)
    if vid != len(skin):
        sys.exit("the skin texture has %d vertices, the mesh %d" % (len(skin), vid))
    print("%s: %d vertex ids in TEXCOORD_%d, joints and weights equal the skin texture" % (glb, vid, uv_set))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
