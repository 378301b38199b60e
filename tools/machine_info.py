"""The machine a measurement ran on, for the data files of tools/make_results.py and
tools/make_tuning_doc.py, and the CPU time of the programs a benchmark script ran. Standard library
only."""
import os
import pathlib
import platform
import resource
import subprocess

ROOT = pathlib.Path(__file__).resolve().parent.parent


def machine():
    """CPU model, logical cores, kernel and the leeway commit, in one line."""
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    return f"{model}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}; leeway commit {commit}"


def cpu_of_children():
    """User plus system CPU time [s] of the finished child processes so far (take differences)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime
