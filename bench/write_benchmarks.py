#!/usr/bin/env python3
"""Writes BENCHMARKS.md from one run's results (bench/run_all.sh leaves them in
bench/results/): the machine and the method, then one section per question, each
a function below registered with @section(title, result names). A section reads
RESULTS/NAME.json; one whose results are missing says so (the GPU's falls back
to the archived tables in bench/sections/, which say where they come from).
Adding a table: one function here, one `step` line in bench/run_all.sh.

  bench/write_benchmarks.py bench/results > BENCHMARKS.md
"""
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SECTIONS = []  # (title, result names, function), in the document's order


def section(title, *results):
    """Registers f(results...) -> Markdown as a section of the document."""
    def register(f):
        SECTIONS.append((title, results, f))
        return f
    return register


# ---- formatting ----------------------------------------------------------------------------------

def ms(v):
    """Milliseconds to three significant digits or so: 0.123, 12.3, 1234."""
    if v is None:
        return "-"
    return f"{v:.3f}" if v < 1 else f"{v:.2f}" if v < 10 else f"{v:.1f}" if v < 1000 else f"{v:.0f}"


def num(v, digits=2):
    return "-" if v is None else f"{v:.{digits}f}"


def ratio(a, b):
    """a / b as "1.23x", "-" when either is missing."""
    return f"{a / b:.2f}x" if a and b else "-"


def table(header, rows):
    """A Markdown table; columns after the first are right-aligned."""
    lines = ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def short(device_name):
    """'opencl:0 (pthread-..., Portable Computing Language)' -> 'opencl:0'."""
    return device_name.split(" (")[0]


def read_text(name):
    with open(os.path.join(HERE, "sections", name)) as f:
        return f.read().strip() + "\n"


# ---- the machine and the method ------------------------------------------------------------------

def header(results, steps):
    m = results.get("machine") or {}
    quick = any(isinstance(r, dict) and (r.get("quick") or (r.get("settings") or {}).get("quick"))
                for r in results.values())
    out = ["# Benchmarks", "",
           "<!-- Written by bench/write_benchmarks.py from bench/results/: edit the generator, not this file. -->", ""]
    if quick:
        out += ["**SMOKE RUN (`--quick`): tiny images, one run each. These figures test the pipeline; they are not "
                "measurements.**", ""]
    later = sorted({s["commit"] for s in steps if s.get("commit") and s["commit"] != m.get("commit")})
    out += ["Every figure below comes from one run of one command, on one machine, at one commit "
            f"(`{m.get('commit', '?')}`{', with uncommitted changes' if m.get('uncommitted_changes') else ''}"
            + (f"; the steps the load table shows at {', '.join(f'`{c}`' for c in later)} were run again there"
               if later else "") + ")"
            + ("." if results.get("gpu") else ", except the GPU's (section e), which say where they come from.")
            + " To regenerate them all:", "",
            "    scripts/install-deps.sh --bench --full   # Embree, POV-Ray, matplotlib, Open MPI",
            "    bench/run_all.sh                         # builds, measures into bench/results/, writes this file", "",
            "## The machine and the method", ""]
    out += [f"- **Machine**: {m.get('cpu', '?')}, {m.get('logical_cpus', '?')} logical CPUs, "
            f"{m.get('memory_gib', '?')} GiB; {m.get('os', '?')}.",
            "- **Devices** (`kdrt-render --list-devices`): " + "; ".join(device_line(d) for d in m.get("devices", [])) + ".",
            f"- **Software**: {m.get('kdrt', 'kdrt')} at `{m.get('commit', '?')}` ({m.get('commit_date', '?')}), "
            f"{m.get('compiler', '?')}, Release; {embree_version(results)}; {m.get('povray') or 'no POV-Ray'}; "
            f"{m.get('mpirun') or 'no Open MPI'}; Python {m.get('python', '?')}, matplotlib {m.get('matplotlib')}.",
            f"- **Date**: {m.get('date', '?')}.", ""]
    if steps:
        out += ["- **Load**: each step's time, the load average before and after it, and how many cores other "
                "processes kept busy meanwhile (all CPU time from /proc/stat less the step's own):", ""]
        out.append(table(["step", "commit", "minutes", "load before", "load after", "others' cores", "exit"],
                         [[s["step"], s.get("commit") or m.get("commit", "?"), num(s["wall_s"] / 60, 1),
                           s["load_before"], s["load_after"], s["others_cores"], s["exit"]] for s in steps]))
    out += [read_text("method.md")]
    return "\n".join(out)


def device_line(line):
    """'opencl:0   Portable Computing Language | NAME | VENDOR | cpu | driver 3.1 | 2 compute units | ...'
    -> '`opencl:0` NAME (Portable Computing Language, cpu, driver 3.1, 2 compute units)'."""
    first, *fields = [f.strip() for f in line.split("|")]
    device, _, platform = first.partition(" ")
    return f"`{device}` {fields[0]} ({platform.strip()}, {', '.join(fields[2:5])})" if len(fields) >= 5 else line


def embree_version(results):
    for r in results.get("table", {}).get("embree", []):
        return r["name"].split(" (")[0]
    return "Embree not in this run"


# ---- where kdrt stands: the wide BVH's targets ---------------------------------------------------

def tracer_ratio(rows, a, b, mesh=None, rays=None, query=None):
    """{(mesh, rays, query): mrays(a) / mrays(b)} for rays.json rows with both tracers; a and b: a name,
    or a (prefix, suffix) pair matching one."""
    def rate(t, name):
        if isinstance(name, tuple):
            name = next((n for n in t if n.startswith(name[0]) and n.endswith(name[1])), None)
        return (t.get(name) or {}).get("mrays_per_s")
    out = {}
    for row in rows:
        if (mesh and row["input"] != mesh) or (rays and row["rays"] != rays) or (query and row["query"] != query):
            continue
        t = {x["name"]: x for x in row["tracers"]}
        x, y = rate(t, a), rate(t, b)
        if x and y:
            out[row["input"], row["rays"], row["query"]] = x / y
    return out


def span(values, fmt="{:.2f}x"):
    """The range of `values` as "0.78-0.98x" (one value: "0.78x"); "-" for none."""
    values = sorted(v for v in values if v is not None)
    if not values:
        return "-"
    lo, hi = fmt.format(values[0]), fmt.format(values[-1])
    return lo if lo == hi else lo.rstrip("x") + "-" + hi


