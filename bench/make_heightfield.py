#!/usr/bin/env python3
"""Writes a heightfield scene for the scale measurements: an OBJ grid of N x N
vertices (2 (N-1)^2 triangles; N = 1000 gives the 2M-triangle case) with a
smooth, deterministic relief, and a kdrt-scene/1 JSON file that references it.

Usage: bench/make_heightfield.py OUT_DIR [N]   (writes OUT_DIR/heightfield.{obj,json})
"""
import json
import math
import os
import sys


def height(x, z):
    return (0.08 * math.sin(7.0 * x) * math.cos(5.0 * z)
            + 0.03 * math.sin(23.0 * x + 11.0 * z)
            + 0.15 * math.exp(-8.0 * ((x - 0.2) ** 2 + (z + 0.1) ** 2)))


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    out_dir = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) == 3 else 1000
    if n < 2:
        sys.exit("N must be at least 2")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "heightfield.obj"), "w") as f:
        lines = []
        for i in range(n):
            x = -1.0 + 2.0 * i / (n - 1)
            for j in range(n):
                z = -1.0 + 2.0 * j / (n - 1)
                lines.append(f"v {x:.6f} {height(x, z):.6f} {z:.6f}\n")
        f.writelines(lines)
        lines = []
        for i in range(n - 1):
            for j in range(n - 1):
                a = i * n + j + 1  # OBJ indices start at 1
                b, c, d = a + n, a + n + 1, a + 1
                lines.append(f"f {a} {b} {c}\nf {a} {c} {d}\n")
        f.writelines(lines)
    scene = {
        "format": "kdrt-scene/1",
        "name": f"heightfield-{2 * (n - 1) ** 2}",
        "camera": {"position": [0.0, 1.4, -2.2], "look_at": [0.0, 0.0, 0.0], "up": [0, 1, 0], "fov_y": 45},
        "settings": {"width": 500, "height": 500, "max_depth": 2, "samples": 1,
                     "background": [0.1, 0.1, 0.15], "ambient": [0.1, 0.1, 0.1]},
        "materials": {"ground": {"color": [0.5, 0.7, 0.4], "specular": 0.1}},
        "lights": [{"position": [2.0, 3.0, -2.0], "color": [1, 1, 1]}],
        "meshes": [{"obj": "heightfield.obj", "material": "ground"}],
    }
    with open(os.path.join(out_dir, "heightfield.json"), "w") as f:
        json.dump(scene, f, indent=1)


if __name__ == "__main__":
    main()
