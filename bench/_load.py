"""A busy machine on demand: ``with busy(2): ...`` runs two spinning Python processes beside the
block and stops them after (the shared 2-core machine of issue 47, made repeatable)."""

from __future__ import annotations

import contextlib
import signal
import subprocess
import sys

#: A process that keeps one core busy: pure Python, no threads, no memory traffic to speak of.
SPIN = "while True:\n    pass\n"


@contextlib.contextmanager
def busy(processes: int):
    """Run ``processes`` spinning processes while the block runs (none for 0)."""
    def stop(signum, frame):  # a kill (SIGTERM) of the benchmark stops them too
        raise SystemExit(128 + signum)

    previous = signal.signal(signal.SIGTERM, stop)
    started = [subprocess.Popen([sys.executable, "-c", SPIN], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for _ in range(processes)]
    try:
        yield started
    finally:
        for process in started:  # only the ones started here, each by its own handle
            process.kill()
        for process in started:
            process.wait()
        signal.signal(signal.SIGTERM, previous)