def verdict(values, ok):
    values = [v for v in values if v is not None]
    if not values:
        return "not measured"
    met = sum(ok(v) for v in values)
    return "met" if met == len(values) else f"**short** ({len(values) - met} of {len(values)})"


def cpu_opencl_ids(devices):
    """The ids of the OpenCL devices that are CPUs (PoCL) in a results file's device list."""
    return [d["id"] for d in devices or [] if d["id"].startswith("opencl") and d.get("type") == "cpu"]


def ray_targets(r):
    """The rays.json rows of the targets table."""
    rr, rows = r["rows"], []
    cam = tracer_ratio(rr, "kdrt cpu bvh", "Embree rtcIntersect1", rays="camera", query="closest")
    cam = {k: v for k, v in cam.items() if k[0].startswith(("torus-99856", "heightfield"))}
    rows.append(["camera rays, closest hit, torus 100k and heightfield 2M: at least 1.0x `rtcIntersect1`",
                 ", ".join(f"{k[0]} {v:.2f}x" for k, v in sorted(cam.items())), verdict(cam.values(), lambda v: v >= 1.0),
                 "c"])
    for query in ("closest", "any hit"):
        inc = tracer_ratio(rr, "kdrt cpu bvh", "Embree rtcIntersect1", rays="incoherent", query=query)
        low = min(inc, key=inc.get) if inc else None
        rows.append([f"incoherent rays, {query}: at least 0.8x `rtcIntersect1`",
                     span(inc.values()) + (f" (lowest: {low[0]})" if low else ""), verdict(inc.values(), lambda v: v >= 0.8),
                     "c"])
    builds = [x for x in r["trees"] if x.get("accel") == "bvh"]
    big = [x["build_ms"] / x["embree_build_ms"] for x in builds if x["input"] == "torus-1000000" and x.get("embree_build_ms")]
    rows.append(["build of the 1M torus: at most 1.5x Embree's medium build", span(big), verdict(big, lambda v: v <= 1.5), "c"])
    structure = [x["bytes_per_object"] for x in builds]
    packed = [x["bytes_per_object"] + x["device_bytes"] / x["objects"] for x in builds if x.get("device_bytes") and x["objects"]]
    rows.append(["memory: at most 48 B a triangle for the BVH",
                 f"the structure {span(structure, '{:.1f}')}; with the cpu device's packed leaves and their nodes "
                 f"{span(packed, '{:.0f}')}",
                 verdict(structure, lambda v: v <= 48) + " (the structure); " + verdict(packed, lambda v: v <= 48)
                 + " (with the packed leaves)", "c"])
    refits = [x["refit_ms"] / x["build_ms"] for x in builds if x.get("refit_ms") and x["build_ms"]]
    rows.append(["refit, every vertex moved: at most 10 % of the build", span(refits, "{:.0%}"),
                 verdict(refits, lambda v: v <= 0.10), "c"])
    for device in cpu_opencl_ids(r.get("devices")):
        for rays in ("camera", "incoherent"):
            for query in ("closest", "any hit"):
                twin = tracer_ratio(rr, f"kdrt {device} bvh", "kdrt cpu bvh", rays=rays, query=query)
                rows.append([f"PoCL's kernels (`{device}`), {rays} {query}: within 1.2x of the C++ twin (at least "
                             "0.83x its speed)", span(twin.values()), verdict(twin.values(), lambda v: v >= 1 / 1.2), "c"])
    return rows


def process_targets(p):
    """The processes.json rows of the targets table: the BVH's whole kdrt-render process."""
    wall = lambda row, key: (row.get("cpu") or {}).get(key)  # kdrt-render's default structure, the BVH
    hf = [wall(row, "wall_ms") / row["embree"]["wall_ms"] for row in p["rows"]
          if row["input"].startswith("heightfield") and wall(row, "wall_ms") and (row.get("embree") or {}).get("wall_ms")]
    big = [wall(row, "peak_rss_mib") for row in p["rows"] if row["input"].startswith("torus-4")]
    return [["the 2M heightfield's whole `kdrt-render` process: at most 1.2x the Embree-based one", span(hf),
             verdict(hf, lambda v: v <= 1.2), "a"],
            ["the 4M torus's whole process: under 1 GiB", span(big, "{:.0f} MiB"), verdict(big, lambda v: v < 1024), "a"]]


def frames_by_scene(rows):
    """structures.json's measured rows as {(scene, device): {accel: row}}."""
    by = {}
    for row in rows:
        if "error" not in row:
            by.setdefault((row["scene"], row["device"]), {})[row["accel"]] = row
    return by


def frame_targets(st):
    """The structures.json rows of the targets table: Whitted frames, kd-tree against BVH."""
    by = {k: {accel: row["render_ms"] for accel, row in v.items() if row.get("render_ms")}
          for k, v in frames_by_scene(st["rows"]).items()}
    pocl = {row["device"] for row in st["rows"] if "Portable Computing Language" in (row.get("device_name") or "")}
    both = {k: v["bvh"] / v["kd"] for k, v in by.items() if "kd" in v and "bvh" in v}
    meshes = [v for k, v in both.items() if k[0] not in STUDY_SCENES]
    kd_wins = sorted(f"{k[0]} on {k[1]} ({v:.2f}x)" for k, v in both.items() if v > 1)
    cpu_bvh = {k[0]: v["bvh"] for k, v in by.items() if k[1] == "cpu" and "bvh" in v}
    frames = [v["bvh"] / cpu_bvh[k[0]] for k, v in by.items() if k[1] in pocl and "bvh" in v and k[0] in cpu_bvh]
    return [["Whitted frames on the meshes: the BVH no slower than the kd-tree (bvh / kd at most 1)", span(meshes),
             verdict(meshes, lambda v: v <= 1.0), "d"],
            ["where the kd-tree renders faster (bvh / kd above 1)", ", ".join(kd_wins) or "nowhere", "-", "d"],
            ["PoCL's Whitted frames with the BVH: within 1.2x of the cpu device's", span(frames),
             verdict(frames, lambda v: v <= 1.2), "d"]]


@section("Where kdrt stands: the wide BVH's targets", "rays", "processes", "structures")
def targets(r, p, st):
    """The targets of the wide BVH (issue 35) against this run's figures, each from the section named."""
    rows = (ray_targets(r) if r else []) + (process_targets(p) if p else []) + (frame_targets(st) if st else [])
    return "\n".join(["The wide BVH's targets against this run, each computed from the section named (2 threads for "
                      "every tracer, Embree 3 the yardstick; PoCL's kernels against their C++ twin on the same BVH).",
                      "", table(["target", "this run", "met", "section"], rows), read_text("targets.md")])


