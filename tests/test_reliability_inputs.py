"""The last bad inputs: each is refused in one line with exit status 2 before any work
and leaves nothing behind, or is handled correctly (a byte-order mark, a sets file given
to ``plot``, figure names that carry what distinguishes their run)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from harness_texts import RANGE_FINDER, SHORT, experiment, one_line_error
from harness_texts import run_cli as run

ROOT = Path(__file__).resolve().parents[1]


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in Path(path).rglob("*") if p.is_file())


def _refused(capsys, out: Path, *args) -> str:
    r = run(capsys, *args, "--out", out)
    assert one_line_error(r), r.stderr
    assert files_under(out) == []
    return r.stderr


# -- scenario values -----------------------------------------------------------------
def test_an_unregistered_scenario_estimator_is_refused(short, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", "intercept", short,
                   "--set", 'experiment.estimator="foo"')  # fmt: skip
    assert "experiment.estimator" in err and "infoset" in err


def test_a_closing_speed_interval_without_the_truth_is_refused(short, tmp_path, capsys):
    """The truth closes at 57.9..58.1 km/s: [59.5, 60] cannot contain it (the prior
    must contain the truth, like the boxes)."""
    err = _refused(capsys, tmp_path / "out", "intercept", short,
                   "--set", "estimator.closing_speed_kmps=[59.5, 60.0]")  # fmt: skip
    assert "estimator.closing_speed_kmps" in err and "truth" in err


def test_a_closing_speed_interval_holding_the_truth_is_taken(short):
    from kalman_vs_infoset.experiments.scenario import load_scenario

    sc = load_scenario(short, ["estimator.closing_speed_kmps=[57.0, 59.0]"])
    assert sc.closing_speed_kmps == (57.0, 59.0)


def test_a_truth_faster_or_slower_than_a_known_closing_speed_is_refused(tmp_path, capsys):
    """Fig. 5's truth closes at 57.9..58.1 km/s; a scenario that leaves out the
    estimators' interval makes them assume 58 km/s exactly, and the sets then lose the
    truth (by hundreds of steps): refused like an interval that misses the truth."""
    text = (ROOT / "data/scenarios/kp_fig5.toml").read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if not ln.startswith("closing_speed_kmps = [")]
    assert len(lines) == len(text.splitlines()) - 1  # the estimator's interval went
    path = tmp_path / "no_interval.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    err = _refused(capsys, tmp_path / "out", "intercept", str(path), "--runs", "1")
    assert "assume the closing speed known" in err and "estimator.closing_speed_kmps" in err


def test_the_truths_default_closing_velocity_is_the_speeds_the_estimators_assume():
    """Without a [truth] vx box the truth closes at the estimators' closing speeds: the
    model's known speed, or the interval given; the a-priori vx box is not used."""
    from kalman_vs_infoset.experiments.scenario import parse_scenario

    assert parse_scenario({}).truth.vx_kmps == (-58.0, -58.0)
    known = parse_scenario({"model": {"closing_speed_kmps": 57.5}})
    assert known.truth.vx_kmps == (-57.5, -57.5)
    given = parse_scenario({"estimator": {"closing_speed_kmps": [57.9, 58.1]}})
    assert given.truth.vx_kmps == (-58.1, -57.9)
    assert given.estimator.vx_kmps == (-59.0, -57.0)


@pytest.mark.parametrize("override", ['description="é – ü/ö"', 'reference.source="Müller (2003)"'])
def test_a_free_text_override_with_letters_beyond_ascii_is_taken(override):
    """``--set 'description="é"'`` was refused with a message about the field ``name``,
    which the user never set: the name's suffix kept ``é`` (a letter to ``str.isalnum``),
    then the name check (ASCII letters and digits) refused it."""
    import re

    from kalman_vs_infoset.experiments.scenario import load_scenario

    sc = load_scenario("kp_fig3", [override])
    assert re.fullmatch(r"[A-Za-z0-9_.,=+-]+", sc.name) and sc.name.startswith("kp_fig3+")
    key, value = override.split("=", 1)
    table, _, field = key.rpartition(".")
    got = getattr(getattr(sc, table) if table else sc, field)
    assert got == value.strip('"')


def test_a_file_name_with_letters_beyond_ascii_names_its_results_after_itself():
    """A scenario file's stem with an ``é`` fell back to the generic name ``scenario``
    (every such file then shared it); its other letters now stay."""
    from kalman_vs_infoset.experiments.scenario import default_name

    assert default_name("/x/szénario fig5.toml") == "sz_nario_fig5"


def test_many_overrides_still_name_files_the_system_accepts(short, tmp_path, capsys):
    """Seven --set overrides once made a result file's name longer than 255 bytes ("File
    name too long", exit 2); past 96 characters the suffix names the rest by a hash."""
    from kalman_vs_infoset.experiments.scenario import MAX_SUFFIX, override_suffix

    sets = [f"estimator.infoset.{k}" for k in (
        "n_nodes=6", "min_live_nodes=4", "max_pieces=4", "n_bands=2", "split_bands=false",
        "tighten_rtol=0.5", "node_split_ratio=3.0")]  # fmt: skip
    suffix = override_suffix(sets)
    assert len(suffix) <= MAX_SUFFIX and suffix.startswith("+" + sorted(sets)[0])
    assert override_suffix(sets) == suffix  # stable: a rerun resumes the same files
    assert override_suffix(sets[::-1]) == suffix  # in any order: the same files
    assert override_suffix([*sets[:-1], "estimator.infoset.node_split_ratio=4.0"]) != suffix
    assert override_suffix(sets[:2]) == "+" + "+".join(sorted(sets[:2]))  # short: unchanged
    # a table and one of its fields: the later wins, so the order given names the file
    table, field = "guidance={max_impulse_mps=2.0}", "guidance.max_impulse_mps=5.0"
    assert override_suffix([table, field]) != override_suffix([field, table])
    out = tmp_path / "out"
    args = [a for kv in sets for a in ("--set", kv)]
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--no-progress",
            "--out", out, *args)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert all(len(p.name.encode()) <= 255 for p in files_under(out))


