#!/usr/bin/env python3
"""The study's tables on one OpenCL device (a GPU, say) beside kdrt's C++ cpu device, in one run.

Through kdrt-render alone, so it needs nothing but the binary and a Python 3:
  1. every traversal on the five scenes: the device's pictures and id maps against the cpu device's,
     cold compile time, and render time (median of warm runs) on both devices;
  2. the per-kernel profile (--profile-commands) of each scene;
  3. each kernel's private and local memory and preferred work-group multiple (kernel_resources);
  4. big meshes when their scene files are given (kdrt-bench generate), and larger images;
  5. double precision, the plain schedule and fixed local sizes against the defaults.
Sections run in that order while --budget-s lasts; what did not fit is listed as skipped.
Writes results.jsonl (one record per render) and summary.md to --out.

  bench/opencl_device_tables.py --render build/apps/kdrt-render/kdrt-render --device opencl:gpu --out out/gpu
"""
import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from array import array

SCENES = ["2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"]
TRAVERSALS = ["none", "restart", "ropes", "stack", "short-stack"]


class Runner:
    def __init__(self, args):
        self.args = args
        self.deadline = time.monotonic() + args.budget_s
        self.records = open(os.path.join(args.out, "results.jsonl"), "w")
        self.work = tempfile.mkdtemp(prefix="kdrt-tables-")
        self.kernel_cache = os.path.join(self.work, "kernels")  # empty: the first run of a variant compiles
        self.lines = []
        self.skipped = []
        self.renders = 0

    def left(self):
        return self.deadline - time.monotonic()

    def render(self, scene, device, extra=(), outputs=False, tag=""):
        """One kdrt-render process; its --stats-json, or {"error": ...}."""
        # The study's structure, the kd-tree, in every row (kdrt-render's default is the BVH).
        cmd = [self.args.render, scene, "--device", device, "--accel", "kd", "--stats-json", "-q",
               "--kernel-cache", self.kernel_cache]
        cmd += list(extra)
        self.renders += 1
        stem = os.path.join(self.work, str(self.renders))
        if outputs:
            cmd += ["-o", stem + ".pfm", "--aov-ids", stem + ".ids"]
        started = time.monotonic()
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=max(5.0, min(300.0, self.left())))
        except subprocess.TimeoutExpired:
            stats = {"error": "timed out"}
        else:
            if done.returncode != 0:
                stats = {"error": f"exit {done.returncode}: {done.stderr.strip()[-400:]}"}
            else:
                stats = json.loads(done.stdout)
        stats["process_s"] = time.monotonic() - started
        if outputs and "error" not in stats:
            stats["_pfm"], stats["_ids"] = stem + ".pfm", stem + ".ids"
        record = {"tag": tag, "scene": os.path.basename(scene), "device": device, "args": list(extra)}
        record.update({k: v for k, v in stats.items() if not k.startswith("_") and k != "tree_stats"})
        self.records.write(json.dumps(record) + "\n")
        self.records.flush()
        return stats

    def timed(self, scene, device, extra=(), reps=None, outputs=False, tag=""):
        """A first run (it compiles, and writes the picture when asked), then warm runs: their median render_ms."""
        first = self.render(scene, device, extra, outputs, tag + " first")
        if "error" in first:
            return first, None
        times = []
        for _ in range(reps or self.args.reps):
            if self.left() < 10:
                break
            s = self.render(scene, device, extra, False, tag)
            if "error" in s:
                return s, None
            times.append(s["render_ms"])
        return first, (statistics.median(times) if times else None)

    def say(self, text=""):
        print(text, flush=True)
        self.lines.append(text)

    def table(self, header, rows):
        self.say("| " + " | ".join(header) + " |")
        self.say("|" + "|".join("---" if i == 0 else "---:" for i in range(len(header))) + "|")
        for r in rows:
            self.say("| " + " | ".join(r) + " |")
        self.say()


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = array("f")
        data.frombytes(f.read(w * h * 12))
    if (scale > 0) != (sys.byteorder == "big"):
        data.byteswap()
    return data


def read_ids(path):
    with open(path, "rb") as f:
        raw = f.read()
    n = len(raw) // 8
    ids = array("i")
    ids.frombytes(raw[: 4 * n])
    if sys.byteorder == "big":
        ids.byteswap()
    return ids