# ---- a. the study's scenes -----------------------------------------------------------------------

STUDY_SCENES = ["2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"]
# The study's figures in ms (i7-2670QM, 4 cores / 8 threads; GeForce GT 540M; 500x500, depth 15, its
# median kd-tree at depth 10); "> N": it stopped there. Context, not a yardstick: its scenes are
# described in words, ours follow the descriptions.
STUDY = {
    "study CPU none": ["252", "13138", "74844", "188", "> 720000"],
    "study CPU basic (restart)": ["133", "15593", "251", "170", "10910"],
    "study CPU neighbour (ropes)": ["131", "15443", "250", "175", "10760"],
    "study GPU none": ["590", "1010", "2660", "610", "> 15000"],
    "study GPU basic (restart)": ["603", "1480", "619", "610", "4730"],
    "study GPU neighbour (ropes)": ["612", "1483", "620", "607", "4470"],
}


@section("a. The study's five scenes", "table", "processes")
def study(t, processes):
    out = []
    if t:
        s = t["settings"]
        scenes = list(dict.fromkeys(r["scene"] for r in t["rows"]))
        configs = list(dict.fromkeys((r["device"], r["traversal"], r["tree"]) for r in t["rows"]))
        cell = {(r["device"], r["traversal"], r["tree"], r["scene"]): r for r in t["rows"]}
        embree = {e["scene"]: e for e in t["embree"]}

        def shown(r):
            return ms(r["render_ms"]) if r["status"] == "timed" else r["status"] + (f" ({r['note']})" if r["note"] else "")

        out += [f"Render time in ms: {s['width']}x{s['height']}, ray depth {s['max_depth']}, one sample per pixel, "
                f"median of {s['runs']} rounds in which every row renders once. `median-{s['median_depth']}` is the "
                f"study's median builder at depth {s['median_depth']}, `sah` the kd-tree's binned SAH builder, `bvh` the "
                f"8-wide BVH (kdrt's default structure, its stack traversal); `none` is brute force. The cpu device and Embree use {s['threads']} threads. Embree 3 renders through "
                "kdrt's own shading (bench/embree_render.h). Every row's camera id map was checked against the "
                "cpu device without a tree before it was timed.", ""]
        rows = [[d, tr, tree] + [shown(cell[d, tr, tree, sc]) for sc in scenes] for d, tr, tree in configs]
        if embree:
            rows.append(["Embree", "BVH", "Embree"] + [ms(embree[sc]["render_ms"]) if sc in embree else "-"
                                                        for sc in scenes])
        rows += [[label, "", "study"] + [v[STUDY_SCENES.index(sc)] if sc in STUDY_SCENES else "-" for sc in scenes]
                 for label, v in STUDY.items()]
        out += [table(["device", "traversal", "tree"] + scenes, rows)]
        if plot_study(t):
            out += ["![render time per scene, log scale](bench/results/table.png)", ""]
        if embree:
            out += ["kdrt's default (the BVH) and its fastest row per device against Embree, same "
                    "rounds; above 1, kdrt is slower. Embree's image against the cpu device's (RMSE), its ids "
                    "against brute force's, and the harness (kdrt's shader over kdrt's own traversal) against the "
                    "cpu device:", ""]
            devices = list(dict.fromkeys(d for d, _, _ in configs))
            header = ["scene", "Embree ms", "Embree BVH build ms"]
            for d in devices:
                header += [f"{d} default", f"{d} / Embree", f"{d} fastest (row)"]
            header += ["image RMSE", "Embree ids", "harness RMSE"]
            rows = []
            for sc in scenes:
                e = embree.get(sc, {})
                row = [sc, ms(e.get("render_ms")), ms(e.get("bvh_build_ms"))]
                for d in devices:
                    default = cell.get((d, "stack", "bvh", sc), {}).get("render_ms")
                    timed = [r for r in t["rows"] if r["scene"] == sc and r["device"] == d and r["render_ms"]]
                    best = min(timed, key=lambda r: r["render_ms"], default=None)
                    row += [ms(default), ratio(default, e.get("render_ms")),
                            f"{ms(best['render_ms'])} ({best['traversal']} {best['tree']})" if best else "-"]
                row += [num(e.get("rmse_vs_kdrt_cpu"), 5), e.get("ids", "-"), num(e.get("harness_rmse"), 6)]
                rows.append(row)
            out += [table(header, rows)]
    if processes:
        s = processes["settings"]
        devices = s["devices"]
        out += [f"Whole processes, start to PNG written, {s['size']}x{s['size']} (meshes: their own size), median of "
                f"{s['rounds']} runs in turn after a warm-up: kdrt-render (kernels cached, the tree built in every "
                "run), the Embree-based `kdrt-bench embree-render` (kdrt's loader, shading and PNG writer), and "
                f"POV-Ray 3.7 (`povray {' '.join(s['povray_options'])}`, all cores, the scene written by "
                "`kdrt-bench povray`). The 1x1 column is the same process for one pixel: start-up, loading, "
                "the tree and writing, which every frame pays. POV-Ray's RMSE against kdrt's picture checks that "
                "the scenes agree. kdrt-render with its default structure, the BVH; `cpu+kd`: the cpu device with `--accel kd`.", ""]
        header = ["input"] + [f"kdrt-render {d} ms" for d in devices] + ["Embree-based ms", "POV-Ray ms",
                  f"POV-Ray / kdrt {devices[0]}", f"kdrt {devices[0]} / Embree-based",
                  f"1x1: kdrt {devices[0]}, Embree-based, POV-Ray ms", "peak RSS MiB: " + ", ".join([f"kdrt {d}" for d in devices] + ["Embree-based", "POV-Ray"]),
                  "POV-Ray RMSE"] + [f"kdrt {d} / Embree-based" for d in devices if "+" in d]
        rows = []
        for r in processes["rows"]:
            wall = lambda k: (r.get(k) or {}).get("wall_ms")
            rows.append([r["input"]] + [ms(wall(d)) for d in devices] + [
                ms(wall("embree")), ms(wall("povray")), ratio(wall("povray"), wall(devices[0])),
                ratio(wall(devices[0]), wall("embree")),
                f"{ms(wall(devices[0] + '_1x1'))}, {ms(wall('embree_1x1'))}, {ms(wall('povray_1x1'))}",
                ", ".join(num((r.get(k) or {}).get("peak_rss_mib"), 0) for k in [*devices, "embree", "povray"]),
                num(r.get("povray_rmse"), 4)] + [ratio(wall(d), wall("embree")) for d in devices if "+" in d])
        out += [table(header, rows)]
    return "\n".join(out)