def test_the_same_overrides_in_another_order_resume_the_same_table(short, tmp_path, capsys):
    """Overrides named the files in the order given: the same two in the other order
    ran the finished runs again into a second table."""
    out = tmp_path / "out"
    a, b = "guidance.max_impulse_mps=5", "model.nu_mps2=0.004"
    base = ["intercept", short, "--workers", 1, "--no-progress", "--estimators", "ekf",
            "--out", out]  # fmt: skip
    assert run(capsys, *base, "--runs", 1, "--set", a, "--set", b).returncode == 0
    r = run(capsys, *base, "--runs", 2, "--set", b, "--set", a)
    assert r.returncode == 0 and "1 run of 2 already in" in r.stderr, r.stderr
    assert len(list(out.glob("*.parquet"))) == 1


@pytest.mark.parametrize("value", ['description="wait... what"', 'reference.label="v1..v2"'])
def test_a_text_value_with_dots_names_its_files(short, tmp_path, capsys, value):
    """A text override holding '..' ran under a name with '..' in it, refused as a
    "field 'name'" the user never set; the name now replaces it, and the run is made."""
    out = tmp_path / "out"
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--no-progress",
            "--estimators", "ekf", "--set", value, "--out", out)  # fmt: skip
    assert r.returncode == 0, r.stderr
    (table,) = out.glob("*.parquet")
    assert ".." not in table.name and table.name.startswith("short+")


@pytest.mark.parametrize("setting", ["range_finder.first_s=0.3", "range_finder.period_s=0.7"])
def test_a_range_finder_off_the_decision_steps_is_refused(tmp_path, capsys, setting):
    """The range finder measures at decision steps: a first time off them was never met
    (no range in a whole run) and a period off them was met at a multiple of the step
    (every 3.5 s for 0.7 s), silently; both are refused, naming the field and the step."""
    p = tmp_path / "short.toml"
    p.write_text(SHORT + RANGE_FINDER)
    err = _refused(capsys, tmp_path / "out", "intercept", p, "--runs", 1, "--set", setting)
    assert f"'{setting.split('=')[0]}'" in err and "'model.dt_s' 0.5 s" in err


def test_a_scenario_name_too_long_for_file_names_is_refused(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text(SHORT.replace('name = "short"', f'name = "{"n" * 200}"'))
    err = _refused(capsys, tmp_path / "out", "intercept", p, "--runs", "1")
    assert "field 'name' has 200 characters" in err


def test_the_same_set_key_twice_is_refused(short, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", "intercept", short,
                   "--set", "model.nu_mps2=0.01", "--set", "model.nu_mps2=0.02")  # fmt: skip
    assert "model.nu_mps2 given twice" in err


@pytest.mark.parametrize(
    "flat,tables",
    [
        ("n_sections=9", ["'estimator.infoset.n_sections'"]),
        ("kalman_noise_inflation=3", ["'estimator.ekf.noise_inflation'",
                                      "'estimator.ukf.noise_inflation'"]),
    ],
)  # fmt: skip
def test_a_flat_option_key_is_refused_naming_its_table_key(short, tmp_path, capsys, flat, tables):
    """One spelling of each option: the flat keys of earlier releases (one of them used
    to be silently ignored beside its table key) are refused, naming the table key."""
    err = _refused(capsys, tmp_path / "out", "intercept", short, "--set", f"estimator.{flat}")
    assert f"'estimator.{flat.split('=')[0]}'" in err and all(t in err for t in tables)


@pytest.mark.parametrize("value", ["7", "{ekf = 5}", '"x"'])
def test_estimator_options_that_are_not_tables_are_refused(short, tmp_path, capsys, value):
    """``estimator.options`` holds the ``[estimator.<name>]`` tables; any other value
    raised an AttributeError or TypeError out of the command (found by random
    ``--set`` overrides)."""
    err = _refused(capsys, tmp_path / "out", "intercept", short, "--runs", "1",
                   "--set", f"estimator.options={value}")  # fmt: skip
    assert "'estimator.options'" in err and "[estimator.<name>]" in err


@pytest.mark.parametrize("name", ["ekf", "infoset"])
def test_an_estimator_table_given_a_value_is_refused_as_not_a_table(short, tmp_path, capsys, name):
    """``--set estimator.ekf=7`` was refused as "unknown key 'estimator.ekf'", listing
    the fields, though the key is the estimator's table."""
    err = _refused(capsys, tmp_path / "out", "intercept", short, "--runs", "1",
                   "--set", f"estimator.{name}=7")  # fmt: skip
    assert f"field 'estimator.{name}' must be a table" in err and "unknown" not in err


def test_estimator_options_given_as_tables_still_reach_their_estimator(short):
    from kalman_vs_infoset.experiments.scenario import load_scenario

    sc = load_scenario(short, ["estimator.options={ekf = {noise_inflation = 3.0}}"])
    assert sc.estimator.options_for("ekf").noise_inflation == 3.0


def test_shipped_scenarios_use_only_table_keys():
    from kalman_vs_infoset.experiments.scenario import load_toml
    from kalman_vs_infoset.experiments.sim.intercept_config import legacy_options

    for path in sorted((ROOT / "data/scenarios").glob("kp_*.toml")):
        assert not set(load_toml(path).get("estimator", {})) & set(legacy_options()), path


def test_a_utf8_byte_order_mark_is_accepted(tmp_path, capsys):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + (SHORT + experiment(runs=1)).encode())
    r = run(capsys, "intercept", p, "--workers", 1, "--no-progress", "--out", tmp_path / "o")
    assert r.returncode == 0, r.stderr