def compare(ref, got):
    """Image RMSE and the count of camera-ray ids that differ, against the reference's outputs."""
    a, b = read_pfm(ref["_pfm"]), read_pfm(got["_pfm"])
    rmse = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)) / max(1, len(a)))
    ia, ib = read_ids(ref["_ids"]), read_ids(got["_ids"])
    return rmse, sum(1 for x, y in zip(ia, ib) if x != y), len(ia)


def ms(v):
    return "-" if v is None else f"{v:.1f}" if v >= 10 else f"{v:.2f}"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", default="build/apps/kdrt-render/kdrt-render")
    p.add_argument("--device", default="opencl:gpu", help="the OpenCL device to measure")
    p.add_argument("--scenes-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes"))
    p.add_argument("--meshes", nargs="*", default=[], help="big-mesh scene files (kdrt-bench generate)")
    p.add_argument("--reps", type=int, default=3, help="warm runs per configuration (their median)")
    p.add_argument("--budget-s", type=float, default=400)
    p.add_argument("--big", type=int, default=2000, help="image side of the larger-image section")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    r = Runner(args)
    scene = {s: os.path.join(args.scenes_dir, s + ".json") for s in SCENES}
    dev = args.device

    r.say(f"# kdrt on {dev} beside the cpu device")
    listing = subprocess.run([args.render, "--list-devices"], capture_output=True, text=True)
    r.say("```\n" + listing.stdout.strip() + "\n```\n")

    # 1. Every traversal: pictures and id maps against the cpu device's stack traversal, and times.
    refs, cpu_ms, dev_ms, cold, checks, stack_stats = {}, {}, {}, {}, {}, {}
    for s in SCENES:
        refs[s] = r.render(scene[s], "cpu", ["--traversal", "stack"], True, "reference")
        for t in TRAVERSALS:
            if r.left() < 30:
                r.skipped.append(f"traversals from {s} {t}")
                break
            reps = 1 if t == "none" else None
            first, med = r.timed(scene[s], dev, ["--traversal", t], reps, True, "traversal")
            if "error" in first:
                checks[s, t] = "ERROR " + first["error"]
                continue
            dev_ms[s, t], cold[s, t] = med, first.get("compile_ms")
            if t == "stack":
                stack_stats[s] = first
            if "error" not in refs[s]:
                rmse, bad, n = compare(refs[s], first)
                checks[s, t] = f"rmse {rmse:.1e}, ids {bad}/{n}"
            _, cpu_ms[s, t] = r.timed(scene[s], "cpu", ["--traversal", t], reps, False, "cpu traversal")
    r.say("## 1. Render ms, every traversal (SAH tree, float, persistent; median of warm runs)\n")
    r.table(["scene"] + [f"{t} {d}" for t in TRAVERSALS for d in ("dev", "cpu")],
            [[s] + [ms(m.get((s, t))) for t in TRAVERSALS for m in (dev_ms, cpu_ms)] for s in SCENES])
    r.say("Device / cpu ratio:\n")
    r.table(["scene"] + TRAVERSALS,
            [[s] + [(f"{dev_ms[s, t] / cpu_ms[s, t]:.2f}" if dev_ms.get((s, t)) and cpu_ms.get((s, t)) else "-")
                    for t in TRAVERSALS] for s in SCENES])
    r.say("Compile ms of the device's program with an empty kdrt cache (the driver's own cache, if any, may be warm):\n")
    r.table(["scene"] + TRAVERSALS, [[s] + [ms(cold.get((s, t))) for t in TRAVERSALS] for s in SCENES])
    r.say("Against the cpu device's stack traversal (image RMSE, camera-ray ids that differ):\n")
    r.table(["scene"] + TRAVERSALS, [[s] + [checks.get((s, t), "-") for t in TRAVERSALS] for s in SCENES])

    # 2-3. Profile and resources of the stack and short-stack kernels.
    if r.left() > 30:
        r.say("## 2. Device ms per command and level (stack traversal, --profile-commands)\n")
        for s in SCENES:
            st = r.render(scene[s], dev, ["--profile-commands"], False, "profile")
            if "error" in st:
                r.say(f"{s}: {st['error']}\n")
                continue
            parts = {}
            for c in st.get("command_times", []):
                parts[c["command"]] = parts.get(c["command"], 0.0) + c["device_ms"]
            r.say(f"- {s}: render {ms(st['render_ms'])} ms, launches {st.get('launches')}; " +
                  ", ".join(f"{k} {ms(v)}" for k, v in sorted(parts.items(), key=lambda kv: -kv[1])))
        r.say()
    else:
        r.skipped.append("profile")
    rows = []
    for t in ("stack", "short-stack", "restart", "ropes"):
        if r.left() < 20:
            break
        st = r.render(scene["insane"], dev, ["--traversal", t], False, "resources")
        for k in st.get("kernel_resources", []):
            if k["kernel"] in ("trace_persistent", "trace_plain", "query_closest"):
                rows.append([t, k["kernel"], str(k["private_bytes"]), str(k["local_bytes"]), str(k["work_group_size"]),
                             str(k["preferred_multiple"]), str(st.get("traversal_stack_bytes"))])
    r.say("## 3. Kernel resources (insane)\n")
    r.table(["traversal", "kernel", "private B", "local B", "max work-group", "preferred multiple", "stack B"], rows)

    # 4. Larger images and big meshes: the work a GPU is sized for.
    rows = []
    big = ["--width", str(args.big), "--height", str(args.big)]
    for m in args.meshes:
        if r.left() < 60:
            r.skipped.append(f"mesh {m}")
            continue
        cache = ["--tree-cache", os.path.join(r.work, "trees")]
        first, med = r.timed(m, dev, cache, None, False, "mesh")
        _, cmed = r.timed(m, "cpu", cache, None, False, "cpu mesh")
        label = os.path.basename(m).removesuffix(".json")
        if "error" in first:
            rows.append([label, first["error"][:80], "", "", ""])
            continue
        rows.append([f"{label} (upload {ms(first.get('upload_ms'))} ms)", ms(med), ms(cmed),
                     f"{cmed / med:.1f}" if med and cmed else "-",
                     f"{first.get('rays', {}).get('total', 0) / (med * 1e3):.0f}" if med else "-"])
    for s in SCENES:
        if r.left() < 40:
            r.skipped.append(f"big image {s}")
            continue
        first, med = r.timed(scene[s], dev, big, None, False, "big image")
        _, cmed = r.timed(scene[s], "cpu", big, None, False, "cpu big image")
        rows.append([f"{s} {args.big}x{args.big}", ms(med), ms(cmed), f"{cmed / med:.1f}" if med and cmed else "-",
                     f"{first.get('rays', {}).get('total', 0) / (med * 1e3):.0f}" if med else "-"])
    r.say("## 4. Larger work: render ms (stack traversal, float)\n")
    r.table(["work", "device", "cpu", "cpu / device", "device Mrays/s"], rows)

    # 5. Precision, schedule, local size: the stack traversal against its default.
    variants = [("double", ["--precision", "double"]), ("plain", ["--schedule", "plain"]),
                ("local 32", ["--local-size", "32"]), ("local 64", ["--local-size", "64"]),
                ("local 128", ["--local-size", "128"]), ("local 256", ["--local-size", "256"]),
                ("short-stack double", ["--traversal", "short-stack", "--precision", "double"])]
    got = {}
    for name, extra in variants:
        for s in SCENES:
            if r.left() < 30:
                r.skipped.append(f"variant {name} {s}")
                continue
            first, med = r.timed(scene[s], dev, extra, 2, False, "variant " + name)
            got[name, s] = med if "error" not in first else None
    r.say("## 5. Render ms of variants (stack traversal unless named; default = section 1's stack)\n")
    r.table(["variant"] + SCENES, [["default"] + [ms(dev_ms.get((s, "stack"))) for s in SCENES]] +
            [[n] + [ms(got.get((n, s))) for s in SCENES] for n, _ in variants])

    if r.skipped:
        r.say("Skipped for time: " + "; ".join(r.skipped))
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write("\n".join(r.lines) + "\n")
    shutil.rmtree(r.work)  # pictures, id maps, kernels and trees: hundreds of MB


if __name__ == "__main__":
    main()
