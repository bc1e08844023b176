#!/usr/bin/env python3
# Usage: make_scene_wire_seeds.py tests/fuzz/corpus/scene_wire
# Writes seed scenes in the scene wire format (libkdrt/src/scene/scene_wire.cpp, version 1).
import struct, sys
def u8(v): return struct.pack('<B', v)
def u32(v): return struct.pack('<I', v)
def i32(v): return struct.pack('<i', v)
def u64(v): return struct.pack('<Q', v)
def f64(v): return struct.pack('<d', v)
def vec3(a): return b''.join(f64(x) for x in a)
def string(s): b = s.encode(); return u64(len(b)) + b
def mesh(pos, nrm, tris):
    out = u64(len(pos)) + b''.join(vec3(p) for p in pos) + u64(len(nrm)) + b''.join(vec3(n) for n in nrm)
    out += u64(len(tris))
    for v, n, m in tris: out += b''.join(u32(x) for x in v) + b''.join(u32(x) for x in n) + u32(m)
    return out
def scene(name, spheres, loose, meshes, added):
    p = string(name) + vec3((0, 0, -5)) + vec3((0, 0, 0)) + vec3((0, 1, 0)) + f64(40)
    p += i32(32) + i32(24) + i32(5) + i32(1) + vec3((0.1, 0.1, 0.2)) + vec3((0.05, 0.05, 0.05))
    mats = [("red", (1, 0, 0), 0.8, 0.2, 20, 0.0, 0.0, 1.0), ("glass", (1, 1, 1), 0.1, 0.5, 50, 0.1, 0.9, 1.5)]
    p += u64(len(mats))
    for n, c, *v in mats: p += string(n) + vec3(c) + b''.join(f64(x) for x in v)
    p += u64(1) + vec3((5, 5, -5)) + vec3((1, 1, 1))
    p += u64(len(spheres)) + b''.join(vec3(c) + f64(r) + u32(m) for c, r, m in spheres)
    p += mesh(*loose) + u64(len(meshes)) + b''.join(mesh(*m) for m in meshes)
    p += u64(len(added)) + b''.join(u8(k) + u32(f) + u32(c) for k, f, c in added)
    head = b'KDRTSCNE' + u32(1) + u64(len(p))
    return head + u64(0) + p  # checksum 0: the fuzz target recomputes it
NO = 0xFFFFFFFF
tri = ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [((0, 1, 2), (NO, NO, NO), 0)])
quad = ([(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], [(0, 0, -1), (0, 0.1, -1)],
        [((0, 1, 2), (0, 1, 0), 1), ((0, 2, 3), (NO, NO, NO), 0)])
open(sys.argv[1] + '/spheres.scene', 'wb').write(scene('spheres', [((0, 0, 0), 1, 0), ((2, 0, 1), 0.5, 1)], ([], [], []), [], [(0, 0, 2)]))
open(sys.argv[1] + '/meshes.scene', 'wb').write(scene('meshes', [((0, 0, 0), 1, 1)], tri, [quad], [(1, 0, 1), (0, 0, 1), (2, 0, 2)]))