# -- sweep ---------------------------------------------------------------------------
SWEEP = ["sweep", "--estimators", "infoset", "--noise", "random", "--runs", 1, "--no-progress"]


def test_sweep_values_equal_as_numbers_are_refused(short, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", *SWEEP, short, "--key", "model.nu_mps2",
                   "--values", "[0, 0.0]")  # fmt: skip
    assert "twice" in err


@pytest.mark.parametrize("values", ["[nan]", "[inf]", "[1e-5, -inf]"])
def test_sweep_values_not_finite_are_refused_by_the_field(short, tmp_path, capsys, values):
    """TOML's nan and inf were handed on in JSON's spelling (NaN, Infinity) and refused
    as "not a TOML value"; the field's own bound refuses them now."""
    err = _refused(capsys, tmp_path / "out", *SWEEP, short, "--key", "model.nu_mps2",
                   "--values", values)  # fmt: skip
    assert "field 'model.nu_mps2' must be a number" in err and "TOML" not in err


def test_toml_value_writes_what_toml_reads():
    import tomllib

    import numpy as np
    from kalman_vs_infoset.experiments.scenario import toml_value

    for value in (1, 2.5, True, "a b", [1.0, float("inf")], (np.float64(-np.inf), 2),
                  np.array([[1.0, 2.0]]), [["x"], []]):  # fmt: skip
        back = tomllib.loads(f"v = {toml_value(value)}")["v"]
        plain = value.tolist() if hasattr(value, "tolist") else value
        assert json_equal(back, plain), (value, back)
    back = tomllib.loads(f"v = {toml_value([float('nan')])}")["v"]
    assert len(back) == 1 and back[0] != back[0]


def json_equal(a, b) -> bool:
    """Equal as TOML holds them (tuples are lists)."""
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(json_equal(x, y) for x, y in zip(a, b, strict=True))
    return a == b and type(a) is type(b) or (isinstance(a, float) and a == b)


def test_a_swept_key_also_given_with_set_is_refused(short, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", *SWEEP, short, "--key", "model.nu_mps2",
                   "--values", "[0.5, 1.0]", "--set", "model.nu_mps2=2")  # fmt: skip
    assert "--key model.nu_mps2" in err


def test_a_swept_flat_key_is_refused_naming_its_table_keys(short, tmp_path, capsys):
    """Beside ``--set estimator.ekf.noise_inflation=10`` the table key used to win
    silently: the swept value was never used."""
    err = _refused(capsys, tmp_path / "out", *SWEEP, short,
                   "--key", "estimator.kalman_noise_inflation", "--values", "[1, 3]",
                   "--set", "estimator.ekf.noise_inflation=10")  # fmt: skip
    assert "'estimator.ekf.noise_inflation'" in err


def test_a_sweep_sets_a_comma_list_of_keys_to_each_value(short):
    """Both filters' inflation swept together (what the flat key did), table keys."""
    from kalman_vs_infoset.experiments.cmd_sweep import _keys
    from kalman_vs_infoset.experiments.scenario import load_scenario

    keys = _keys("estimator.ekf.noise_inflation, estimator.ukf.noise_inflation", [])
    sc = load_scenario(short, [f"{k}=3" for k in keys])
    assert [sc.estimator.options_for(n).noise_inflation for n in ("ekf", "ukf")] == [3.0, 3.0]


