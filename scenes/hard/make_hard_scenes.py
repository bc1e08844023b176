#!/usr/bin/env python3
"""Writes the hard-case scenes used by bench/accuracy.py next to this file.

- lens-moved-1e5.json: the study's lens scene translated by (1e5, -1e5, 1e5).
- insane-shrunk-1e-3.json: insane scaled by 1e-3 about the origin.
- inside-sphere.json + icosphere.obj: the camera inside a closed, 20480-triangle
  geodesic sphere with a mirror wall and a glass ball; the background is a
  colour that appears nowhere else, so any leak shows.
Run: python3 scenes/hard/make_hard_scenes.py
"""
import json
import math
import os

here = os.path.dirname(os.path.abspath(__file__))
scenes = os.path.dirname(here)


def transform(scene, scale, offset):
    tf = lambda p: [p[i] * scale + offset[i] for i in range(3)]
    s = json.loads(json.dumps(scene))
    s["camera"]["position"] = tf(s["camera"]["position"])
    s["camera"]["look_at"] = tf(s["camera"]["look_at"])
    for light in s.get("lights", []):
        light["position"] = tf(light["position"])
    for sphere in s.get("spheres", []):
        sphere["center"] = tf(sphere["center"])
        sphere["radius"] *= scale
    for tri in s.get("triangles", []):
        tri["v"] = [tf(v) for v in tri["v"]]
    return s


def write(name, scene):
    with open(os.path.join(here, name), "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    norm = lambda p: tuple(c / math.sqrt(sum(x * x for x in p)) for c in p)
    v = [norm(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7),
         (9, 8, 1)]
    for _ in range(levels):
        mid = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                v.append(norm(tuple((v[a][i] + v[b][i]) / 2 for i in range(3))))
                mid[key] = len(v) - 1
            return mid[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f


def main():
    with open(os.path.join(scenes, "lens.json")) as f:
        lens = json.load(f)
    with open(os.path.join(scenes, "insane.json")) as f:
        insane = json.load(f)
    moved = transform(lens, 1.0, (1e5, -1e5, 1e5))
    moved["name"] = "lens-moved-1e5"
    write("lens-moved-1e5.json", moved)
    shrunk = transform(insane, 1e-3, (0.0, 0.0, 0.0))
    shrunk["name"] = "insane-shrunk-1e-3"
    write("insane-shrunk-1e-3.json", shrunk)

    v, f = icosphere(5)
    with open(os.path.join(here, "icosphere.obj"), "w") as out:
        out.write("# geodesic sphere, 5 subdivisions of an icosahedron, %d triangles (make_hard_scenes.py)\n" % len(f))
        for p in v:
            out.write("v %.9f %.9f %.9f\n" % p)
        for a, b, c in f:
            out.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))
    inside = {
        "format": "kdrt-scene/1",
        "name": "inside-sphere",
        "camera": {"position": [0.31, -0.17, 0.23], "look_at": [2.0, 0.6, 1.1], "up": [0, 1, 0], "fov_y": 100},
        "settings": {"width": 500, "height": 500, "max_depth": 6, "samples": 1,
                     "background": [1, 0, 1], "ambient": [0.05, 0.1, 0.1]},
        "materials": {
            "wall": {"color": [0.2, 0.6, 0.8], "diffuse": 0.6, "specular": 0.3, "shininess": 40, "reflect": 0.6},
            "glass": {"color": [1, 1, 1], "diffuse": 0.05, "specular": 0.8, "shininess": 100,
                      "transmit": 0.9, "ior": 1.5},
        },
        "lights": [{"position": [-0.5, 1.2, -0.4], "color": [1, 1, 1]}],
        "spheres": [{"center": [1.1, 0.3, 0.6], "radius": 0.5, "material": "glass"}],
        "meshes": [{"obj": "icosphere.obj", "material": "wall",
                    "transform": [3, 0, 0, 0.013, 0, 3, 0, -0.021, 0, 0, 3, 0.007, 0, 0, 0, 1]}],
    }
    write("inside-sphere.json", inside)


if __name__ == "__main__":
    main()
