#!/usr/bin/env python3
"""Writes the large or pathological scene files used to time the scene loader
(the robustness issue's case 8): a valid scene of N spheres, a scene with N
unknown top-level keys, and an N-deep unterminated object.

Usage: bench/make_large_scene.py spheres|unknown-keys|deep OUT.json N
"""
import sys


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in ("spheres", "unknown-keys", "deep"):
        sys.exit(__doc__)
    kind, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    head = ('{"format": "kdrt-scene/1",\n "camera": {"position": [0, 0, -50], "look_at": [0, 0, 0], '
            '"up": [0, 1, 0], "fov_y": 40},\n "materials": {"m": {"color": [0.8, 0.3, 0.2]}},\n')
    with open(out, "w") as f:
        if kind == "spheres":
            side = max(1, round(n ** (1 / 3)))
            f.write(head + ' "lights": [{"position": [0, 50, -50], "color": [1, 1, 1]}],\n "spheres": [\n')
            f.write(",\n".join(
                f'  {{"center": [{i % side * 0.5:.3f}, {i // side % side * 0.5:.3f}, {i // (side * side) * 0.5:.3f}],'
                f' "radius": 0.2, "material": "m"}}' for i in range(n)))
            f.write("\n ]\n}\n")
        elif kind == "unknown-keys":
            f.write('{"format": "kdrt-scene/1",\n')
            f.write("".join(f' "unknown{i}": {i},\n' for i in range(n)))
            f.write(' "name": "keys"\n}\n')
        else:
            f.write('{"format": "kdrt-scene/1", "x": ' + '{"a": ' * n)


if __name__ == "__main__":
    main()
