#!/usr/bin/env python3
"""Writes scene.gltf + scene.bin, the glTF 2.0 test model of test_model_import.cpp:
a ground quad and two cubes (glass with KHR_materials_transmission and
KHR_materials_ior, smooth metal) under translated nodes, a perspective camera
and two KHR_lights_punctual lights (point, directional). Run it in this folder."""
import json, math, struct

quad = [(-5, 0, -5), (5, 0, -5), (5, 0, 5), (-5, 0, 5)]
cube = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
quad_idx = [0, 2, 1, 0, 3, 2]
# corners: index = 4*(x>0) + 2*(y>0) + (z>0)
cube_idx = [0, 1, 3, 0, 3, 2,  4, 6, 7, 4, 7, 5,  0, 4, 5, 0, 5, 1,
            2, 3, 7, 2, 7, 6,  0, 2, 6, 0, 6, 4,  1, 5, 7, 1, 7, 3]
pos = b"".join(struct.pack("<3f", *p) for p in quad + cube)
idx = struct.pack("<%dH" % len(quad_idx + cube_idx), *(quad_idx + cube_idx))
open("scene.bin", "wb").write(pos + idx)

def bounds(ps):
    return {"min": [min(p[i] for p in ps) for i in range(3)], "max": [max(p[i] for p in ps) for i in range(3)]}

s = math.sin(math.radians(-5)); c = math.cos(math.radians(-5))
h = math.sqrt(0.5)
gltf = {
    "asset": {"version": "2.0", "generator": "kdrt tests/data/models/make_scene_gltf.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "lamp", "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 2.0},
        {"name": "sun", "type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 0.5}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
    "nodes": [
        {"name": "ground", "mesh": 0},
        {"name": "glass_cube", "mesh": 1, "translation": [-1, 1.2, 0], "scale": [1.5, 1.5, 1.5]},
        {"name": "metal_cube", "mesh": 2, "translation": [2.5, 0.5, 0]},
        {"name": "eye", "camera": 0, "translation": [0, 2, 8], "rotation": [s, 0, 0, c]},
        {"name": "lights", "children": [5, 6]},
        {"name": "lamp_node", "translation": [3, 6, 4], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "sun_node", "rotation": [-h, 0, 0, h], "extensions": {"KHR_lights_punctual": {"light": 1}}},
    ],
    "cameras": [{"name": "eye", "type": "perspective",
                 "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}}],
    "meshes": [
        {"name": "ground", "primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "material": 0}]},
        {"name": "glass", "primitives": [{"attributes": {"POSITION": 1}, "indices": 3, "material": 1}]},
        {"name": "metal", "primitives": [{"attributes": {"POSITION": 1}, "indices": 3, "material": 2}]},
    ],
    "materials": [
        {"name": "grass", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.6, 0.3, 1], "metallicFactor": 0, "roughnessFactor": 0.5}},
        {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.33}}},
        {"name": "chrome", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 1, "roughnessFactor": 0.1}},
    ],
    "buffers": [{"uri": "scene.bin", "byteLength": len(pos) + len(idx)}],
    "bufferViews": [
        {"buffer": 0, "byteOffset": 0, "byteLength": len(pos), "target": 34962},
        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx), "target": 34963},
    ],
    "accessors": [
        dict({"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3"}, **bounds(quad)),
        dict({"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 8, "type": "VEC3"}, **bounds(cube)),
        {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 6, "type": "SCALAR"},
        {"bufferView": 1, "byteOffset": 12, "componentType": 5123, "count": 36, "type": "SCALAR"},
    ],
}
open("scene.gltf", "w").write(json.dumps(gltf, indent=1) + "\n")
