#!/usr/bin/env python3
"""add_vertex_colors.py IN.glb OUT.glb - a copy of a GLB whose every primitive gains COLOR_0:
normalized UNSIGNED_BYTE RGB (byteStride 4), a pattern of colours by vertex index. For the tests of
`crowdbake mesh`, which carries vertex colours (no model of the shared set has any)."""
import json
import struct
import sys


def read_glb(path):
    data = open(path, 'rb').read()
    json_len = struct.unpack_from('<I', data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    at = 20 + json_len
    bin_len = struct.unpack_from('<I', data, at)[0]
    return doc, bytearray(data[at + 8:at + 8 + bin_len])


def write_glb(path, doc, blob):
    text = json.dumps(doc, separators=(',', ':')).encode()
    text += b' ' * (-len(text) % 4)
    blob += b'\0' * (-len(blob) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    with open(path, 'wb') as f:
        f.write(struct.pack('<III', 0x46546C67, 2, total))
        f.write(struct.pack('<II', len(text), 0x4E4F534A) + text)
        f.write(struct.pack('<II', len(blob), 0x004E4942) + bytes(blob))


def main(src, dst):
    doc, blob = read_glb(src)
    for mesh in doc['meshes']:
        for prim in mesh['primitives']:
            count = doc['accessors'][prim['attributes']['POSITION']]['count']
            blob += b'\0' * (-len(blob) % 4)
            offset = len(blob)
            for v in range(count):
                blob += bytes(((v * 37) % 256, (v * 91 + 80) % 256, (v * 53 + 160) % 256, 0))
            doc['bufferViews'].append({'buffer': 0, 'byteOffset': offset, 'byteLength': count * 4, 'byteStride': 4,
                                       'target': 34962})
            doc['accessors'].append({'bufferView': len(doc['bufferViews']) - 1, 'componentType': 5121, 'normalized': True,
                                     'count': count, 'type': 'VEC3'})
            prim['attributes']['COLOR_0'] = len(doc['accessors']) - 1
    doc['buffers'][0]['byteLength'] = len(blob) + (-len(blob) % 4)
    write_glb(dst, doc, blob)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
