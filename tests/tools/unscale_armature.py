#!/usr/bin/env python3
"""unscale_armature.py IN.glb OUT.glb - a test variant of a model whose armature carries a scale
(Quaternius' exports: AnimalArmature and the skinned mesh node at scale 100): every node's scale set
to 1, so the joints and their sockets have unit-length axes. The inverse bind matrices are kept, so
the skinned mesh stays a valid (larger) model: the sockets of a model without a scaled node."""
import json
import struct
import sys


def main(src, dst):
    data = open(src, 'rb').read()
    length = struct.unpack_from('<I', data, 12)[0]
    doc = json.loads(data[20:20 + length])
    for node in doc.get('nodes', []):
        if 'scale' in node:
            node['scale'] = [1.0, 1.0, 1.0]
    text = json.dumps(doc, separators=(',', ':')).encode()
    text += b' ' * (-len(text) % 4)
    rest = data[20 + length:]
    body = struct.pack('<II', len(text), 0x4E4F534A) + text + rest
    open(dst, 'wb').write(struct.pack('<III', 0x46546C67, 2, 12 + len(body)) + body)


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit('usage: unscale_armature.py IN.glb OUT.glb')
    main(sys.argv[1], sys.argv[2])
