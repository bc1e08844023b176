#!/usr/bin/env python3
"""What the bench scripts share: whole processes timed with their peak memory,
kdrt-render's --stats-json, medians, result files, and the machine's record.
Run as a program, it is bench/run_all.sh's step runner:

  bench/benchlib.py machine OUT KDRT_RENDER   writes OUT/machine.json
  bench/benchlib.py step OUT NAME -- CMD      runs CMD, then appends to OUT/steps.jsonl how long it
                                              took and how busy other processes kept the machine
"""
import datetime
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STUDY_SCENES = ["2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"]


def now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def scene_path(name):
    """A scene file as given, else scenes/NAME.json."""
    return name if os.path.isfile(name) else os.path.join(ROOT, "scenes", name + ".json")


def run(cmd, env=None):
    """Runs a command to its end: {"stdout", "wall_ms", "peak_rss_mib", "cpu_s"} (the child's own, from
    wait4). Raises RuntimeError with the end of its stderr when it fails."""
    with tempfile.TemporaryFile() as err:
        start = time.monotonic()
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, env=env)
        out = p.stdout.read()
        _, status, usage = os.wait4(p.pid, 0)
        wall_ms = (time.monotonic() - start) * 1000.0
        p.stdout.close()
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode != 0:
            err.seek(0)
            raise RuntimeError(f"{' '.join(cmd)}: exit {p.returncode}: {err.read().decode(errors='replace')[-500:]}")
    return {"stdout": out.decode(), "wall_ms": wall_ms, "peak_rss_mib": usage.ru_maxrss / 1024.0,
            "cpu_s": usage.ru_utime + usage.ru_stime}


def render(kdrt_render, scene, args=(), env=None):
    """One kdrt-render process with --stats-json: its statistics, with the process's wall_ms,
    peak_rss_mib and cpu_s added as process_ms, process_rss_mib, process_cpu_s."""
    r = run([kdrt_render, scene_path(scene), "--stats-json", "-q", *args], env)
    stats = json.loads(r["stdout"].strip().splitlines()[-1])
    stats.update(process_ms=r["wall_ms"], process_rss_mib=r["peak_rss_mib"], process_cpu_s=r["cpu_s"])
    return stats


def in_turn(configs, rounds, measure):
    """Calls measure(config) for every config, rounds times, in turn (A B, then B A, ...) so that
    a change in the machine's load hits all alike and no config always goes first.
    Returns {config: [results]}."""
    results = {c: [] for c in configs}
    for r in range(rounds):
        for c in configs if r % 2 == 0 else configs[::-1]:
            results[c].append(measure(c))
    return results


def write_result(out, name, command, data):
    """OUT/NAME.json: the command, the time it ran, and the data."""
    os.makedirs(out, exist_ok=True)
    result = {"command": command, "finished": now(), **data}
    with open(os.path.join(out, name + ".json"), "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")
    print(f"{sys.argv[0]}: wrote {os.path.join(out, name + '.json')}", file=sys.stderr)


def output_of(cmd, containing=""):
    """The first line of a command's output that contains `containing`, or None."""
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return next((line for line in (done.stdout + done.stderr).splitlines() if containing in line), None)


def checkout():
    """The commit measured, its date, and whether the checkout held changes besides the results a run
    rewrites. A copy without .git (one carried to a machine lent with a GPU) is described by
    KDRT_COMMIT, KDRT_COMMIT_DATE and KDRT_UNCOMMITTED=1."""
    if os.environ.get("KDRT_COMMIT"):
        return {"commit": os.environ["KDRT_COMMIT"], "commit_date": os.environ.get("KDRT_COMMIT_DATE"),
                "uncommitted_changes": os.environ.get("KDRT_UNCOMMITTED") == "1"}
    try:
        status = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                 ":!bench/results"], capture_output=True, text=True).stdout.strip()
    except OSError:  # no git
        status = ""
    return {"commit": output_of(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"]),
            "commit_date": output_of(["git", "-C", ROOT, "log", "-1", "--format=%cI"]),
            "uncommitted_changes": bool(status)}


def machine_record(kdrt_render):
    """The machine, the software and the commit: what BENCHMARKS.md's first section says."""
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "?")
    mem_kib = next(int(line.split()[1]) for line in open("/proc/meminfo") if line.startswith("MemTotal"))
    os_name = next((line.split("=", 1)[1].strip().strip('"') for line in open("/etc/os-release")
                    if line.startswith("PRETTY_NAME")), platform.system())
    try:
        import matplotlib
        mpl = matplotlib.__version__
    except ImportError:
        mpl = None
    return {
        "date": now(),
        "cpu": cpu,
        "logical_cpus": os.cpu_count(),
        "memory_gib": round(mem_kib / 1024 / 1024, 1),
        "os": f"{os_name}, Linux {platform.release()} {platform.machine()}",
        **checkout(),
        "devices": subprocess.run([kdrt_render, "--list-devices"], capture_output=True, text=True).stdout.splitlines(),
        "compiler": output_of(["c++", "--version"]),
        "kdrt": output_of([kdrt_render, "--version"]),
        "povray": output_of(["povray", "--version"], "POV-Ray"),
        "mpirun": output_of(["mpirun", "--version"]),
        "python": platform.python_version(),
        "matplotlib": mpl,
    }


def cpu_busy_s():
    """CPU seconds all processes have spent so far (/proc/stat: user, nice, system, irq, softirq, steal)."""
    fields = open("/proc/stat").readline().split()[1:]
    ticks = sum(int(fields[i]) for i in (0, 1, 2, 5, 6, 7))
    return ticks / os.sysconf("SC_CLK_TCK")


def step(out, name, cmd):
    """Runs one step of run_all.sh; records its time, the load averages before and after, and the
    cores others kept busy meanwhile (all busy CPU time minus the step's own, over its wall time)."""
    load = lambda: open("/proc/loadavg").read().split()[0]
    record = {"step": name, "command": " ".join(cmd), "started": now(), "load_before": float(load()),
              **{k: v for k, v in checkout().items() if k != "commit_date"}}
    print(f"== {record['started']} load {record['load_before']}: {name}: {record['command']}", file=sys.stderr)
    busy, ours = cpu_busy_s(), resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    rc = subprocess.run(cmd).returncode
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    ours_s = after.ru_utime + after.ru_stime - ours.ru_utime - ours.ru_stime
    record.update(wall_s=round(wall, 1), exit=rc, load_after=float(load()),
                  others_cores=round(max(0.0, (cpu_busy_s() - busy - ours_s) / max(wall, 1e-3)), 2))
    # A step run again replaces its earlier record: the file lists what the results are.
    path = os.path.join(out, "steps.jsonl")
    kept = [line for line in (open(path).read().splitlines() if os.path.exists(path) else [])
            if line.strip() and json.loads(line).get("step") != name]
    with open(path, "w") as f:
        f.write("".join(line + "\n" for line in kept) + json.dumps(record) + "\n")
    print(f"== {now()} load {record['load_after']}: {name} {'done' if rc == 0 else f'FAILED ({rc})'} in "
          f"{record['wall_s']} s; others kept {record['others_cores']} cores busy", file=sys.stderr)
    return rc


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "machine":
        write_result(sys.argv[2], "machine", "bench/benchlib.py machine", machine_record(sys.argv[3]))
        return 0
    if len(sys.argv) > 5 and sys.argv[1] == "step" and sys.argv[4] == "--":
        return step(sys.argv[2], sys.argv[3], sys.argv[5:])
    sys.exit(__doc__)


if __name__ == "__main__":
    sys.exit(main())
