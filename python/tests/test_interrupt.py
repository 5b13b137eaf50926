"""ctrl-c during a long Problem.evaluate: the batch is evaluated in parts with Python's
signal handlers run between them, so KeyboardInterrupt comes within a part's time (about
a quarter of a second), not when the whole batch is done (a minute and more here)."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

from conftest import BOTTLE

SCRIPT = """
import sys, time
import gripopt
p = gripopt.Problem.load(sys.argv[1])
x = p.bounds.sample(int(sys.argv[2]), seed=3)
print("ready", flush=True)
t = time.monotonic()
try:
    p.evaluate(x)
except KeyboardInterrupt:
    print(f"interrupted after {time.monotonic() - t:.2f} s", flush=True)
    sys.exit(0)
print("finished", flush=True)
"""


def test_ctrl_c_interrupts_a_long_evaluate():
    # a million random designs, a fifth of them simulated: about 3 minutes of a core's
    # work (18 s for 200 000 on 2 cores), so tens of seconds even on many cores
    proc = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(BOTTLE), "1000000"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(1.0)  # inside the batch
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail("Problem.evaluate went on for 30 s after SIGINT (the batch would take minutes)")
    waited = time.monotonic() - sent
    assert proc.returncode == 0, err
    assert out.startswith("interrupted after"), out + err
    assert waited < 5, f"KeyboardInterrupt {waited:.1f} s after SIGINT"
