"""CPU time and peak memory of a command and its finished workers
(``experiments.usage``), against what a child process was made to spend."""

import subprocess
import sys

from kalman_vs_infoset.experiments import usage

# a child that burns CPU for ~0.3 s of its own time and holds ~200 MB for a moment
_CHILD = """
import time
t = time.process_time()
while time.process_time() - t < 0.3:
    pass
block = bytearray(200 * 1024 * 1024)
block[::4096] = b"x" * len(block[::4096])
"""


def test_a_finished_childs_cpu_time_and_peak_memory_are_counted():
    before = usage.cpu_s()
    subprocess.run([sys.executable, "-c", _CHILD], check=True, timeout=120)
    spent = usage.cpu_s() - before
    assert spent >= 0.3  # the child's busy loop, counted once it was waited for
    assert usage.peak_rss_mb(children=True) >= 200.0  # the child's 200 MB block
    assert 1.0 < usage.peak_rss_mb() < 1e5  # this process's own peak (MB, not kB)
