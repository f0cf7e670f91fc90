#!/usr/bin/env python3
"""Records one timed fuzzing run (fuzz/run.sh) in docs/fuzzing/results.json, or renders the
results into the table of docs/fuzzing.md (between its <!-- results --> markers).

  record_run.py RESULTS TARGET SECONDS EXIT CORPUS_BEFORE CORPUS_AFTER ARTIFACTS LOG
  record_run.py --render RESULTS FUZZING_MD
"""
import datetime
import json
import os
import platform
import re
import subprocess
import sys


def machine():
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def clang_version():
    try:
        out = subprocess.run(["clang++-14", "--version"], capture_output=True, text=True).stdout
        return out.splitlines()[0]
    except (OSError, IndexError):
        return "unknown"


def parse_log(path):
    stats = {}
    with open(path, errors="replace") as f:
        text = f.read()
    for key in ("number_of_executed_units", "average_exec_per_sec", "peak_rss_mb"):
        m = re.search(rf"stat::{key}:\s+(\d+)", text)
        stats[key] = int(m.group(1)) if m else None
    cov = re.findall(r"cov: (\d+) ft: (\d+)", text)
    stats["cov"], stats["ft"] = (int(cov[-1][0]), int(cov[-1][1])) if cov else (None, None)
    return stats


def record(results_path, target, seconds, status, before, after, artifacts, log):
    results = {"runs": []}
    if os.path.exists(results_path):
        with open(results_path) as f:
            results = json.load(f)
    s = parse_log(log)
    results["runs"].append({
        "target": target,
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "seconds": int(seconds),
        "exit_status": int(status),
        "executions": s["number_of_executed_units"],
        "executions_per_s": s["average_exec_per_sec"],
        "peak_rss_mb": s["peak_rss_mb"],
        "edges_covered": s["cov"],
        "features": s["ft"],
        "corpus_before": int(before),
        "corpus_after": int(after),
        "failures": int(artifacts),
        "compiler": clang_version(),
        "machine": machine(),
    })
    os.makedirs(os.path.dirname(results_path), exist_ok=True)
    with open(results_path, "w") as f:
        json.dump(results, f, indent=1)
        f.write("\n")


def render(results_path, md_path):
    with open(results_path) as f:
        runs = json.load(f)["runs"]
    rows = ["| target | minutes in all (clean runs) | last run | executions (last) | exec/s | edges | corpus files | failures found (all runs) |",
            "|---|---|---|---|---|---|---|---|"]
    for target in sorted({r["target"] for r in runs}):
        mine = [r for r in runs if r["target"] == target]
        last = mine[-1]
        clean = sum(r["seconds"] for r in mine if r["exit_status"] == 0) / 60
        rows.append(f"| {target} | {clean:.0f} | {last['date']} | {last['executions']} | "
                    f"{last['executions_per_s']} | {last['edges_covered']} | {last['corpus_before']} -> "
                    f"{last['corpus_after']} | {sum(r['failures'] for r in mine)} |")
    machines = sorted({r["machine"] for r in runs})
    compilers = sorted({r["compiler"] for r in runs})
    table = "\n".join(rows) + f"\n\nMachine: {'; '.join(machines)}. Compiler: {'; '.join(compilers)}.\n"
    with open(md_path) as f:
        md = f.read()
    md = re.sub(r"(<!-- results -->\n).*?(<!-- /results -->)", lambda m: m.group(1) + table + m.group(2), md,
                flags=re.S)
    with open(md_path, "w") as f:
        f.write(md)


if __name__ == "__main__":
    if sys.argv[1] == "--render":
        render(sys.argv[2], sys.argv[3])
    else:
        record(*sys.argv[1:9])