def plot_study(t):
    """bench/results/table.png: kdrt's default per device, Embree and the study's best, per scene (log scale)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("write_benchmarks: no matplotlib (scripts/install-deps.sh --bench): no plots", file=sys.stderr)
        return False
    scenes = list(dict.fromkeys(r["scene"] for r in t["rows"]))
    series = {}
    for r in t["rows"]:
        if r["traversal"] == "stack" and r["tree"] == "bvh":
            series.setdefault(f"kdrt {r['device']} (BVH)", {})[r["scene"]] = r["render_ms"]
    series["Embree 3 (same shading)"] = {e["scene"]: e["render_ms"] for e in t["embree"]}
    for label in ("study CPU neighbour (ropes)", "study GPU neighbour (ropes)"):
        series[label + ", 2016"] = {sc: float(STUDY[label][i]) for i, sc in enumerate(STUDY_SCENES)}
    fig, ax = plt.subplots(figsize=(9, 4.5))
    width = 0.8 / len(series)
    for k, (label, values) in enumerate(series.items()):
        xs = [i + (k - (len(series) - 1) / 2) * width for i in range(len(scenes))]
        ax.bar(xs, [values.get(sc) or 0 for sc in scenes], width, label=label)
    ax.set_xticks(range(len(scenes)), scenes)
    ax.set_yscale("log")
    ax.set_ylabel("render ms (log)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "table.png"), dpi=110)
    plt.close(fig)
    return True


# ---- b. building the tree ------------------------------------------------------------------------

@section("b. Building the tree", "build", "frames")
def builds(b, frames):
    out = []
    if b:
        s = b["settings"]
        out += [f"Each builder on its own (median of {s['runs']} builds after a warm-up; one build from 2M "
                f"objects), with the cpu device's SAH constants (triangle cost {s['triangle_cost']}). `bvh`: the "
                "BVH builder (binned SAH, collapsed to 8-wide nodes), timed as a commit with `Accel::Bvh` on the "
                "cpu device reports it (`CommitStats::build_ms`: the objects' boxes and the build); its depth is "
                "in wide levels. Bytes per object: nodes (a kd-tree's 8 B each, a BVH's 8-wide ones 256 B) and "
                "leaf lists, without ropes (only the kd-tree's ropes traversal builds them; their time and bytes "
                "apart). Build peak: the process's memory high-water mark during one build, reset before it, less "
                "the memory before it (not taken for the BVH, whose commit holds more than its build).", ""]
        rows = []
        for r in b["rows"]:
            n = max(r["objects"], 2)
            peak = (r["build_peak_rss_mib"] - r["rss_before_mib"]) if r["build_peak_rss_mib"] is not None else None
            rows.append([r["input"], r["objects"], r["builder"], r["threads"], ms(r["build_ms"]),
                         num(r["build_ms"] * 1e6 / (n * math.log2(n))),
                         num((r["node_bytes"] + r["leaf_list_bytes"]) / n, 1),
                         f"{ms(r['ropes_ms'])} ({num(r['rope_bytes'] / n, 1)} B)" if r["ropes_ms"] is not None else "-",
                         num(r["sah_cost"], 1), r["nodes"],
                         r["max_depth"], num(r["references_per_object"]), num(peak, 0)])
        out += [table(["input", "objects", "builder", "threads", "build ms", "ns per N log2 N", "B/object",
                       "ropes ms (B/object)", "SAH cost", "nodes", "depth", "references/object",
                       "build peak MiB"], rows)]
        if b["embree"]:
            out += ["Embree's BVH build (`rtcCommitScene`, on its TBB pool of every logical CPU) over the same "
                    "float geometry, against kdrt's kd-tree builder (`sah`) and BVH builder (`bvh`), each on one "
                    "thread and on every logical CPU:", ""]
            rows = []

            def by_threads(e, builder):
                return {r["threads"]: r["build_ms"] for r in b["rows"]
                        if r["input"] == e["input"] and r["builder"] == builder}

            for e in b["embree"]:
                sah, bvh = by_threads(e, "sah"), by_threads(e, "bvh")
                most = sah.get(max(sah)) if sah else None
                bvh_most = bvh.get(max(bvh)) if bvh else None
                rows.append([e["input"], ms(e["medium_ms"]), ms(e["high_ms"]), ms(sah.get(1)),
                             f"{ms(most)} ({max(sah)})" if sah else "-", ratio(most, e["high_ms"]),
                             ratio(most, e["medium_ms"]), ratio(sah.get(1), most), ms(bvh.get(1)),
                             f"{ms(bvh_most)} ({max(bvh)})" if bvh else "-", ratio(bvh_most, e["medium_ms"]),
                             ratio(bvh.get(1), bvh_most)])
            out += [table(["input", "Embree medium ms", "Embree high ms", "kd 1 thread ms", "kd all threads ms (n)",
                           "kd / Embree high", "kd / Embree medium", "kd 1 -> n threads", "BVH 1 thread ms",
                           "BVH all threads ms (n)", "BVH / Embree medium", "BVH 1 -> n threads"], rows)]
        if b.get("skipped"):
            out += ["Left out: " + "; ".join(b["skipped"]) + ".", ""]
    if frames:
        s = frames["settings"]
        out += [f"What a later frame costs: a CommittedScene's frame 1 (open the device, commit, render) against "
                f"frames 2-{s['frames']}, for which the camera orbits {s['step_degrees']} degrees, `update()` "
                f"then `render()`; medians of {s['runs']} sequences, each on a fresh device.", ""]
        rows = []
        for q in frames["sequences"]:
            first, later = q["frames"][0], q["frames"][1:]
            later_ms = sorted(f["wall_ms"] for f in later)[len(later) // 2]
            rows.append([q["input"], q["device"], ms(first["wall_ms"]), ms(later_ms),
                         ms(sorted(f["update_ms"] for f in later)[len(later) // 2]), ratio(later_ms, first["wall_ms"]),
                         f"{sum(f['builds'] for f in later)} / {sum(f['compiles'] for f in later)} / "
                         f"{sum(f['geometry_upload_bytes'] for f in later)}"])
        out += [table(["input", "device", "frame 1 ms", "later frame ms", "update() ms", "later / first",
                       "later frames' builds / compiles / upload bytes"], rows)]
    return "\n".join(out)


# ---- c. rays on meshes ---------------------------------------------------------------------------

@section("c. Rays on meshes: kd-tree, BVH and Embree", "rays")
def rays(r):
    s = r["settings"]
    tracers = [t["name"] for t in r["rows"][0]["tracers"]] if r["rows"] else []
    kdrt_cpu = [n for n in tracers if n.startswith("kdrt cpu")]
    out = [f"Rays per second (millions), no shading, {s['threads']} threads for every tracer; medians of {s['runs']} "
           f"rounds in which the tracers take turns, after a round that checks every tracer's ids against "
           f"`rtcIntersect1`'s. Camera rays: {s['camera_size']}x{s['camera_size']} through the scene's pinhole; "
           f"incoherent: {s['random_rays']} rays, origins uniform in the bounds, directions uniform on the sphere. "
           "Any hit: t_max = inf. kdrt: `kdrt::intersect` / `kdrt::occluded` on a CommittedScene, each device "
           "on its own structure (`kd`: the kd-tree, `bvh`: the 8-wide BVH, `CommitOptions::accel`); Embree: build "
           f"quality {s['embree_quality']}, single rays and 16-wide packets. The `layers` mesh stacks wavy sheets "
           "seen nearly edge-on: high depth complexity.", ""]
    rows = []
    for row in r["rows"]:
        t = {x["name"]: x for x in row["tracers"]}
        reference = t[tracers[0]]["mrays_per_s"]
        differ = max(x["differ_beyond_ties"] for x in row["tracers"]) / row["count"]
        rows.append([row["input"], row["rays"], row["query"]] + [num(t[n]["mrays_per_s"]) for n in tracers] +
                    [ratio(t[n]["mrays_per_s"], reference) for n in kdrt_cpu] + [f"{100 * differ:.3f} %"])
    out += [table(["mesh", "rays", "query"] + [f"{n} Mrays/s" for n in tracers] +
                  [f"{n} / rtcIntersect1" for n in kdrt_cpu] + ["ids unlike rtcIntersect1's, beyond ties"], rows)]
    out += spatial_splits(r, tracers)
    if r["trees"]:
        out += ["The structures the cpu device traced (BVH: wide nodes and leaf slots), and Embree's BVH build "
                "beside them. Builds, refits and updates: medians of 3 after a warm-up, in the process that "
                "traced the rays:", ""]
        out += [table(["mesh", "structure", "triangles", "build ms", "Embree BVH build ms", "build / Embree's",
                       "nodes", "leaves (empty)", "references/triangle", "B/triangle", "SAH cost",
                       "refit ms (every vertex moved)", "refit / build", "whole update() ms"],
                      [[x["input"], x.get("accel", "kd"), x["objects"], ms(x["build_ms"]), ms(x["embree_build_ms"]),
                        ratio(x["build_ms"], x["embree_build_ms"]), x.get("nodes", "-"),
                        f"{x.get('leaves', '-')} ({x.get('empty_leaves', '-')})",
                        num(x["references_per_object"]) if "references_per_object" in x else "-",
                        num(x["bytes_per_object"], 1) if "bytes_per_object" in x else "-",
                        num(x["sah_cost"], 1) if "sah_cost" in x else "-",
                        ms(x.get("refit_ms")), f"{100 * x['refit_ms'] / x['build_ms']:.0f} %" if "refit_ms" in x
                        else "-", ms(x.get("update_ms"))] for x in r["trees"]])]
        bvhs = [x for x in r["trees"] if x.get("accel") == "bvh" and x.get("device_bytes") and x["objects"]]
        if bvhs:
            extra = ", ".join(f"{x['input']} {x['device_bytes'] / x['objects']:.0f}" for x in bvhs)
            out += ["", "B/triangle is the structure alone. The cpu device also keeps every BVH leaf's triangles "
                    "packed for its leaf test (cpu/packed_leaves.h: blocks of up to 8 triangles, a lane each, in "
                    "the AVX2 copy) and a copy of the nodes whose leaf slots refer to the blocks; "
                    "`CommitStats::device_bytes` reports them, in B per triangle: "
                    f"{extra}."]
    return "\n".join(out)


def spatial_splits(r, tracers):
    """What Embree's spatial-split build (quality high) gives the meshes' rays against its medium one."""
    high = "Embree rtcIntersect1 high"
    if high not in tracers:
        return []
    gains = {}
    for row in r["rows"]:
        t = {x["name"]: x["mrays_per_s"] for x in row["tracers"]}
        if t[high] and t[tracers[0]]:
            gains.setdefault(f"{row['rays']} {row['query']}", []).append(t[high] / t[tracers[0]])
    every = sorted(g for v in gains.values() for g in v)
    if not every:
        return []
    median = every[len(every) // 2]
    builds = [b["high_ms"] / b["medium_ms"] for b in r.get("embree_builds", []) if b["medium_ms"] > 0]
    span = lambda v, d: f"{min(v):.{d}f}" + (f"-{max(v):.{d}f}" if f"{min(v):.{d}f}" != f"{max(v):.{d}f}" else "")
    build_text = f", for {span(builds, 1)}x the build time" if builds else ""
    verdict = ("On these meshes spatial splits do not pay: kdrt's BVH has none" if median < 1.05 else
               "On these meshes spatial splits pay; kdrt's BVH has none yet")
    return ["", "Spatial splits: `Embree rtcIntersect1 high` is `rtcIntersect1` (`rtcOccluded1` for any hit) on "
            "Embree's high-quality build of the same mesh, which splits triangles where that lowers the SAH (SBVH, "
            "Stich et al. 2009), timed in the same rounds. Its Mrays/s over `rtcIntersect1`'s on the medium build: " +
            "; ".join(f"{k} {span(v, 2)}x" for k, v in gains.items()) +
            f"; the median row {median:.2f}x{build_text}. {verdict}."]


# ---- d. kd-tree or BVH in whole frames -----------------------------------------------------------

@section("d. kd-tree or BVH: Whitted frames on every device", "structures")
def structures(t):
    s = t["settings"]
    out = [f"`kdrt-render --accel kd` against `--accel bvh` at {s['size']}, the scene's depth and effects: the "
           f"structure's build and the frame's render (no compile or write), medians of {s['rounds']} processes "
           "taken in turn. bvh / kd below 1: the BVH renders faster.", ""]
    errors = [f"- {row['scene']} on {row['device']} with `--accel {row['accel']}`: {row['error'].strip()}"
              for row in t["rows"] if "error" in row]
    rows = []
    for (scene, device), r in frames_by_scene(t["rows"]).items():
        kd, bvh = r.get("kd"), r.get("bvh")
        get = lambda x, k: x[k] if x else None
        rows.append([scene, short((kd or bvh)["device_name"]), ms(get(kd, "build_ms")), ms(get(bvh, "build_ms")),
                     ms(get(kd, "render_ms")), ms(get(bvh, "render_ms")),
                     ratio(get(bvh, "render_ms"), get(kd, "render_ms")),
                     num(get(kd, "objects_bytes"), 1), num(get(bvh, "objects_bytes"), 1)])
    out += [table(["scene", "device", "kd build ms", "BVH build ms", "kd render ms", "BVH render ms",
                   "render bvh / kd", "kd B/object", "BVH B/object"], rows)]
    if errors:
        out += ["", "Not measured:", ""] + errors
    return "\n".join(out)


# ---- e. the GPU ----------------------------------------------------------------------------------

GPU_KEPT = os.path.join(HERE, "results-gpu")  # bench/gpu_tables.sh's last run, on a machine lent with a GPU


@section("e. The GPU", "gpu")
def gpu(g):
    """The run's GPU tables (bench/opencl_device_tables.py), else the kept ones, which say where they come from."""
    if g is None:
        return "\n".join(kept_gpu_tables(load_kept_gpu()) + [read_text("gpu-archived.md")])
    # The script's own headings go one level below this section's.
    return "\n".join("###" + line.lstrip("#") if line.startswith("#") else line for line in g.splitlines()) + "\n"


