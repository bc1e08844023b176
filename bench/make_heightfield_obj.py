#!/usr/bin/env python3
"""Writes a heightfield OBJ: an N x N vertex grid (default 1001 x 1001, i.e.
2,000,000 triangles) over [-1, 1]^2 with a smooth height function, for timing
the OBJ loader against tinyobjloader (kdrt-obj-bench).

Usage: bench/make_heightfield_obj.py OUT.obj [N]
"""
import math
import sys


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) == 3 else 1001
    with open(out, "w") as f:
        f.write(f"# heightfield {n}x{n}, {2 * (n - 1) ** 2} triangles (make_heightfield_obj.py)\n")
        lines = []
        for j in range(n):
            y = -1.0 + 2.0 * j / (n - 1)
            for i in range(n):
                x = -1.0 + 2.0 * i / (n - 1)
                z = 0.25 * math.sin(6.0 * x) * math.cos(5.0 * y) + 0.1 * math.sin(17.0 * x * y)
                lines.append(f"v {x:.6f} {y:.6f} {z:.6f}\n")
        f.writelines(lines)
        lines = []
        for j in range(n - 1):
            for i in range(n - 1):
                a = j * n + i + 1  # OBJ indices are 1-based
                b, c, d = a + 1, a + n, a + n + 1
                lines.append(f"f {a} {b} {d}\nf {a} {d} {c}\n")
        f.writelines(lines)


if __name__ == "__main__":
    main()
