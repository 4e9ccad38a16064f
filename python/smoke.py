"""CI smoke test of the Python binding: re-evaluate the bundled trial's kept ellipse
tracking solution without iterating, and check what comes back. Run from the repository
root (the bundled model and trial are found relative to it)."""
import tempfile

import footfall
import numpy as np

out = tempfile.mkdtemp() + "/run"
run = footfall.track(foot="ellipse", out=out, init="tests/data/hidden/base",
                     max_iter=0, check_points=False, quiet=True)
assert run["converged"], run["status"]
assert abs(run["objective"] - 7.896) < 0.01, run["objective"]
# the kept solution lets the ground pull the left foot between two nodes (`docs/method.md`,
# "Physically valid between the nodes")
assert run["physically_valid"] is False, run["physically_valid"]
states, time = run["states"], run["time"]
assert isinstance(states, np.ndarray) and states.shape == (len(time), len(run["state_names"]))
assert np.all(np.diff(time) > 0) and np.all(np.isfinite(states))
print(f"python binding: {run['status']}, J = {run['objective']:.4f}, states {states.shape}")
