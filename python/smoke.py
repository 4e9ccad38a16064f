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

# a study of the shipped manifest (checks only): the table returned is the one written
import csv
import json

study_out = tempfile.mkdtemp() + "/study"
table = footfall.study("tests/data/study/clock_edit.csv", out=study_out, quiet=True)
with open(study_out + "/study.csv", newline="") as f:
    rows = list(csv.DictReader(f))
assert list(table["id"]) == [r["id"] for r in rows], table["id"]
assert list(table["status"]) == ["done"] * len(rows), table["status"]
clock = np.asarray(table["clock_right"], dtype=float)
assert np.array_equal(clock, [float(r["clock_right"]) for r in rows]), clock
print(f"python binding: a study of {len(rows)} trials, right plate's clock {np.round(clock * 1e3, 2)} ms")

# the measurement check of an edit with its truth beside it: the right plate's clock 20 ms
# late, read against the untouched recording; the joint torques are the run folder's
edit = "tests/data/check/trials/opencap_s4_walking1/clock_r+20ms"
with open(edit + "/truth.json") as f:
    truth = json.load(f)
checked = footfall.check(edit + "/trial.csv", model="models/opencap_s4.json",
                         out=tempfile.mkdtemp() + "/check", quiet=True)
untouched = footfall.check("data/opencap_s4_walking1_sagittal.csv", model="models/opencap_s4.json",
                           out=tempfile.mkdtemp() + "/check", quiet=True)
assert truth["effect"] in checked["found"], checked["found"]
reading = {r["effect"]: r for r in checked["readings"]}[truth["effect"]]
base = {r["effect"]: r for r in untouched["readings"]}[truth["effect"]]
read = reading["estimate"] - base["estimate"]
assert abs(read - truth["value"]) <= max(0.2 * abs(truth["value"]), 2 * reading["sd"]), read
torques, powers = checked["joint_torques"], checked["joint_powers"]
assert torques.shape == powers.shape == (len(checked["torque_time"]), 6)
assert np.all(np.isfinite(torques)) and np.all(np.isfinite(powers))
written = np.loadtxt(checked["run_folder"] + "/joint_torques.csv", delimiter=",", skiprows=1)
assert np.array_equal(written[:, 1:], torques), "joint_torques.csv differs from the binding's"
print(f"python binding: check read the right plate's clock {read * 1e3:+.2f} ms (edit {truth['value'] * 1e3:+.0f} ms)")

# bad input: an error naming what is wrong, raised as a Python exception
for call, kind, words in [
    (lambda: footfall.check("tests/data/no_such_trial.csv", out=tempfile.mkdtemp() + "/c", quiet=True),
     RuntimeError, "no_such_trial.csv"),
    (lambda: footfall.check(cutoff=-1.0, out=tempfile.mkdtemp() + "/c", quiet=True), ValueError, "cutoff"),
]:
    try:
        call()
    except kind as e:
        assert words in str(e), e
    else:
        raise AssertionError(f"no {kind.__name__} naming {words}")
print("python binding: bad input to check raises an error naming it")
