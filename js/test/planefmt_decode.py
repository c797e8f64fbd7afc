"""Prints planefmt's decoding of a .pln file for the JavaScript tests: one line of JSON with the
counts, then the world-frame vertices as little-endian float64 (3 per vertex) and the triangles
as little-endian uint32 (3 per triangle). Usage: python planefmt_decode.py FILE.pln"""

import json
import sys

import numpy as np

import planefmt


def main() -> None:
    mesh = planefmt.decode_mesh(sys.argv[1])
    vertices = np.ascontiguousarray(mesh.vertices, dtype="<f8")
    faces = np.ascontiguousarray(mesh.faces, dtype="<u4")
    out = sys.stdout.buffer
    out.write(json.dumps({"vertices": len(vertices), "triangles": len(faces)}).encode() + b"\n")
    out.write(vertices.tobytes())
    out.write(faces.tobytes())


if __name__ == "__main__":
    main()
