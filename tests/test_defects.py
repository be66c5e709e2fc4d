"""Regression tests of the defects found by trying the package as a new user and as a
tester would. Each failed on the code before the fix.

"One line" = one line on stderr, exit status 2, no traceback, nothing half-written.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from harness_texts import SHORT as SHORT_ENGAGEMENT
from harness_texts import TINY_RW, Result, experiment, one_line_error
from harness_texts import run_cli as run
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]

SHORT = SHORT_ENGAGEMENT + experiment(runs=2)


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in Path(path).rglob("*") if p.is_file())


@pytest.fixture
def short(tmp_path) -> Path:
    p = tmp_path / "short.toml"
    p.write_text(SHORT)
    return p


def _intercept(capsys, scenario, out, *extra) -> Result:
    return run(capsys, "intercept", scenario, "--out", out, "--workers", 1, "--no-progress", *extra)


def _parquet(out: Path) -> Path:
    (pq,) = [p for p in files_under(out) if p.suffix == ".parquet"]
    return pq


# -- a ------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["intercept", "attitude"])
def test_a_non_utf8_scenario_is_refused_in_one_line(tmp_path, capsys, command):
    p = tmp_path / "latin1.toml"
    p.write_bytes('name = "caf\xe9"\n'.encode("latin-1"))
    r = run(capsys, command, p, "--out", tmp_path / "out")
    assert one_line_error(r), r.stderr
    assert "latin1.toml" in r.stderr and "UTF-8" in r.stderr


# -- b ------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", ["18446744073709551616", "9223372036854775808"])
def test_b_seed_beyond_64_bits_is_refused_before_any_run(short, tmp_path, capsys, seed):
    out = tmp_path / "out"
    r = _intercept(capsys, short, out, "--runs", 1, "--seed", seed)
    assert one_line_error(r), r.stderr
    assert files_under(out) == []


def test_b_attitude_seed_beyond_64_bits_is_refused(tiny_rw, tmp_path, capsys):
    out = tmp_path / "out"
    r = run(capsys, "attitude", tiny_rw, "--seed", "18446744073709551616", "--out", out)
    assert one_line_error(r), r.stderr
    assert files_under(out) == []


# -- c ------------------------------------------------------------------------------
def test_c_scheduler_that_is_not_an_address_is_one_line(short, tmp_path, capsys):
    pytest.importorskip("distributed")
    r = _intercept(capsys, short, tmp_path / "out", "--runs", 1, "--scheduler", "notanaddress")
    assert one_line_error(r), r.stderr
    assert "notanaddress" in r.stderr


# -- d ------------------------------------------------------------------------------
def test_d_more_sections_than_the_set_may_hold_is_refused_at_load(short, tmp_path, capsys):
    out = tmp_path / "out"
    r = _intercept(capsys, short, out, "--runs", 1, "--set", "estimator.infoset.n_sections=129")
    assert one_line_error(r), r.stderr
    assert "n_sections" in r.stderr


# -- e ------------------------------------------------------------------------------
def test_e_attitude_run_too_long_to_allocate_is_refused_at_load(tiny_rw, tmp_path, capsys):
    text = TINY_RW.replace("duration_s = 5.0", "duration_s = 1e5").replace(
        "control_period_s = 0.05", "control_period_s = 1e-4"
    )
    p = tmp_path / "huge.toml"
    p.write_text(text)
    r = run(capsys, "attitude", p, "--out", tmp_path / "out")
    assert one_line_error(r), r.stderr
    assert "huge.toml" in r.stderr and "simulation." in r.stderr


def test_e_a_failed_attitude_run_reports_its_error(tiny_rw, tmp_path, capsys, monkeypatch):
    from kalman_vs_infoset.guidance.attitude import pd as pd_law

    def broken(self, x):
        raise ArithmeticError("broken law for the test")

    monkeypatch.setattr(pd_law.QuaternionPD, "torque", broken)
    out = tmp_path / "out"
    r = run(capsys, "attitude", tiny_rw, "--out", out, "--json")
    assert r.returncode == 1, r.stderr  # a command with failed runs exits 1
    assert "1 run failed" in r.stderr.strip().splitlines()[-1]
    assert json.loads(r.stdout.strip().splitlines()[-1])["failures"] == 1
    assert "broken law for the test" in r.stderr  # said, not swallowed
    df = pd.read_parquet(_parquet(out))
    assert list(df["status"]) == ["failed"] and "broken law" in df["error"][0]


# -- f ------------------------------------------------------------------------------
def test_f_intercept_with_too_many_steps_is_refused_at_load(tmp_path, capsys):
    text = (
        SHORT.replace("[model]\n", "[model]\ndt_s = 0.01\n")
        # the bearing bound's line reaching past the far range: the steps are at fault
        .replace("nominal_range_km = 1000.0", "nominal_range_km = 1e6")
        .replace("x_km = [900.0, 1100.0]", "x_km = [9e5, 1e6]\nvx_kmps = [-2.0, -0.5]")
        .replace("x_km = [950.0, 1050.0]", "x_km = [9.5e5, 9.6e5]")
        .replace("vx_kmps = [-58.1, -57.9]", "vx_kmps = [-1.0, -1.0]")
        # the a-priori interval must hold the truth's closing speed (1 km/s)
        .replace("closing_speed_kmps = [57.9, 58.1]", "closing_speed_kmps = [0.5, 2.0]")
    )
    p = tmp_path / "slow.toml"
    p.write_text(text)
    r = _intercept(capsys, p, tmp_path / "out", "--runs", 1)
    assert one_line_error(r), r.stderr
    assert "slow.toml" in r.stderr and "steps" in r.stderr


# -- g ------------------------------------------------------------------------------
def _children(pid: int) -> set[int]:
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.add(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_g_pool_workers_exit_when_the_main_process_is_killed(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "kalman_vs_infoset", "intercept",
         ROOT / "data/scenarios/kp_fig5.toml",
         "--runs", "400", "--workers", "2", "--no-progress", "--out", tmp_path / "out"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        workers: set[int] = set()
        while time.monotonic() < deadline and len(workers) < 2:
            time.sleep(0.2)
            workers = {p for p in _children(proc.pid) if _alive(p)}
        assert len(workers) >= 2, "the pool never started"
        time.sleep(1.0)  # the workers are running engagements
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and any(_alive(p) for p in workers):
            time.sleep(0.2)
        left = [p for p in workers if _alive(p)]
    finally:
        for p in _children(proc.pid) | locals().get("workers", set()):
            if _alive(p):
                os.kill(p, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()
    assert left == [], f"orphaned workers {left}"


# -- h ------------------------------------------------------------------------------
def test_h_the_same_scenario_under_another_path_spelling_resumes(
    short, tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    for spelling in ("short.toml", "./short.toml", str(short)):
        r = _intercept(capsys, spelling, out, "--runs", 1)
        assert r.returncode == 0, r.stderr


# -- i ------------------------------------------------------------------------------
def test_i_a_smaller_runs_never_deletes_finished_runs(short, tmp_path, capsys):
    out = tmp_path / "out"
    assert _intercept(capsys, short, out, "--runs", 3).returncode == 0
    pq = _parquet(out)
    df = pd.read_parquet(pq)
    df[df["run"] != 1].to_parquet(pq, index=False)  # an interruption left a gap at run 1
    r = _intercept(capsys, short, out, "--runs", 2)
    assert r.returncode == 0, r.stderr
    assert sorted(pd.read_parquet(pq)["run"]) == [0, 1, 2]


# -- j ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "args",
    [
        ["compare", "--estimators", "infoset,infoset"],
        ["compare", "--noise", "random,random"],
        ["sweep", "--estimators", "infoset", "--key", "model.nu_mps2", "--values", "[0.5, 0.5]"],
    ],
)
def test_j_duplicates_are_refused(short, tmp_path, capsys, args):
    out = tmp_path / "out"
    r = run(capsys, args[0], short, *args[1:], "--runs", 1, "--out", out, "--no-progress")
    assert one_line_error(r), r.stderr
    assert files_under(out) == []


# -- k ------------------------------------------------------------------------------
def test_k_attitude_results_of_two_seeds_live_side_by_side(tiny_rw, tmp_path, capsys):
    """(Seed 1's single run untraced with ``--trace none``: one history figure fewer,
    and the option's own check: a single run is traced by default.)"""
    out = tmp_path / "out"
    for seed, trace in ((1, ["--trace", "none"]), (2, [])):
        r = run(capsys, "attitude", tiny_rw, "--seed", seed, "--out", out, "--noise", "random",
                *trace)  # fmt: skip
        assert r.returncode == 0, r.stderr
    # the run tables (a single run is also traced: its history lies beside its table)
    tables = [pd.read_parquet(p) for p in files_under(out)
              if p.suffix == ".parquet" and not p.name.endswith("-trace.parquet")]  # fmt: skip
    assert sorted(int(s) for df in tables for s in df["seed"]) == [1, 2]
    traced = [p.name for p in files_under(out) if p.name.endswith("-trace.parquet")]
    assert len(traced) == 1 and traced[0].endswith("-s2-trace.parquet"), traced


# -- l ------------------------------------------------------------------------------
def test_l_a_foreign_parquet_beside_a_valid_json_is_refused(short, tmp_path, capsys):
    out = tmp_path / "out"
    assert _intercept(capsys, short, out, "--runs", 1).returncode == 0
    pq = _parquet(out)
    pd.DataFrame({"something": [1.0, 2.0]}).to_parquet(pq, index=False)
    r = _intercept(capsys, short, out, "--runs", 1)
    assert one_line_error(r), r.stderr
    assert pq.name in r.stderr


# -- m ------------------------------------------------------------------------------
def test_m_failed_attitude_runs_keep_the_seed_indices(tiny_rw, tmp_path, capsys, monkeypatch):
    from kalman_vs_infoset.guidance.attitude import pd as pd_law

    p = tmp_path / "random_start.toml"
    p.write_text(TINY_RW.replace("angle_deg = 10.0", "random_attitude = true"))
    # run 1 starts from the first draw of its own generator
    rng1 = np.random.default_rng(np.random.SeedSequence(4, spawn_key=(1,)))
    q1 = Rotation.random(rng=rng1).as_quat()
    original = pd_law.QuaternionPD.torque

    def fails_on_run_1(self, x):
        x = np.asarray(x)
        if np.any(np.all(np.isclose(x[..., 0:4], q1, rtol=0, atol=1e-12), axis=-1)):
            raise ArithmeticError("run 1 fails")
        return original(self, x)

    monkeypatch.setattr(pd_law.QuaternionPD, "torque", fails_on_run_1)
    out = tmp_path / "out"
    r = run(capsys, "attitude", p, "--runs", 3, "--seed", 4, "--out", out, "--json")
    assert r.returncode == 1, r.stderr  # a command with failed runs exits 1
    df = pd.read_parquet(_parquet(out))
    assert sorted(df.loc[df["status"] == "ok", "run"]) == [0, 2]
    assert list(df.loc[df["status"] != "ok", "run"]) == [1]


# -- n ------------------------------------------------------------------------------
def test_n_data_files_respect_the_umask(short, tiny_rw, tmp_path, capsys):
    old = os.umask(0o022)
    try:
        assert _intercept(capsys, short, tmp_path / "i", "--runs", 1).returncode == 0
        assert run(capsys, "attitude", tiny_rw, "--out", tmp_path / "a").returncode == 0
        r = run(capsys, "compare", short, "--estimators", "infoset", "--noise", "random",
                "--runs", 1, "--out", tmp_path / "c", "--no-progress", "--workers", 1)  # fmt: skip
        assert r.returncode == 0, r.stderr
    finally:
        os.umask(old)
    written = [p for p in files_under(tmp_path) if p.parent != tmp_path]
    modes = {p.name: oct(p.stat().st_mode & 0o777) for p in written}
    assert set(modes.values()) == {"0o644"}, modes


# -- o: see tests/conftest.py (no test module may write to the repository's results/) --


# -- p ------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["intercept", "attitude"])
def test_p_an_empty_scenario_file_is_refused(tmp_path, capsys, command):
    p = tmp_path / "empty.toml"
    p.write_text("# nothing here\n")
    out = tmp_path / "out"
    r = run(capsys, command, p, "--runs", 1, "--out", out)
    assert one_line_error(r), r.stderr
    assert "empty.toml" in r.stderr and "empty" in r.stderr.replace("empty.toml", "")
    assert files_under(out) == []


# -- q ------------------------------------------------------------------------------
def test_q_a_truncated_results_file_is_refused_with_the_remedy(short, tmp_path, capsys):
    out = tmp_path / "out"
    assert _intercept(capsys, short, out, "--runs", 1).returncode == 0
    pq = _parquet(out)
    pq.write_bytes(pq.read_bytes()[: pq.stat().st_size // 2])
    r = _intercept(capsys, short, out, "--runs", 1)
    assert one_line_error(r), r.stderr
    assert str(pq) in r.stderr and "delete" in r.stderr


# -- r ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["../../../escaped", "a/b", "..", ".hidden", "x\\y"])
def test_r_a_scenario_name_cannot_write_outside_out(tmp_path, capsys, name):
    p = tmp_path / "evil.toml"
    p.write_text(SHORT.replace('name = "short"', f"name = {json.dumps(name)}"))
    out = tmp_path / "a" / "b" / "out"
    r = _intercept(capsys, p, out, "--runs", 1)
    assert one_line_error(r), r.stderr
    assert "name" in r.stderr
    assert [f for f in files_under(tmp_path) if f != p] == []


def test_r_attitude_scenario_name_is_checked_too(tmp_path, capsys):
    p = tmp_path / "evil.toml"
    p.write_text(TINY_RW.replace('name = "tiny_rw"', 'name = "../escaped"'))
    r = run(capsys, "attitude", p, "--out", tmp_path / "out")
    assert one_line_error(r), r.stderr
    assert [f for f in files_under(tmp_path) if f != p] == []
