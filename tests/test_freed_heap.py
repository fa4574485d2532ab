"""A run's process keeps the heap its arrays free (gearlab.memo.keep_freed_heap): glibc mapped each temporary of a
few MB afresh and the kernel zeroed its pages, 1,900 page faults a call of a gap fit's waveform features of 80
revolutions of 4096 points (three quarters of its CPU). Counted in page faults, in a process of its own (the setting
is the process's)."""

import subprocess
import sys

import pytest

FAULTS = """
import resource, numpy as np
from gearlab.gap.views import waveform_view
from gearlab.memo import keep_freed_heap
keep_freed_heap()
X = np.random.default_rng(1).standard_normal((80, 4096))
waveform_view(X)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    waveform_view(X)
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 20)
"""


@pytest.mark.skipif(sys.platform != "linux", reason="glibc's mallopt")
def test_a_kept_heap_gives_the_next_arrays_the_pages_of_the_last():
    out = subprocess.run([sys.executable, "-c", FAULTS], capture_output=True, text=True, check=True)
    assert float(out.stdout) < 100  # 1,888 a call where each array was mapped afresh