def load_kept_gpu():
    kept = {name: v for name in ("machine", "rays", "structures", "warp") if (v := load_json(GPU_KEPT, name))}
    if steps := load_steps(GPU_KEPT):
        kept["steps"] = steps
    notes = os.path.join(GPU_KEPT, "NOTES.md")  # what a reader must know of that run, kept beside its results
    if os.path.exists(notes):
        kept["notes"] = open(notes).read().strip()
    return kept


def best_warp(warp, row, rate):
    """Warp's row with the fastest constructor by `rate` for a row of kdrt-bench rays, or None."""
    rows = [w for w in (warp or {}).get("rows", []) if "error" not in w and (w["input"], w["rays"], w["query"]) ==
            (row["input"], row["rays"], row["query"])]
    return max(rows, key=lambda w: w[rate], default=None)


def step_commits(steps, commit):
    """'`abc`', or '`abc` (rays, structures), `def` (warp)' when the steps ran at different commits."""
    by = {}
    for st in steps or []:
        by.setdefault(st.get("commit") or commit, []).append(st["step"])
    if len(by) < 2:
        return f"`{next(iter(by), commit)}`"
    return ", ".join(f"`{c}` ({', '.join(names)})" for c, names in by.items())


def kept_gpu_tables(k):
    """kd-tree against BVH on the GPU, beside the cpu device, Embree and Warp (bench/results-gpu)."""
    if "rays" not in k:
        return []
    m, r, warp = k.get("machine", {}), k["rays"], k.get("warp")
    gpus = [d for d in m.get("devices", []) if "| gpu |" in d]
    out = ["### kd-tree against BVH on the GPU, and NVIDIA Warp", "",
           f"**Not from this run**: `bench/gpu_tables.sh` on {m.get('date', '?')} at "
           f"{step_commits(k.get('steps'), m.get('commit', '?'))}: "
           f"{'; '.join(device_line(d) for d in gpus) or 'a GPU'}; host {m.get('cpu', '?')}, "
           f"{m.get('logical_cpus', '?')} logical CPUs, {m.get('os', '?')}. "
           f"Every CPU tracer ran on {r['settings']['threads']} threads. The rays and their checks are section c's "
           f"(`kdrt-bench rays`, medians of {r['settings']['runs']} rounds); kdrt's queries are timed from host "
           "arrays to host arrays (rays uploaded, 40-byte hits read back), and with `--device-buffers` also on rays "
           "already in the GPU's memory (`kdrt/opencl_interop.h`: the query alone, hits left there). Warp: `warp-lang` "
           f"{(warp or {}).get('warp_version', '(not run)')} on the same GPU, `wp.Mesh` (its own BVH; the fastest "
           "of its constructors per row, named) with `mesh_query_ray` (closest) and `mesh_query_ray_anyhit`, checked "
           "against Embree's hit distances (within 1e-4) and any-hit answers, timed host to host (rays uploaded; "
           f"{(warp or {}).get('host_read_back', 'the 4-byte distance or the 1-byte answer')} read back) and on rays "
           "already on the GPU (`bench/warp_rays.py`).", ""]
    if "notes" in k:
        out += [k["notes"], ""]
    out += gpu_ray_tables(r, warp) + gpu_build_table(r, warp)
    if "structures" in k:
        out += ["Whitted frames, each structure on each device, as section d measures them:", "",
                structures(k["structures"])]
    out += ["### Earlier GPU tables", ""]
    return out


