#!/usr/bin/env python3
"""Writes a heavy animated glTF for timing the sample's GPU skinning and BLAS refits: an
N x N sheet (default 317: about 100,000 vertices and 200,000 triangles) 4 units wide, skinned
to two joints (its +X half bends about Z by up to 45 degrees and back every two seconds, the
weights blending across a band in the middle) and rippled by one morph target whose weight
is animated too, above a floor.

    python3 scripts/skinned_grid.py out_dir [N]
    sample --headless out_dir/skinned_grid.gltf --width 1920 --height 1080 --frames 64 --time-passes

Writes skinned_grid.gltf and skinned_grid.bin. Standard library only.
"""
import json
import math
import struct
import sys
from pathlib import Path


def main():
    out = Path(sys.argv[1])
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 317
    out.mkdir(parents=True, exist_ok=True)
    positions, joints, weights, ripple = [], [], [], []
    for j in range(n):
        for i in range(n):
            x, z = -2.0 + 4.0 * i / (n - 1), -2.0 + 4.0 * j / (n - 1)
            positions += [x, 0.0, z]
            t = min(max((x + 0.5) / 1.0, 0.0), 1.0)
            w = t * t * (3.0 - 2.0 * t)
            joints += [0, 1, 0, 0]
            weights += [1.0 - w, w, 0.0, 0.0]
            ripple += [0.0, 0.15 * math.sin(3.0 * x) * math.cos(3.0 * z), 0.0]
    indices = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            indices += [a, a + n, a + 1, a + 1, a + n, a + n + 1]
    floor = [-3.0, -1.0, -3.0, 3.0, -1.0, -3.0, -3.0, -1.0, 3.0, 3.0, -1.0, 3.0]
    floor_indices = [0, 2, 1, 1, 2, 3]
    times = [0.0, 1.0, 2.0]
    h = math.sin(math.pi / 8.0)
    rotations = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, h, math.cos(math.pi / 8.0), 0.0, 0.0, 0.0, 1.0]
    ripple_weights = [0.0, 1.0, 0.0]
    inverse_bind = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0] * 2

    blob = bytearray()
    views = []

    def push(fmt, values):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": 4 * len(values)})
        blob.extend(struct.pack(f"<{len(values)}{fmt}", *values))
        return len(views) - 1

    v_pos = push("f", positions)
    v_joints = push("H", joints + [0] * (len(joints) % 2))
    views[v_joints]["byteLength"] = 2 * len(joints)
    v_weights = push("f", weights)
    v_ripple = push("f", ripple)
    v_idx = push("I", indices)
    v_floor = push("f", floor)
    v_floor_idx = push("I", floor_indices)
    v_ibm = push("f", inverse_bind)
    v_times = push("f", times)
    v_rot = push("f", rotations)
    v_rw = push("f", ripple_weights)
    count = n * n
    accessors = [
        {"bufferView": v_pos, "componentType": 5126, "count": count, "type": "VEC3",
         "min": [-2, 0, -2], "max": [2, 0, 2]},
        {"bufferView": v_joints, "componentType": 5123, "count": count, "type": "VEC4"},
        {"bufferView": v_weights, "componentType": 5126, "count": count, "type": "VEC4"},
        {"bufferView": v_ripple, "componentType": 5126, "count": count, "type": "VEC3",
         "min": [0, -0.15, 0], "max": [0, 0.15, 0]},
        {"bufferView": v_idx, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        {"bufferView": v_floor, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [-3, -1, -3], "max": [3, -1, 3]},
        {"bufferView": v_floor_idx, "componentType": 5125, "count": 6, "type": "SCALAR"},
        {"bufferView": v_ibm, "componentType": 5126, "count": 2, "type": "MAT4"},
        {"bufferView": v_times, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [2]},
        {"bufferView": v_rot, "componentType": 5126, "count": 3, "type": "VEC4"},
        {"bufferView": v_rw, "componentType": 5126, "count": 3, "type": "SCALAR"},
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "hybrid-rt scripts/skinned_grid.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 3]}],
        "nodes": [{"mesh": 0, "skin": 0}, {"children": [2]}, {}, {"mesh": 1}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": 7}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2},
                             "targets": [{"POSITION": 3}], "indices": 4, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 5}, "indices": 6, "material": 1}]},
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1], "metallicFactor": 0,
                                      "roughnessFactor": 0.5}, "doubleSided": True},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}},
        ],
        "animations": [{
            "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}},
                         {"sampler": 1, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": 8, "output": 9, "interpolation": "LINEAR"},
                         {"input": 8, "output": 10, "interpolation": "LINEAR"}],
        }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "skinned_grid.bin"}],
    }
    (out / "skinned_grid.bin").write_bytes(bytes(blob))
    (out / "skinned_grid.gltf").write_text(json.dumps(doc))
    print(f"{out / 'skinned_grid.gltf'}: {count} vertices, {len(indices) // 3} triangles")


if __name__ == "__main__":
    main()
