"""Shared helpers of the benchmark scripts: machine description, JSON output, and runs of a
checkout's code in a fresh process."""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np

import ndpack as nd


def cpu_model() -> str:
    """The CPU model name from /proc/cpuinfo, else platform.processor()."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info() -> dict:
    return {
        "date": _dt.date.today().isoformat(),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu_model": cpu_model(),
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "ndpack": getattr(nd, "__version__", "unknown"),
        "loadavg_at_start": load_average(),
    }


def load_average() -> list | None:
    """1, 5 and 15 minute load averages (other processes sharing the cores skew timings)."""
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def run_with(checkout, argv: list[str], env: dict | None = None, timeout: float | None = None):
    """``python ARGV`` in a fresh process whose ``ndpack`` is ``checkout``'s: it is first on the path
    (before the caller's, which may hold dependencies) and the working folder (``-c`` puts that
    first). ``env`` adds to (or, with None values, removes from) this process's environment.
    Returns the finished process (text output)."""
    environment = {**os.environ}
    for name, value in (env or {}).items():
        if value is None:
            environment.pop(name, None)
        else:
            environment[name] = value
    environment["PYTHONPATH"] = os.pathsep.join(filter(None, [str(checkout), os.environ.get("PYTHONPATH")]))
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True, env=environment, cwd=str(checkout),
                          timeout=timeout)


def last_json(done) -> dict:
    """The last line a finished process (:func:`run_with`) printed, as JSON; its error where it failed."""
    if done.returncode:
        raise RuntimeError(done.stderr[-3000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def write_json(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as fh:
        json.dump(data, fh, indent=2, default=_to_builtin)
        fh.write("\n")


def _to_builtin(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")