def gpu_ray_tables(r, warp):
    """Mrays/s from host arrays, then on rays already in the GPU's memory (--device-buffers)."""
    names = [t["name"] for t in r["rows"][0]["tracers"]] if r["rows"] else []
    gpu_kd = next((n for n in names if n.startswith("kdrt opencl") and n.endswith(" kd")), None)
    gpu_bvh = next((n for n in names if n.startswith("kdrt opencl") and n.endswith(" bvh")), None)
    rows, resident = [], []
    for row in r["rows"]:
        t = {x["name"]: x["mrays_per_s"] for x in row["tracers"]}
        w = best_warp(warp, row, "host_mrays_per_s")
        rows.append([row["input"], row["rays"], row["query"], num(t.get("Embree rtcIntersect1")),
                     num(t.get("kdrt cpu bvh")), num(t.get(gpu_kd)), num(t.get(gpu_bvh)),
                     ratio(t.get(gpu_bvh), t.get(gpu_kd)),
                     f"{num(w['host_mrays_per_s'])} ({w['constructor']})" if w else "-",
                     ratio(t.get(gpu_bvh), w["host_mrays_per_s"] if w else None)])
        kd, bvh = t.get(f"{gpu_kd} buffers"), t.get(f"{gpu_bvh} buffers")
        w = best_warp(warp, row, "kernel_mrays_per_s")
        if kd or bvh:
            resident.append([row["input"], row["rays"], row["query"], num(kd), num(bvh), ratio(bvh, kd),
                             f"{num(w['kernel_mrays_per_s'])} ({w['constructor']})" if w else "-",
                             ratio(bvh, w["kernel_mrays_per_s"] if w else None)])
    out = ["Mrays/s, host arrays to host arrays:", "",
           table(["mesh", "rays", "query", "Embree rtcIntersect1", "kdrt cpu bvh", "GPU kd", "GPU bvh",
                  "GPU bvh / kd", "Warp", "GPU bvh / Warp"], rows)]
    if resident:
        out += ["Mrays/s, rays already in the GPU's memory (the query alone):", "",
                table(["mesh", "rays", "query", "GPU kd", "GPU bvh", "GPU bvh / kd", "Warp", "GPU bvh / Warp"],
                      resident)]
    failed = [w for w in (warp or {}).get("rows", []) if "error" in w]
    if failed:
        out += ["Warp rows not timed: " + "; ".join(f"{w['input']} {w.get('rays', '')} {w.get('query', '')} "
                                                      f"{w['constructor']}: {w['error']}" for w in failed) + "."]
    return out


def gpu_build_table(r, warp):
    """kdrt's builds on the host beside Embree's and Warp's on the GPU."""
    builds = []
    for x in r["trees"]:
        wb = sorted({(w["constructor"], w["build_ms"]) for w in (warp or {}).get("rows", [])
                     if w["input"] == x["input"] and "build_ms" in w})
        builds.append([x["input"], x.get("accel", "kd"), x["objects"], ms(x["build_ms"]), ms(x["embree_build_ms"]),
                       ", ".join(f"{c} {ms(b)}" for c, b in wb) if x.get("accel") == "bvh" else ""])
    return ["Builds: kdrt's on the host's cores (the GPU device uploads the same structure), Embree's medium "
            "build on the same cores, Warp's on the GPU (medians of 3):", "",
            table(["mesh", "kdrt structure", "triangles", "kdrt build ms", "Embree build ms", "Warp build ms"],
                  builds)]


# ---- f. accuracy against time --------------------------------------------------------------------

@section("f. Accuracy against time", "accuracy")
def accuracy(a):
    s = a["settings"]
    scenes = list(dict.fromkeys(r["scene"] for r in a["rows"]))
    devices = list(dict.fromkeys(r["device"] for r in a["rows"]))
    settings = list(dict.fromkeys(r["setting"] for r in a["rows"]))
    cell = {(r["scene"], r["device"], r["setting"]): r for r in a["rows"]}
    out = [f"{s['size']}x{s['size']}. Each setting changes one thing from the default (float, the watertight "
           "triangle test, the careful sphere test, the scale-aware self-intersection rule, the scene's depth, one "
           "sample); `all-cheap` takes the three cheap tests at once: " +
           "; ".join(f"`{k}` = `{' '.join(v) or '(none)'}`" for k, v in s["options"].items()) +
           f". The reference: the cpu device in double precision with the robust tests and {s['reference_samples']} "
           "samples per pixel. Each cell: render time against the default's on the same device (median of "
           f"{s['runs']} after a warm-up), then the RMSE of the displayed values against the reference; the share "
           "of camera rays that hit another object than the reference's is given where it is not 0. The scenes "
           "under hard/ are scenes/hard/: lens moved 1e5 away, insane shrunk by 1e-3, and a camera inside a "
           "closed 20480-triangle sphere.", ""]
    for d in devices:
        rows = []
        for st in settings:
            row = [st]
            for sc in scenes:
                r, base = cell.get((sc, d, st)), cell.get((sc, d, "default"))
                if not r:
                    row.append("-")
                    continue
                ids = f", ids {100 * r['ids_differ']:.2f} %" if r.get("ids_differ") else ""
                row.append(f"{ratio(r['render_ms'], base['render_ms'])}, {r['rmse']:.1e}{ids}")
            rows.append(row)
        out += [f"On `{d}` (the default's render ms: " +
                ", ".join(f"{sc} {ms(cell[sc, d, 'default']['render_ms'])}" for sc in scenes
                          if (sc, d, "default") in cell) + "):", "", table(["setting"] + scenes, rows)]
    if plot_accuracy(a, scenes, devices):
        out += ["![RMSE against render time per scene](bench/results/accuracy.png)", ""]
    return "\n".join(out)


