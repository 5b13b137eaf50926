"""Run the Python block of docs/python.md on a run folder written by the tests.

Usage: python tools/check_python_docs.py RUN_DIR GRIPOPT_BINARY
Fails (exit 1) when the block raises, the front is empty or the trajectory has no rows.
"""
import os
import re
import sys
import tempfile

run, gripopt = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
doc = os.path.join(os.path.dirname(__file__), "..", "docs", "python.md")
blocks = re.findall(r"```python\n(.*?)```", open(doc).read(), re.S)
if len(blocks) != 1:
    sys.exit(f"{doc}: expected one python block, found {len(blocks)}")
scope = {"RUN": run, "GRIPOPT": gripopt}
with tempfile.TemporaryDirectory() as d:
    os.chdir(d)
    exec(compile(blocks[0], doc, "exec"), scope)
front, traj = scope["front"], scope["traj"]
assert len(front) > 0, "empty front"
assert list(front.columns[:2]) == ["id", "generation"], list(front.columns)
assert front["mean_force"].is_monotonic_decreasing
assert len(traj) > 10 and traj["t"].is_monotonic_increasing, "trajectory"
print(f"docs/python.md: {len(front)} front designs, {len(traj)} trajectory samples: ok")