# -- other commands ------------------------------------------------------------------
def test_tightness_times_after_every_run_are_refused(short, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", "tightness", short, "--times", "1000")
    assert "--times" in err and "after the end" in err


@pytest.mark.parametrize("command", ["tightness", "attitude-tightness"])
@pytest.mark.parametrize(
    ("times", "said"),
    [("1e308", "at most 1000000"), ("1e7", "at most 1000000"), ("10,10", "10 s given twice"),
     ("10,", "got '10,'"), (",", "got ','"), ("nan", "got 'nan'"), ("-1", "got '-1'")],
)  # fmt: skip
def test_a_bad_times_list_is_one_line(tmp_path, capsys, command, times, said):
    """``--times`` of both tightness commands: a time so large that it overflowed the
    step count (``OverflowError``, exit 1), an empty item or a time given twice (both
    silently dropped) are refused in one line, exit status 2, as the other lists are."""
    scenario = "kp_fig3" if command == "tightness" else "smallsat_rw"
    err = _refused(capsys, tmp_path / "out", command, scenario, "--times", times)
    assert "--times" in err and said in err


def test_bench_counts_are_bounded_before_any_timing(tmp_path, capsys):
    """``kvi bench --repeat 100000000`` timed for hours without a word, and a too large
    ``--mc-runs`` was refused after seconds of timing, under the name ``--runs``."""
    for flag, value, bound in (("--repeat", "100000000", "[1, 100]"),
                               ("--mc-runs", "2000000", "[1, 1000000]"),
                               ("--steps", "0", "[1, 100000]")):  # fmt: skip
        r = run(capsys, "bench", "--quick", flag, value)
        assert one_line_error(r) and f"argument {flag}" in r.stderr and bound in r.stderr


@pytest.mark.parametrize(
    "args",
    [("intercept", "kp_fig3", "--scheduler", ""), ("fig5", "--scheduler", " "),
     ("fig5", "--scenarios", ""), ("bench", "--quick", "--scenarios", ""),
     ("paper-figures", "--scenarios", "")],
)  # fmt: skip
def test_an_empty_scheduler_or_scenario_folder_is_refused(capsys, args):
    """An empty ``--scheduler`` ran the runs locally and an empty ``--scenarios`` read
    the bundled scenarios, both without a word: a value left out of a script."""
    r = run(capsys, *args)
    assert one_line_error(r) and "expected a value, got an empty text" in r.stderr, r.stderr


@pytest.mark.parametrize(
    ("only", "said"),
    [
        ("", "at least one"),
        ("kp_fig4,,lqr", "an empty name"),
        ("lqr,kp_fig4,lqr", "lqr given twice"),
    ],
    ids=["empty", "empty-name", "twice"],
)
def test_paper_figures_only_empty_or_repeated_is_refused(tmp_path, capsys, only, said):
    """An empty ``--only``, an empty name in it or a name given twice (drawn once before,
    without a word, where the other lists refuse them) is refused before any figure."""
    err = _refused(capsys, tmp_path / "out", "paper-figures", "--only", only,
                   "--scenarios", ROOT / "data/scenarios")  # fmt: skip
    assert "--only" in err and said in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "option",
    [
        ["--horizon-s", "1e12"],
        ["--horizon-s", "inf"],
        ["--grid-step", "1e-9"],
        ["--control-period-s", "1e9"],
        ["--control-period-s", "nan"],
    ],
)
def test_pd_gains_options_that_never_end_are_refused(tmp_path, capsys, option):
    err = _refused(capsys, tmp_path / "out", "pd-gains", "--angles-deg", "1", *option)
    assert option[0] in err


@pytest.mark.parametrize("angles", ["10,10", "10,10.0", "5, 5"])
def test_pd_gains_refuses_an_angle_given_twice(tmp_path, capsys, angles):
    """An angle given twice was computed and tabled twice, where every other list of
    the command line refuses a repeated item."""
    err = _refused(capsys, tmp_path / "out", "pd-gains", "--angles-deg", angles)
    assert "--angles-deg" in err and "given twice" in err


@pytest.mark.parametrize(
    "args",
    [
        ["intercept", "SHORT", "--runs", "1"],
        ["attitude", "TINY"],
        ["fig5", "--runs", "1"],
        ["pd-gains", "--angles-deg", "1"],
        ["paper-figures", "--only", "kp_fig3"],
    ],
)
def test_an_empty_out_is_refused(short, tiny_rw, tmp_path, capsys, monkeypatch, args):
    """``Path("")`` is the current folder: an empty --out used to write there."""
    monkeypatch.chdir(tmp_path)
    before = files_under(tmp_path)
    args = [{"SHORT": short, "TINY": tiny_rw}.get(a, a) for a in args]
    r = run(capsys, *args, "--out", "")
    assert one_line_error(r), r.stderr
    assert "--out ''" in r.stderr and files_under(tmp_path) == before


def test_attitude_controller_of_another_simulation_is_named(tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", "attitude", ROOT / "data/scenarios/resurs_p.toml",
                   "--controller", "pd")  # fmt: skip
    assert "--controller pd" in err and "'energy'" in err and "got 'energy'" not in err


def test_an_infinite_torque_limit_is_refused_with_an_open_bound(tiny_rw, tmp_path, capsys):
    err = _refused(capsys, tmp_path / "out", "attitude", tiny_rw,
                   "--set", "wheels.torque_max_Nm=inf")  # fmt: skip
    assert "(0, inf)" in err and "inf]" not in err


# -- results files -------------------------------------------------------------------
@pytest.mark.parametrize("runs", [["a", "b"], [0.0, float("nan")], [-1, 0], [0, 0]])
def test_a_foreign_table_with_a_bad_run_column_is_refused(short, tmp_path, capsys, runs):
    out = tmp_path / "out"
    args = ["intercept", short, "--runs", 1, "--workers", 1, "--no-progress", "--out", out]
    assert run(capsys, *args).returncode == 0
    (pq,) = out.glob("*.parquet")
    pd.DataFrame({"run": runs, "status": ["ok", "ok"]}).to_parquet(pq, index=False)
    r = run(capsys, *args, "--runs", 3)
    assert one_line_error(r), r.stderr
    assert pq.name in r.stderr and "'run'" in r.stderr