def plot_accuracy(a, scenes, devices):
    """bench/results/accuracy.png: RMSE against render time, one panel per scene, one marker per device."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    cols = 4
    fig, axes = plt.subplots((len(scenes) + cols - 1) // cols, cols, figsize=(14, 3.4 * ((len(scenes) + cols - 1) // cols)),
                             squeeze=False)
    for ax, sc in zip(axes.flat, scenes):
        for d, marker in zip(devices, "os^D"):
            pts = [r for r in a["rows"] if r["scene"] == sc and r["device"] == d and r["rmse"] > 0]
            ax.scatter([r["render_ms"] for r in pts], [r["rmse"] for r in pts], marker=marker, label=d)
            if d == devices[0]:
                for r in pts:
                    ax.annotate(r["setting"], (r["render_ms"], r["rmse"]), fontsize=6)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(sc, fontsize=9)
        ax.set_xlabel("render ms", fontsize=8)
        ax.set_ylabel("RMSE", fontsize=8)
    for ax in list(axes.flat)[len(scenes):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "accuracy.png"), dpi=100)
    plt.close(fig)
    return True


# ---- g. several devices and ranks ----------------------------------------------------------------

@section("g. Several devices and ranks", "devices", "cluster")
def several(devices, cluster):
    out = []
    if devices:
        s = devices["settings"]
        alone = [r for r in devices["rows"] if r["tile"] is None]
        together = [r for r in devices["rows"] if r["tile"] is not None]
        names = list(dict.fromkeys(r["devices"] for r in alone))
        tiles = list(dict.fromkeys(r["tile"] for r in together))
        out += [f"One frame in tiles that each device pulls when it has finished one (`kdrt-render --device "
                f"{together[0]['devices'] if together else ','.join(names)} --tile N`) against each device alone, "
                f"{s['size']}, render ms, medians of {s['rounds']} rounds in turn; the share of the pixels each "
                "device took with the fastest tile size.", ""]
        rows = []
        for sc in dict.fromkeys(r["scene"] for r in devices["rows"]):
            by = {(r["devices"], r["tile"]): r for r in devices["rows"] if r["scene"] == sc}
            best_alone = min((by[n, None]["render_ms"] for n in names if (n, None) in by), default=None)
            best = min((r for r in together if r["scene"] == sc), key=lambda r: r["render_ms"], default=None)
            shares = ", ".join(f"{short(d)} {100 * v:.0f} %" for d, v in (best or {}).get("shares", {}).items())
            rows.append([sc] + [ms(by.get((n, None), {}).get("render_ms")) for n in names] +
                        [ms(by.get((together[0]["devices"], t), {}).get("render_ms")) for t in tiles] +
                        [ratio(best_alone, best["render_ms"] if best else None), shares])
        out += [table(["scene"] + [f"{n} alone" for n in names] + [f"together, {t}x{t}" for t in tiles] +
                      ["fastest alone / fastest together", "shares"], rows)]
    if cluster:
        s = cluster["settings"]
        out += [f"A cluster of {s['ranks']} ranks (`mpirun -np {s['ranks']} kdrt-render --threads "
                f"{max(1, s['threads'] // s['ranks'])}`) on this machine against one process with {s['threads']} "
                f"threads and against one rank with all of them (the same tiles: what tiling alone costs); "
                f"{s['size']}, medians of {s['rounds']} rounds in turn. Efficiency: one process's time over the "
                "cluster's, for the render and for the whole command (mpirun's start, loading, broadcast, writing).",
                ""]
        rows = []
        for r in cluster["rows"]:
            p, one, c = r["process"], r["one rank"], r["cluster"]
            rows.append([r["scene"], ms(p["render_ms"]), ms(one["render_ms"]), ms(c["render_ms"]),
                         ratio(p["render_ms"], c["render_ms"]), ratio(one["render_ms"], c["render_ms"]),
                         ms(p["wall_ms"]), ms(c["wall_ms"]), ratio(p["wall_ms"], c["wall_ms"]),
                         f"{ms(r['rank0']['broadcast_ms'])} ({r['rank0']['broadcast_bytes']} B)",
                         ms(r["rank0"]["assemble_ms"]), ms(r["rank0"]["receive_ms"]),
                         "/".join(str(n) for n in r["tiles_per_rank"])])
        out += [table(["scene", "1 process ms", "1 rank ms", "cluster ms", "efficiency (render)",
                       "1 rank / cluster", "1 process, whole ms", "cluster, whole ms", "efficiency (whole)",
                       "broadcast ms", "assemble ms", "receive ms", "tiles per rank"], rows)]
        if cluster["tiles"]:
            out += [f"Tile size on {s['tile_scene']}:", "",
                    table(["tile", "tiles", "cluster ms", "efficiency (render)"],
                          [[f"{t['tile']}x{t['tile']}", t["tiles"], ms(t["cluster_ms"]),
                            ratio(t["process_ms"], t["cluster_ms"])] for t in cluster["tiles"]])]
    return "\n".join(out)


# ---- h. Python ----------------------------------------------------------------------------------

@section("h. Python: kdrt.RaycastingScene against Open3D and trimesh", "python")
def python_queries(p):
    s = p["settings"]
    first = next(c for c in p["columns"] if c.startswith("kdrt"))
    out = [f"`bench/python_raycasting.py`: the same torus of {s['triangles']:,} triangles, {s['rays']:,} rays per "
           f"set and {s['points']:,} points in kdrt {s['kdrt']} (BVH), Open3D {s['open3d']} "
           f"(`open3d-cpu`, Embree inside) and trimesh {s['trimesh']} over embreex, {s['threads']} threads, "
           f"ms, medians of {s['repeats']} calls after a warm-up. The answers were compared first (ids on "
           "99.99 % of rays, t within 1e-5, equal counts and list sizes, distances within 1e-5 of the mesh's "
           "size). trimesh's closest hit and hit lists go through embreex's own Python loop.", ""]
    rows = [[r["query"]] + [ms(1000 * r[c]) if c in r else "-" for c in p["columns"]] +
            [ratio(1000 * r["Open3D"], 1000 * r[first])] for r in p["rows"]]
    out += [table(["query"] + [f"{c} ms" for c in p["columns"]] + [f"Open3D / {first}"], rows)]
    over = "; ".join(f"{k} rays {1000 * v['python_s']:.1f} ms against {1000 * v['cpp_s']:.1f} ms "
                     f"({100 * (v['python_s'] / v['cpp_s'] - 1):+.1f} %)" for k, v in p["overhead"].items())
    mem = ", ".join(f"{k} {v:.0f} MiB" for k, v in p["memory_mib"].items())
    out += [f"Python's overhead over the bare C++ `kdrt::intersect` on the same rays (alternated): {over}.", "",
            f"Memory one committed scene of this mesh adds to a process (resident, after its first query): {mem}.",
            ""]
    return "\n".join(out)


# ---- the document --------------------------------------------------------------------------------

def load(name):
    if name == "gpu":  # bench/opencl_device_tables.py's own summary
        path = os.path.join(RESULTS, "gpu", "summary.md")
        return open(path).read() if os.path.exists(path) else None
    return load_json(RESULTS, name)


def load_json(folder, name):
    """FOLDER/NAME.json, or None."""
    path = os.path.join(folder, name + ".json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def load_steps(folder):
    """FOLDER/steps.jsonl (benchlib.py step's records), or []."""
    path = os.path.join(folder, "steps.jsonl")
    return [json.loads(line) for line in open(path) if line.strip()] if os.path.exists(path) else []


def main():
    global RESULTS
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    RESULTS = sys.argv[1]
    results = {name: load(name) for name in ["machine"] + [n for _, names, _ in SECTIONS for n in names]}
    steps = load_steps(RESULTS)
    out = [header({k: v for k, v in results.items() if v is not None}, steps)]
    for title, names, f in SECTIONS:
        out.append(f"## {title}\n")
        args = [results[n] for n in names]
        if all(a is None for a in args) and names != ("gpu",):
            out.append("Not measured in this run: " + ", ".join(f"bench/results/{n}.json" for n in names) +
                       " (bench/run_all.sh's output says why).\n")
            continue
        out.append(f(*args))
        missing = [n for n, a in zip(names, args) if a is None and n != "gpu"]
        if missing:
            out.append("Not measured in this run: " + ", ".join(f"bench/results/{n}.json" for n in missing) + ".\n")
    out.append("## Tried and dropped\n")
    out.append(read_text("tried-and-dropped.md"))
    sys.stdout.write("\n".join(out))


if __name__ == "__main__":
    main()