def test_a_table_whose_column_types_were_changed_is_refused_on_resume(short, tmp_path, capsys):
    """A results table changed by another tool so that a number column holds text (its
    own description kept, as a pyarrow edit keeps it) ended a resume in a traceback: the
    summary could not convert the text, or, with runs to add, the save could not put it
    beside their numbers. The table records its columns' types when written; a resume
    that finds others refuses it in one line, before any run."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = tmp_path / "out"
    args = ["intercept", short, "--runs", 1, "--workers", 1, "--no-progress", "--out", out]
    assert run(capsys, *args).returncode == 0
    (path,) = out.glob("*.parquet")
    assert run(capsys, *args).returncode == 0  # untouched: resumed
    table = pq.read_table(path)
    i = table.schema.get_field_index("miss_m")
    edited = table.set_column(i, "miss_m", pa.array(["x"] * len(table)))
    pq.write_table(edited.replace_schema_metadata(table.schema.metadata), path)
    for runs in (1, 2):  # everything done, or a run to add
        r = run(capsys, *args[:3], runs, *args[4:])
        assert one_line_error(r), r.stderr
        assert path.name in r.stderr and "'miss_m'" in r.stderr and "delete it" in r.stderr
    assert len(pq.read_table(path)) == 1  # no run added


@pytest.mark.parametrize("text", [["4.5"], ["n/a"]], ids=["numbers", "words"])
def test_a_table_rewritten_by_pandas_with_text_in_a_number_column_is_refused(
    short, tmp_path, capsys, text
):
    """pandas drops the record of the columns' types when it rewrites a table: a number
    column turned to text there ended a resume in a traceback (the summary's float
    conversion, or the save beside the new runs' numbers). The package writes text only
    in the columns it names (status, error, names): any other is refused in one line,
    before any run; a plain pandas rewrite still resumes (test_defects, i)."""
    out = tmp_path / "out"
    args = ["intercept", short, "--runs", 1, "--workers", 1, "--no-progress", "--out", out]
    assert run(capsys, *args).returncode == 0
    (path,) = out.glob("*.parquet")
    df = pd.read_parquet(path)
    df["miss_m"] = text * len(df)
    df.to_parquet(path, index=False)
    for runs in (1, 2):  # everything done, or a run to add
        r = run(capsys, *args[:3], runs, *args[4:])
        assert one_line_error(r), r.stderr
        assert path.name in r.stderr and "'miss_m'" in r.stderr and "delete it" in r.stderr
    assert len(pd.read_parquet(path)) == 1  # no run added


def test_rows_that_cannot_be_saved_beside_a_rewritten_table_are_one_line(short, tmp_path, capsys):
    """A rewritten table whose text column (``final_status``) now holds numbers passes
    the check of the text columns; the new runs' words cannot be saved in that column:
    one line naming the file after the line saying what runs (was a pyarrow
    traceback), and the table left as it was."""
    out = tmp_path / "out"
    args = ["intercept", short, "--runs", 1, "--workers", 1, "--no-progress", "--out", out]
    assert run(capsys, *args).returncode == 0
    (path,) = out.glob("*.parquet")
    df = pd.read_parquet(path).assign(final_status=1.5)
    df.to_parquet(path, index=False)
    r = run(capsys, *args[:3], 2, *args[4:])
    said = r.stderr.strip().splitlines()
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "1 run of 2 already in" in said[0] and len(said) == 2  # then the error
    assert path.name in said[1] and "cannot be saved" in said[1]
    assert pd.read_parquet(path).equals(df)


def test_a_resume_refusal_names_the_changed_field(tmp_path, capsys):
    """A field that changes what a run gives is named with both values. (The
    description and the [experiment] table do not change a run: a resume takes them,
    ``test_a_study_extended_through_the_file_resumes``.)"""
    p = tmp_path / "short.toml"
    p.write_text(SHORT)
    out = tmp_path / "out"
    args = ["intercept", p, "--runs", 1, "--workers", 1, "--no-progress", "--out", out]
    assert run(capsys, *args).returncode == 0
    p.write_text(SHORT.replace("nominal_range_km = 1000.0", "nominal_range_km = 999.0"))
    r = run(capsys, *args)
    assert one_line_error(r), r.stderr
    assert "scenario.model.nominal_range_km" in r.stderr
    assert "1000.0" in r.stderr and "999.0" in r.stderr


def test_a_refused_scheduler_leaves_nothing_behind(short, tmp_path, capsys, monkeypatch):
    distributed = pytest.importorskip("distributed")
    from kalman_vs_infoset.experiments import executors

    def unreachable(address, timeout=None):
        raise OSError(f"Timed out trying to connect to {address}")

    monkeypatch.setattr(distributed, "Client", unreachable)
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 0.2)  # port 9: nothing listens
    out = tmp_path / "out"
    for command in (["intercept"], ["compare", "--estimators", "infoset", "--noise", "random"]):
        r = run(capsys, *command, short, "--runs", 1, "--no-progress",
                "--scheduler", "tcp://127.0.0.1:9", "--out", out)  # fmt: skip
        assert one_line_error(r), r.stderr
        assert not out.exists()


def test_plot_takes_a_sets_file_for_its_trace(tmp_path, capsys, monkeypatch):
    from kalman_vs_infoset.experiments import cmd_plot

    steps, sets = tmp_path / "x-s1-trace.parquet", tmp_path / "x-s1-trace-sets.parquet"
    for p in (steps, sets):
        p.write_bytes(b"")
    drawn = []
    monkeypatch.setattr(cmd_plot, "plot_files", lambda paths, **kw: drawn.append(paths) or [])
    assert run(capsys, "plot", steps, sets).returncode == 0
    assert drawn == [[steps]]  # the `plot *trace*` glob: drawn once, from its trace
    steps.unlink()
    r = run(capsys, "plot", sets)
    assert one_line_error(r) and steps.name in r.stderr, r.stderr


# -- figure names --------------------------------------------------------------------
def test_trace_figures_of_two_seeds_do_not_replace_each_other(short, tmp_path, capsys):
    out = tmp_path / "out"
    for seed in (3, 4):
        r = run(capsys, "intercept", short, "--runs", 1, "--trace", 0, "--seed", seed,
                "--estimators", "ukf", "--workers", 1, "--no-progress", "--out", out)  # fmt: skip
        assert r.returncode == 0, r.stderr
    names = {p.name for p in out.rglob("*-processes.png")}
    assert names == {f"short-ukf-random-s{s}-run0-processes.png" for s in (3, 4)}


def test_attitude_figures_of_two_estimators_do_not_replace_each_other(tiny_rw, tmp_path, capsys):
    out = tmp_path / "out"
    for est in ("perfect", "box"):
        r = run(capsys, "attitude", tiny_rw, "--estimators", est, "--noise", "random",
                "--out", out)  # fmt: skip
        assert r.returncode == 0, r.stderr
    names = {p.name for p in out.rglob("*-history.png")}
    assert names == {f"tiny_rw-pd-{e}-random-s0-history.png" for e in ("perfect", "box")}


def test_pd_gains_horizon_within_the_hold_is_refused(tmp_path, capsys):
    """A horizon of at most the 5-s hold named the hidden ``hold_s`` before."""
    err = _refused(capsys, tmp_path / "out", "pd-gains", "--angles-deg", "1", "--horizon-s", "5")
    assert "--horizon-s 5" in err and "hold_s" not in err


def test_pd_gains_grid_too_coarse_for_the_fit_is_one_line(tmp_path, capsys):
    """A grid with no efficient curve at any angle leaves eq. (28) nothing to fit: one
    line naming the options (a traceback from the fit before)."""
    err = _refused(capsys, tmp_path / "out", "pd-gains", "--angles-deg", "1",
                   "--grid-step", "2", "--no-figures")  # fmt: skip
    assert "--grid-step" in err and "eq. (28)" in err


def test_a_sun_whose_differential_gravity_exceeds_nu_is_refused(short, tmp_path, capsys):
    """``model.sun_distance_km=1e6`` was accepted and left the truth outside the sets for
    hundreds of steps (its differential gravity, about 1.6 m/s^2, is over ``nu``). The
    least distance named is the boundary: 1 % farther is accepted, 1 % nearer refused;
    ``nu = 0`` is refused (1 AU's gravity exceeds it) but for ``tightness``, whose truth
    is the auxiliary model; a truth that may reach the Sun is one line, not a
    ZeroDivisionError."""
    from kalman_vs_infoset.experiments.errors import InputError
    from kalman_vs_infoset.experiments.scenario import load_scenario

    err = _refused(capsys, tmp_path / "out", "intercept", short, "--set",
                   "model.sun_distance_km=1e6")  # fmt: skip
    assert "'model.sun_distance_km' 1e+06" in err and "'model.nu_mps2' 0.005" in err
    least_km = float(err.split("a Sun distance of at least ")[1].split(" km")[0])
    load_scenario(short, [f"model.sun_distance_km={least_km * 1.01:.6g}"])
    with pytest.raises(InputError, match="differential gravity"):
        load_scenario(short, [f"model.sun_distance_km={least_km * 0.99:.6g}"])
    err = _refused(capsys, tmp_path / "out2", "intercept", short, "--set", "model.nu_mps2=0")
    assert "field 'model.nu_mps2' 0:" in err and "'model.nu_mps2' of at least" in err
    # the remedies named are accepted as printed (rounded up, not down)
    err = _refused(capsys, tmp_path / "out3", "intercept", short, "--set", "model.nu_mps2=1e-9")
    nu = err.split("'model.nu_mps2' of at least ")[1].split(" ")[0]
    far_km = err.split("a Sun distance of at least ")[1].split(" km")[0]
    load_scenario(short, [f"model.nu_mps2={nu}"])
    load_scenario(short, ["model.nu_mps2=1e-9", f"model.sun_distance_km={far_km}"])
    with pytest.raises(InputError) as info:  # kp_fig5 at 1e6 km: 1.6 m/s^2, over nu's 1
        load_scenario("kp_fig5", ["model.sun_distance_km=1e6", "model.along_sight_drift=true"])
    assert "of at least 6.8e+06 km keeps it under" in str(info.value)
    assert "'model.nu_mps2' of at least" not in str(info.value)
    # without the sets' along-sight drift the distance named keeps that under 1 m too
    # (docs/infoset.md), and is accepted as printed
    with pytest.raises(InputError) as info:
        load_scenario("kp_fig5", ["model.sun_distance_km=1e6", "model.along_sight_drift=false"])
    least = info.value.args[0].split("a Sun distance of at least ")[1].split(" km")[0]
    assert float(least) > 2e7
    load_scenario("kp_fig5", [f"model.sun_distance_km={least}", "model.along_sight_drift=false"])
    assert load_scenario(short, ["model.nu_mps2=0"], auxiliary_truth=True).model.nu_mps2 == 0
    far = ["model.sun_distance_km=1e6", "estimator.x_km=[5301.3,1e6]", "truth.x_km=[1e6,1e6]",
           "truth.y_km=[0.0,0.0]", "truth.z_km=[0.0,0.0]"]  # fmt: skip
    with pytest.raises(InputError, match="not less than the Sun's distance"):
        load_scenario(short, far)


def test_tightness_with_no_time_left_draws_without_a_legend_warning(tmp_path, capsys):
    """Every time after the truth reaches eps (kp_fig5's runs end by 99 s): each is
    skipped with its reason, and the empty figure is drawn without matplotlib's "No
    artists with labels" warning on stderr."""
    import warnings

    with warnings.catch_warnings():  # the warning as an error (a traceback, exit -1)
        warnings.filterwarnings("error", message="No artists with labels")
        r = run(capsys, "tightness", "kp_fig5", "--times", "99,100,101,150", "--out",
                tmp_path / "out")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert list((tmp_path / "out").glob("*.png"))


def test_a_sweep_value_the_scenario_refuses_is_named(short, tmp_path, capsys):
    """Every value is validated before the first run; the line said why a scenario was
    refused but not which value of the sweep it was."""
    err = _refused(capsys, tmp_path / "out", "sweep", short, "--key", "model.nu_mps2",
                   "--values", "[0.005, 0.0]")  # fmt: skip
    assert err.startswith("kvi sweep: error: --values: model.nu_mps2 = 0.0: ")
    assert "field 'model.nu_mps2' 0" in err


def test_fig5_refuses_a_set_of_the_field_that_makes_its_variants(capsys, tmp_path):
    """``fig5 --set range_finder.enabled=true`` ran both variants with the range finder,
    the first under the label "bearing only": a field in which the variants' files
    differ is refused in one line (no folder made); other fields of the range finder
    (which only the range variant uses) are taken."""
    from kalman_vs_infoset.experiments.cmd_fig5 import _refuse_variant_overrides, variant_keys
    from kalman_vs_infoset.experiments.scenario import scenario_folder

    folder = scenario_folder(None)
    assert variant_keys(folder) == ["range_finder.enabled"]
    out = tmp_path / "f5"
    for value in ("true", "false"):
        r = run(capsys, "fig5", "--runs", "1", "--set", f"range_finder.enabled={value}",
                "--out", out)  # fmt: skip
        assert one_line_error(r) and "range_finder.enabled" in r.stderr, r.stderr
        assert not out.exists()
    _refuse_variant_overrides(folder, ["range_finder.rel_bound=0.1", "model.nu_mps2=0.01"])
    # the variants read from another folder: what they differ in there
    other = tmp_path / "scen"
    other.mkdir()
    for name in ("kp_fig5.toml", "kp_fig5_range.toml"):
        text = (folder / name).read_text(encoding="utf-8")
        if name == "kp_fig5_range.toml":
            text = text.replace("nu_mps2 = 0.005", "nu_mps2 = 0.01")
        (other / name).write_text(text, encoding="utf-8")
    assert variant_keys(other) == ["model.nu_mps2", "range_finder.enabled"]


def test_an_override_of_an_option_the_estimator_does_not_read_is_warned(capsys, tmp_path):
    """``--set estimator.infoset.n_sections=2`` with the node set ran the bundled set
    under a new name, silently (its results equal the original's): an option of
    another variant of the family is warned, once; an option the set reads is not."""
    import warnings

    from kalman_vs_infoset.experiments.scenario import load_scenario

    with pytest.warns(UserWarning, match=r"--set estimator.infoset.n_sections has no effect"):
        load_scenario("kp_fig5", ["estimator.infoset.n_sections=2"])
    slabs = 'estimator.infoset.sections="slabs"'
    node_only = r'n_nodes has no effect: a node-set option: sections = "slabs"'
    with pytest.warns(UserWarning, match=node_only):
        load_scenario("kp_fig5", [slabs, "estimator.infoset.n_nodes=20"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # read: no warning
        load_scenario("kp_fig5", [slabs, "estimator.infoset.n_sections=40"])
        load_scenario("kp_fig5", ["estimator.infoset.n_nodes=20", "model.nu_mps2=0.01"])
        load_scenario("kp_fig5", ["estimator.infoset.kinematic_margin=false"])
    r = run(capsys, "intercept", "kp_fig5", "--set", "estimator.infoset.max_sections=500",
            "--runs", "1", "--workers", "1", "--no-progress", "--out", tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    warned = [line for line in r.stderr.splitlines() if "has no effect" in line]
    assert warned == [
        "kvi: warning: --set estimator.infoset.max_sections has no effect: the node set "
        '(sections = "nodes") does not read it: it sizes slabs and points'
    ]


def test_an_override_of_a_table_no_run_reads_is_warned(capsys, tmp_path):
    """``--set estimator.ekf.n_sigma=1`` on runs of the information set ran them under a
    new name, silently (their results equal the original's): a table that no run of the
    command reads is warned, once; the information set's options under game errors are
    read by the adversary's set, whatever the pursuer, and are not warned."""
    base = ["--runs", "1", "--workers", "1", "--no-progress"]

    def warned(*args):
        r = run(capsys, "intercept", "kp_fig3", *base, *args)
        assert r.returncode == 0, r.stderr
        return [line for line in r.stderr.splitlines() if "has no effect" in line]

    assert warned(
        "--estimators",
        "infoset",
        "--noise",
        "random",
        "--out",
        tmp_path / "a",
        "--set",
        "estimator.ekf.n_sigma=1.0",
    ) == [  # fmt: skip
        "kvi: warning: --set estimator.ekf.n_sigma has no effect: no run here reads "
        "[estimator.ekf] (these runs read infoset)"
    ]
    assert warned("--estimators", "ekf", "--noise", "game", "--out", tmp_path / "b",
                  "--set", "estimator.infoset.n_nodes=8") == []  # fmt: skip


def test_a_table_copied_beside_another_jobs_description_is_refused(tmp_path, capsys):
    """The table's own description decides a resume: a table of one scenario copied
    (without its ``_meta`` JSON) over the table of another was resumed under the other's
    description, adding runs of one setting to runs of another in one table."""
    p, q = tmp_path / "a.toml", tmp_path / "b.toml"
    p.write_text(SHORT)
    q.write_text(SHORT.replace("nominal_range_km = 1000.0", "nominal_range_km = 999.0"))
    args = ["--workers", 1, "--no-progress", "--estimators", "ekf"]
    assert run(capsys, "intercept", p, "--runs", 1, *args, "--out", tmp_path / "A").returncode == 0
    assert run(capsys, "intercept", q, "--runs", 2, *args, "--out", tmp_path / "B").returncode == 0
    (table,) = (tmp_path / "A").glob("*.parquet")
    (other,) = (tmp_path / "B").glob("*.parquet")
    table.write_bytes(other.read_bytes())  # as a merge of folders: the table only
    r = run(capsys, "intercept", p, "--runs", 3, *args, "--out", tmp_path / "A")
    assert one_line_error(r) and "scenario.model.nominal_range_km" in r.stderr, r.stderr
    assert len(pd.read_parquet(table)) == 2  # nothing added


def _server(reply: bytes | None) -> int:
    """A local server that answers every connection with ``reply`` and closes it, or
    (``None``) accepts and stays silent; its port."""
    import socket
    import threading

    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(4)
    kept = []

    def serve() -> None:
        while True:
            conn, _ = sock.accept()
            if reply is None:  # reads, as an HTTP server waiting for a request's end
                conn.recv(64)
                kept.append(conn)  # open, silent
            else:
                conn.recv(64)
                conn.sendall(reply)
                conn.close()

    threading.Thread(target=serve, daemon=True).start()
    return sock.getsockname()[1]


@pytest.mark.parametrize(
    "reply",
    [b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", None],
    ids=["http", "silent"],
)
def test_a_scheduler_address_that_is_not_a_scheduler_is_one_line(
    short, tmp_path, capsys, monkeypatch, reply
):
    """--scheduler at a server that is not Dask's (the dashboard's port, say): an HTTP
    reply was read as a frame length (a MemoryError traceback) and a silent server hung
    the command; both are refused in one line within the connect timeout."""
    pytest.importorskip("distributed")
    from kalman_vs_infoset.experiments import executors

    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 0.3)
    out = tmp_path / "out"
    r = run(capsys, "intercept", short, "--runs", 1, "--no-progress", "--scheduler",
            f"tcp://127.0.0.1:{_server(reply)}", "--out", out)  # fmt: skip
    assert one_line_error(r) and "not a scheduler" in r.stderr, r.stderr
    assert not out.exists()


def test_the_scheduler_probe_connects_as_the_client_does(monkeypatch):
    """The probe's handshake takes the connection arguments the Dask client takes from
    its configuration (TLS certificates): without them a tls:// scheduler was refused
    ("TLS expects a ssl_context argument")."""
    distributed = pytest.importorskip("distributed")
    from distributed import comm as dask_comm
    from distributed import security
    from kalman_vs_infoset.experiments import executors

    seen: dict = {}

    class Comm:
        async def close(self) -> None:
            seen["closed"] = True

    async def connect(address, timeout=None, **kwargs):
        seen.update(address=address, **kwargs)
        return Comm()

    context = object()
    args = {"ssl_context": context, "require_encryption": True}
    monkeypatch.setattr(dask_comm, "connect", connect)
    monkeypatch.setattr(security.Security, "get_connection_args", lambda self, role: args)
    executors._probe_scheduler("tls://127.0.0.1:8786", timeout_s=2.0)
    assert seen["ssl_context"] is context and seen["closed"] and distributed


def test_trace_takes_run_ids_or_none_and_refuses_a_mix(capsys):
    """``--trace none`` is no run (a single attitude run is traced by default); a mix of
    ``none`` and ids, a repeat or a negative id is refused in one line."""
    import argparse

    from kalman_vs_infoset.experiments.options import parse_runs

    assert parse_runs("none") == [] and parse_runs(" None ") == []
    assert parse_runs("0,3") == [0, 3]
    for bad in ("none,1", "1,1", "-1", "", "0,,3"):
        with pytest.raises(argparse.ArgumentTypeError, match="or 'none'"):
            parse_runs(bad)


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="a folder no file can be made in")
def test_an_out_folder_that_takes_no_file_is_named_not_the_lock(short, capsys):
    """``--out /proc`` (a folder where no file can be made) said "No such file or
    directory (/proc/.short-ekf-random-s3.parquet.lock)": the package's own lock file.
    The line names the folder given."""
    r = run(capsys, "intercept", short, "--estimators", "ekf", "--runs", "1", "--out", "/proc")
    assert one_line_error(r), r.stderr
    assert "cannot write a file in this folder (/proc)" in r.stderr and ".lock" not in r.stderr
