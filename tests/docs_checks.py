"""The table of the docs' numbers and where each comes from (read by
``test_docs_numbers.py``, which describes the rows).

The results files and the commands that write them (the ``--json`` line of stdout,
kept under ``docs/results/``) are listed in ``docs/results/README.txt``.
"""

from __future__ import annotations

import re

README, FIGMD = "README.md", "docs/figures.md"
ATT, INT, PERF = "docs/attitude.md", "docs/intercept.md", "docs/performance.md"
FIGS = "docs/figures/paper_figures.json"
FIG5 = "docs/results/fig5.json"
CMP = "docs/results/compare_kp_fig5.json"
F3 = "docs/results/fig3/kp_fig3-infoset-"
BENCH = "docs/results/bench.json"
BENCH_SLOW = "docs/results/bench_slow_host.json"
BENCH_PREV = "docs/results/bench_at_1f4367d.json"
BENCH_39E = "docs/results/bench_at_39ec9cf.json"
VS_1F4 = "docs/results/vs_1f4367d.json"
BENCH_NOW = "docs/results/bench_after_trial_splits.json"
BENCH_PP = "docs/results/bench_per_piece.json"
BENCH_TAIL = "docs/results/bench_tail.json"
VS_SLOW = "docs/results/vs_35e3739_slow_host.json"
VS_THIRD = "docs/results/vs_35e3739_third_host.json"
STUDY = "docs/results/study/fig5-"
SPEED = "docs/results/speed/kp_fig5-"
SLOW10 = "docs/results/speed/kp_fig3-closing_"
SLOW_T = "docs/results/tightness/slow_encounter/kp_fig3-closing_10kmps-tightness-"
CONS = "docs/results/constrained/compare_kp_fig5_kalman_constrained.json"
E2E = "docs/results/e2e/kp_fig3_attitude-infoset-"
INFL = "docs/results/sweeps/kp_fig5_kalman_inflated-noise_inflation.json"
NODES = "docs/results/sweeps/kp_fig5-n_nodes.json"
FAM = "docs/results/families/compare_kp_fig5_families.json"
WIDE = "docs/results/wide_d/kp_fig5-closing_speed_57_59-infoset-"
ADV5 = "docs/results/adversaries/kp_fig5-adversaries.json"
VS = "docs/results/vs_35e3739.json"
FZT = "docs/results/fuzz_tightness/seed400000-1200.json"
VS_5F9 = "docs/results/vs_35e3739_at_5f9e157.json"
VS_E8E = "docs/results/vs_35e3739_at_e8e92a3.json"
VS_8790E49 = "docs/results/vs_35e3739_at_8790e49.json"
VS_6CA6544 = "docs/results/vs_35e3739_at_6ca6544.json"
VS_BEFORE = "docs/results/vs_35e3739_before_trial_splits.json"
N = "numbers/"
#: docs/attitude.md's results files (docs/results/README.txt lists their commands)
PDG = "docs/results/attitude/pd_gains.json"
GYC = "docs/results/attitude/gyrostat_game-seed1-constant.json"
SETS = "docs/results/attitude/smallsat_rw-sets.json"
SIGNS = N + "resurs_inertia_signs/"
#: kvi attitude-tightness's files, by scenario and noise
ATT_T = "docs/results/attitude_tightness/{}-{}-seed0.json"
MISS_FUEL = ("miss_m/mean", "fuel_mps/mean")


def _row(estimator: str, noise: str, *fields: str, path: str = CMP) -> tuple[str, ...]:
    """Keys of a compare row's fields (in another results file than ``CMP``: its path
    before ``::``)."""
    pre = "" if path == CMP else path + "::"
    return tuple(f"{pre}rows/[estimator={estimator},noise={noise}]/{f}" for f in fields)


def _fig3_row(label: str, stem: str) -> tuple[str, str, str, tuple[str, ...]]:
    """A row of the Fig. 3 table: miss, fuel, steps outside, empty sets of one run."""
    cell = r"\**([\d.]+)\**"
    pattern = rf"\| {label} \| {cell} \| {cell} \| (\d+) \| (\d+) \|"
    keys = (*MISS_FUEL, "truth_outside", "empty_set")
    return (INT, pattern, F3 + stem + ".json", keys)


def _e2e_row(label: str, noise: str, more: str = r" \|", fields: tuple[str, ...] = ()):
    """A row of the end-to-end table: the run of ``kvi intercept kp_fig3_attitude``."""
    cell = r"\**([\d.]+)\**"
    pattern = rf"\| {label} \| {cell} \| {cell} \| (\d+){more}"
    keys = tuple(f"0/{f}" for f in ("miss_m", "fuel_mps", "truth_outside", *fields))
    return (INT, pattern, E2E + noise + "-s3.parquet", keys)


ROUNDS = "docs/results/tightness/rounds/kp_fig5-"

#: (document, pattern with one group per number, results file, key per group)
#: figures.md's table of the inertia sign readings: each row's cell and its key in the
#: results file
SIGN_READINGS = (
    ('standard, all "-"', "[-,-,-] standard"),
    ('entries, all "+"', "[+,+,+] entries"),
    ("[+, -, -]", "[+,-,-]"),
    ("[+, -, +]", "[+,-,+]"),
    ("[+, +, -]", "[+,+,-]"),
    ("[-, +, +]", "[-,+,+]"),
    ("[-, +, -]", "[-,+,-]"),
    ("[-, -, +]", "[-,-,+]"),
)


def _sign_row(cell: str, key: str) -> tuple[str, str, str, tuple[str, ...]]:
    """A CHECKS row of that table: Z of the energy-saving law and of the Euler baseline."""
    return (FIGMD, rf"\| {re.escape(cell)} \| ([\d]+) \| ([\d]+) \|", FIGS,
            (SIGNS + f"Z_energy/{key}", SIGNS + f"Z_euler/{key}"))  # fmt: skip


CHECKS: list[tuple[str, str, str, tuple[str, ...]]] = [
    # the auxiliary model's impulse (docs/infoset.md)
    ("docs/infoset.md", r"The same case\s+now reads ([\d.]+) at 6 s", "docs/results/tightness/"
     "impulse_geometry/case70830-tightness-infoset-game-seed70830-guided.json", ("ratio/0",)),
    ("docs/infoset.md", r"kp_fig5 runs \(([\d.]+) at 95 s under switching errors, seed 5\)",
     "docs/results/tightness/kp_fig5-tightness-infoset-switch-seed5.json", ("ratio/4",)),
    # the tightening's rounds (docs/infoset.md)
    ("docs/infoset.md", r"the set was at worst ([\d.]+) and ([\d.]+) times as wide as\s+the "
     r"exact one with 4 rounds, and ([\d.]+) and ([\d.]+) with 16", ROUNDS
     + "switch-seed41-max_inserts_4.json", ("max_ratio", *(
         f"{ROUNDS}{f}.json::max_ratio" for f in ("game-seed5-max_inserts_4",
         "switch-seed41-max_inserts_16", "game-seed5-max_inserts_16")))),
    # seed 003
    (FIGMD, r"random errors, miss ([\d.]+) m and fuel ([\d.]+) m/s against the "
     r"paper's 4.3", FIGS, (N + "kp_fig3/ours_miss_fuel/random/0",
                            N + "kp_fig3/ours_miss_fuel/random/1")),
    (FIGMD, r"game fuel, ([\d.]+) m/s against 521.7 m/s \(miss ([\d.]+) m", FIGS,
     (N + "kp_fig3/ours_miss_fuel/game/1", N + "kp_fig3/ours_miss_fuel/game/0")),
    (FIGMD, r"they spend ([\d]+)-([\d]+) m/s \(miss ([\d.]+)-([\d.]+) m\) against ([\d]+) m/s",
     FIGS,
     (N + "kp_fig3_overlay/kalman_miss_fuel/ukf_random/1",
      N + "kp_fig3_overlay/kalman_miss_fuel/ekf_random/1",
      N + "kp_fig3_overlay/kalman_miss_fuel/ukf_random/0",
      N + "kp_fig3_overlay/kalman_miss_fuel/ekf_random/0", N + "kp_fig3/ours_miss_fuel/random/1")),
    (FIGMD, r"and they miss by ([\d]+)-([\d]+) m\.", FIGS,
     (N + "kp_fig3_overlay/kalman_miss_fuel/ukf_game/0",
      N + "kp_fig3_overlay/kalman_miss_fuel/ekf_game/0")),
    (FIGMD, r"\(([\d]+) node slices before, ([\d]+) after\)", FIGS,
     (N + "kp_fig4/sections_before", N + "kp_fig4/sections_after")),
    (FIGMD, r"bearings only ([\d.]+) m / ([\d.]+) m/s \(random\), ([\d.]+) m / "
     r"([\d.]+) m/s \(game\)", FIGS,
     (N + "kp_fig5/mean_miss_fuel/bearings only, random/0",
      N + "kp_fig5/mean_miss_fuel/bearings only, random/1",
      N + "kp_fig5/mean_miss_fuel/bearings only, game/0",
      N + "kp_fig5/mean_miss_fuel/bearings only, game/1")),
    (FIGMD, r"with the range finder ([\d.]+) m / ([\d.]+) m/s \(random\) and "
     r"([\d.]+) m / ([\d.]+) m/s \(game\)", FIGS,
     (N + "kp_fig5/mean_miss_fuel/bearings + range, random/0",
      N + "kp_fig5/mean_miss_fuel/bearings + range, random/1",
      N + "kp_fig5/mean_miss_fuel/bearings + range, game/0",
      N + "kp_fig5/mean_miss_fuel/bearings + range, game/1")),
    (FIGMD, r"our game miss is larger, ([\d.]+) m against ([\d.]+) m \(curve 4", FIGS,
     (N + "kp_fig5/mean_miss_fuel/bearings + range, game/0",
      N + "kp_fig5/mean_miss_fuel/bearings only, game/0")),
    # seed 000
    (FIGMD, r"at 300 s the error is ([\d.]+) deg and ([\d.]+) deg/s", FIGS,
     (N + "resurs/angle_at_300s_deg", N + "resurs/rate_at_300s_degps")),
    (FIGMD, r"within 0.2 deg from ([\d.]+) s", FIGS,
     (N + "resurs/within_tolerance_from_s",)),
    (FIGMD, r"Z = ([\d]+) N\^2 m\^2 s at 300 s against the paper's 2150", FIGS,
     (N + "resurs/Z_ours/energy",)),
    (FIGMD, r"Z = ([\d]+) against the paper's 11200", FIGS,
     (N + "resurs/Z_ours/euler",)),
    (FIGMD, r"excess variation ([\d.]+) N m over the first 30 s", FIGS,
     (N + "resurs/initial_swing_Nm/U0=0",)),
    (FIGMD, r"\(excess variation ([\d.]+) N m against ([\d.]+) N m\)", FIGS,
     (N + "resurs/initial_swing_Nm/U0 paper", N + "resurs/initial_swing_Nm/U0=0")),
    *(_sign_row(cell, key) for cell, key in SIGN_READINGS),
    (FIGMD, r"UKF spends Z = ([\d]+) N\^2 m\^2 s \(exact state ([\d]+)\)", FIGS,
     (N + "resurs_noisy/Z_noisy", N + "resurs_noisy/Z_exact")),
    (FIGMD, r"error at 300 s ([\d.]+) deg \(exact state ([\d.]+) deg\)", FIGS,
     (N + "resurs_noisy/angle_at_300s_deg/noisy", N + "resurs_noisy/angle_at_300s_deg/exact")),
    # seed 001
    (FIGMD, r"settles \(0.01 deg, 0.01 deg/s\) at ([\d.]+) s against the paper's",
     FIGS, (N + "akimov/akimov_fig12/settle_s",)),
    (FIGMD, r"the same gains. turn settles at ([\d.]+) s", FIGS,
     (N + "akimov/akimov_fig12/settle_twice_s",)),
    (FIGMD, r"transient \(([\d.]+) s against ([\d.]+) s\)", FIGS,
     (N + "akimov/akimov_fig6/settle_s", N + "akimov/akimov_fig3/settle_s")),
    (FIGMD, r"phi10 = ([\d.]+) deg and phi20 = ([\d.]+) deg", FIGS,
     (N + "akimov_fig8/phi10_deg", N + "akimov_fig8/phi20_deg")),
    (FIGMD, r"peak torque ([\d.]+) of M_max", FIGS,
     (N + "akimov_fig9/peak_torque_ratio",)),
    # seed 002
    (FIGMD, r"from V = ([\d.]+) to ([\d.e-]+)", FIGS,
     (N + "lqr_lyapunov/V0", N + "lqr_lyapunov/V_end")),
    # seed 004
    (FIGMD, r"settles at ([\d.]+) s \(exact state\) and ([\d.]+) s \(game\) within "
     r"the guaranteed time tau = ([\d.]+) s", FIGS,
     (N + "gyrostat/settle_s/perfect/none", N + "gyrostat/settle_s/box/game",
      N + "gyrostat/tau_s")),
    # docs/attitude.md, the Resurs-P section
    (ATT, r"\| Z energy-saving, U0 = 0 / U0 = \(-5.4, -1.1, -2.4\) N m \| ([\d]+) / "
     r"([\d]+) N\^2 m\^2 s", FIGS, (N + "resurs/Z_ours/energy", N + "resurs/Z_u0_paper")),
    (ATT, r"\| Z Euler-axis flight turn \([\d.]+-s jerk-limited phases, CALIBRATED\) \| "
     r"([\d]+) N\^2 m\^2 s", FIGS, (N + "resurs/Z_ours/euler",)),
    (ATT, r"\| min-energy bound of the linear model, 300 s \| ([\d]+) N\^2 m\^2 s", FIGS,
     (N + "resurs/lower_bound_N2m2s",)),
    (ATT, r"\| energy-saving error at 300 s \| ([\d.]+) deg, ([\d.]+) deg/s \(0.2 deg "
     r"reached at ([\d]+) s\)", FIGS,
     (N + "resurs/angle_at_300s_deg", N + "resurs/rate_at_300s_degps",
      N + "resurs/within_tolerance_from_s")),
    (ATT, r"\| initial torque swing, first 30 s, U0 = 0 vs seed U0 \| ([\d.]+) vs "
     r"([\d.]+) N m", FIGS, (N + "resurs/initial_swing_Nm/U0=0",
                             N + "resurs/initial_swing_Nm/U0 paper")),
    (ATT, r"with gentler 100-s phases an Euler-axis turn costs ([\d]+) N\^2", FIGS,
     (N + "resurs/Z_euler_100s_phases",)),
    (ATT, r"Z energy-saving under the sign readings: standard ([\d]+), entries ([\d]+), "
     r"\[\+, -, -\] ([\d]+), \[\+, -, \+\] ([\d]+)", FIGS,
     (SIGNS + "Z_energy/[-,-,-] standard", SIGNS + "Z_energy/[+,+,+] entries",
      SIGNS + "Z_energy/[+,-,-]", SIGNS + "Z_energy/[+,-,+]")),
    (ATT, r"the full gyrodine simulation within tolerance from ([\d.]+) s \(([\d.]+) "
     r"deg, ([\d.]+) deg/s at 300 s\) for Z = ([\d]+)", FIGS,
     (N + "resurs/f1_raised/within_tolerance_from_s", N + "resurs/f1_raised/angle_deg",
      N + "resurs/f1_raised/rate_degps", N + "resurs/f1_raised/Z")),
    (ATT, r"settles in \*\*([\d.]+) s\*\* \(seed: ([\d.]+) s\)", FIGS,
     (N + "akimov/akimov_fig12/settle_s", N + "akimov/akimov_fig12/paper_settle_s")),
    (ATT, r"boundary phi10 = ([\d.]+) deg is not consistent with J = 1.5 \(we get ([\d.]+) deg\)",
     FIGS, (N + "akimov_fig8/paper_phi10_deg", N + "akimov_fig8/phi10_deg")),
    (ATT, r"guaranteed time tau = ([\d.]+) s", FIGS, (N + "gyrostat/tau_s",)),
    (ATT, r"the gyro momentum falls back to ([\d.]+) N m s at 300 s \(the body's remaining "
     r"rate of ([\d.]+) deg/s", FIGS,
     (N + "resurs/gyro_momentum_at_300s_Nms", N + "resurs/rate_at_300s_degps")),
    # docs/intercept.md: numbers its prose repeats or adds beside the tables
    (INT, r"the EKF's mean miss is ([\d.]+) m, the UKF's ([\d.]+) m\)", INFL,
     ("rows/[value=30,estimator=ekf,noise=game]/miss_m/mean",
      "rows/[value=30,estimator=ukf,noise=game]/miss_m/mean")),
    # docs/figures.md: the papers' numbers as the results file records them, and ours
    (FIGMD, r"against the paper's ([\d.]+) m and ([\d.]+) m/s \(one realisation each\)", FIGS,
     (N + "kp_fig3/paper_miss_fuel/random/0", N + "kp_fig3/paper_miss_fuel/random/1")),
    (FIGMD, r"\(miss [\d.]+ m against ([\d.]+) m\): the Fig\. 3 game fuel", FIGS,
     (N + "kp_fig3/paper_miss_fuel/game/0",)),
    (FIGMD, r"the 300-s error is ([\d.]+) deg under every reading", FIGS,
     (N + "resurs/angle_at_300s_deg",)),
    (FIGMD, r"at [\d.]+ s against the paper's ([\d.]+) s", FIGS,
     (N + "akimov/akimov_fig12/paper_settle_s",)),
    (FIGMD, r"round-off, ([\d.e-]+)\)", FIGS, (N + "lqr_lyapunov/max_increase",)),
    (FIGMD, r"rotor torques stay at ([\d.]+) of their limits", FIGS,
     (N + "gyrostat/max_torque_ratio/box/game",)),
    # docs/attitude.md, the PD gains (kvi pd-gains --json)
    (ATT, r"The best k_q on the grid at k_w 2\.625 is ([\d.]+), which settles in ([\d.]+) s",
     PDG, ("map/efficient_kq_at_kw_2.625", "map/efficient_settle_at_kw_2.625_s")),
    (ATT, r"1 deg ([\d.]+) vs ([\d.]+), 2 deg ([\d.]+) vs ([\d.]+), 6 deg ([\d.]+) vs "
     r"([\d.]+)\)", PDG,
     ("f0/1", "seed_table/1", "f0/2", "seed_table/2", "f0/6", "seed_table/6")),
    (ATT, r"c1 ([\d.]+), p1 ([\d.]+), c2 ([\d.]+), p2 ([\d.]+) \(seed, written with the "
     r"vector part, i\.e\. 2x the table: ([\d.]+), ([\d.]+), ([\d.]+), ([\d.]+)\)", PDG,
     ("fit/c1", "fit/p1", "fit/c2", "fit/p2", "seed_fit_eq28/c1", "seed_fit_eq28/p1",
      "seed_fit_eq28/c2", "seed_fit_eq28/p2")),
    # docs/attitude.md, Resurs-P and the gyrostat
    (ATT, r"the energy-saving turn is within 0\.2 deg only at ([\d]+) s, not 300 s", FIGS,
     (N + "resurs/within_tolerance_from_s",)),
    (ATT, r"settles in ([\d.]+) s on average and ([\d.]+) s at most, within tau, for an "
     r"energy index of ([\d.]+) N\^2 m\^2 s and a final error of ([\d.e-]+) deg", GYC,
     ("settle_time_s/mean", "settle_time_s/max", "energy_N2m2s/mean", "final_angle_deg/mean")),
    (ATT, r"measured peak ([\d.]+) alpha", FIGS, (N + "gyrostat/max_torque_ratio/box/game",)),
    # README: the tightness search on random scenarios (tests/fuzz_tightness.py)
    (README, r"On (\d+) random\s+scenarios within the bounds the scenario files accept", FZT,
     ("cases",)),  # fmt: skip
    (README, r"three times; (\d+) compared, the rest refused", FZT, ("ok",)),
    (README, r"At the node set's default options \((\d+) cases\) a case's largest\s+ratio had "
     r"a median of ([\d.]+) and a 95th percentile of ([\d.]+); (\d+) passed 1\.1, and one "
     r"read\s+(\d+):", FZT, tuple(f"default_options/{k}" for k in (
         "compared", "p50", "p95", "n_over_1_1", "p100"))),
    (README, r"with four times the bands \(`--set estimator\.infoset\.max_bands=256`\) the same\s+"
     r"case reads (\d+)\.", "docs/results/tightness/corner/case400957-tightness-infoset-bias-"
     "seed400957-guided-max_bands_256.json", ("max_ratio",)),
    (README, r"trade tightness for time, the 95th\s+percentile was ([\d.]+)\.", FZT,
     ("options_drawn/p95",)),
    # README: the runs per CPU-second against release 35e3739
    (README, r"Fig\. 5's Monte Carlo does ([\d.]+) times the runs per CPU-second of release "
     r"(?:`35e3739` )?\((\d+) runs,", VS, ("runs_per_cpu_s_ratio_mean", "runs")),
    # README: the papers' numbers beside ours
    (README, r"Fig\. 3, random errors \| miss, fuel \| ([\d.]+) m, ([\d.]+) m/s \| ([\d.]+) m, "
     r"([\d.]+) m/s \|", FIGS,
     (N + "kp_fig3/paper_miss_fuel/random/0", N + "kp_fig3/paper_miss_fuel/random/1",
      N + "kp_fig3/ours_miss_fuel/random/0", N + "kp_fig3/ours_miss_fuel/random/1")),
    (README, r"Fig\. 3, game errors \| miss, fuel \| ([\d.]+) m, ([\d.]+) m/s \| ([\d.]+) m, "
     r"([\d.]+) m/s \|", FIGS,
     (N + "kp_fig3/paper_miss_fuel/game/0", N + "kp_fig3/paper_miss_fuel/game/1",
      N + "kp_fig3/ours_miss_fuel/game/0", N + "kp_fig3/ours_miss_fuel/game/1")),
    (README, r"energy-saving law \| index Z \| ([\d]+) N\^2 m\^2 s \| ([\d]+) N\^2 m\^2 s \|",
     FIGS, (N + "resurs/Z_paper/energy", N + "resurs/Z_ours/energy")),
    (README, r"\| error at 300 s \| <= 0\.2 deg \| ([\d.]+) deg \|", FIGS,
     (N + "resurs/angle_at_300s_deg",)),
    (README, r"Euler-axis baseline \| index Z \| ([\d]+) N\^2 m\^2 s \| ([\d]+) N\^2 m\^2 s \|",
     FIGS, (N + "resurs/Z_paper/euler", N + "resurs/Z_ours/euler")),
    (README, r"Fig\. 12 \| settling time \| ([\d.]+) s \| ([\d.]+) s \|", FIGS,
     (N + "akimov/akimov_fig12/paper_settle_s", N + "akimov/akimov_fig12/settle_s")),
    (README, r"Lyapunov function V along a turn \| decreases \| ([\d.]+) -> ([\d.e-]+), never "
     r"increasing \|", FIGS, (N + "lqr_lyapunov/V0", N + "lqr_lyapunov/V_end")),
    (README, r"settling time, adversarial torques \| within the guaranteed time \| ([\d.]+) s "
     r"within ([\d.]+) s \|", FIGS, (N + "gyrostat/settle_s/box/game", N + "gyrostat/tau_s")),
    (README, r"within 0\.2 deg only from ([\d]+) s", FIGS, (N + "resurs/within_tolerance_from_s",)),
    (README, r"Fig\. 5 \(four variants x (\d+) runs\)", FIG5, ("runs",)),
    # the largest ratio of the guided runs on unseen seeds (its file: the worst run,
    # test_docs_tightness checks that it is the largest)
    # (the counts and the threshold: test_docs_tightness)
    (README, r"within 1\.03 times its width in all \d+ guided runs on unseen seeds, at most "
     r"([\d.]+) times",
     "docs/results/tightness/seeds_401/kp_fig5-tightness-infoset-game-seed420-guided.json",
     ("max_ratio",)),
    # the widest with band_trials="impulse_spread", the default before (the count, the
    # CPU-time ratios and the seeds checked every second: test_docs_tightness)
    (README, r"without them \d+ of those runs read past 1\.03, at most ([\d.]+), and with them "
     r"the range-finder runs cost [\d.]+-[\d.]+ times the CPU time; checked every second of "
     r"the first minute, one of four seeds still passed 1\.03 for a second",
     "docs/results/tightness/range_707/kp_fig5_range-tightness-infoset-random-seed731-guided.json",
     ("max_ratio",)),
    (README, r"The estimators on the same (\d+) Fig\. 5 engagements", CMP, ("runs",)),
    (README, r"the set misses by ([\d.]+) m for ([\d.]+) m/s; the EKF by ([\d.]+) m for "
     r"([\d.]+) m/s and the UKF by ([\d.]+) m for ([\d.]+) m/s", CMP,
     _row("infoset", "random", *MISS_FUEL) + _row("ekf", "random", *MISS_FUEL)
     + _row("ukf", "random", *MISS_FUEL)),
    (README, r"their ellipsoid left the truth at (\d+) and (\d+) steps, the set at (\d+)", CMP,
     _row("ekf", "random", "truth_outside") + _row("ukf", "random", "truth_outside")
     + _row("infoset", "random", "truth_outside")),
    (README, r"the EKF misses by ([\d.]+) m and the UKF by ([\d.]+) m against the set's "
     r"([\d.]+) m", CMP,
     _row("ekf", "bias", "miss_m/mean") + _row("ukf", "bias", "miss_m/mean")
     + _row("infoset", "bias", "miss_m/mean")),
    (README, r"the fuel differences are not significant \(signed-rank p\s+([\d.]+) and ([\d.]+)\)",
     CMP, ("paired/rows/[estimator=ekf,noise=bias]/fuel_mps/wilcoxon_p",
           "paired/rows/[estimator=ukf,noise=bias]/fuel_mps/wilcoxon_p")),
    (README, r"the set's miss grows to ([\d.]+) m for ([\d.]+) m/s, its guarantee holds "
     r"\((\d+) steps outside\)", CMP, _row("infoset", "game", *MISS_FUEL, "truth_outside")),
    (README, r"they miss by ([\d.]+) m \(EKF\) and ([\d.]+) m \(UKF\)", CMP,
     _row("ekf", "game", "miss_m/mean") + _row("ukf", "game", "miss_m/mean")),
    # docs/intercept.md: Fig. 3, one engagement per row, and the paper's numbers
    (INT, r"\| seed, random noise \| ([\d.]+) \| ([\d.]+) \|", FIGS,
     (N + "kp_fig3/paper_miss_fuel/random/0", N + "kp_fig3/paper_miss_fuel/random/1")),
    (INT, r"\| seed, game noise \| ([\d.]+) \| ([\d.]+) \|", FIGS,
     (N + "kp_fig3/paper_miss_fuel/game/0", N + "kp_fig3/paper_miss_fuel/game/1")),
    _fig3_row(r"\*\*ours, random\*\* \(node set, default\)", "random"),
    _fig3_row(r"ours, random \(slabs, the previous default\)", "random-slabs"),
    _fig3_row(r"ours, random \(seed's point sections\)", "random-points"),
    _fig3_row(r"\*\*ours, game\*\* \(node set\)", "game"),
    _fig3_row(r"ours, game \(slabs\)", "game-slabs"),
    _fig3_row(r"ours, game \(seed's point sections\)", "game-points"),
    (INT, r"with the node set \(the default\) the miss is ([\d.]+) m against the seed's ([\d.]+) m",
     FIGS, (N + "kp_fig3/ours_miss_fuel/random/0", N + "kp_fig3/paper_miss_fuel/random/0")),
    (INT, r"our adversary costs the pursuer ([\d.]+) m/s with the node set, \d+ % "
     r"of the seed's ([\d.]+) m/s \(miss ([\d.]+) m against ([\d.]+) m\)", FIGS,
     (N + "kp_fig3/ours_miss_fuel/game/1", N + "kp_fig3/paper_miss_fuel/game/1",
      N + "kp_fig3/ours_miss_fuel/game/0", N + "kp_fig3/paper_miss_fuel/game/0")),
    # docs/intercept.md: Fig. 5 (``make run``)
    (INT, r"Perfect-information fuel \(mean over runs\) ([\d.]+) m/s; "
     r"bearing-limited miss scale ([\d.]+) m", FIG5, ("fuel_perfect_info_mps", "miss_floor_m")),
    # docs/intercept.md: the paper's whole closing-speed interval D (kvi intercept kp_fig5 --set)
    (INT, r"mean miss ([\d.]+) m \(random\), ([\d.]+) m \(game\), ([\d.]+) m \(bias\), fuel "
     r"([\d.]+) / ([\d.]+) / ([\d.]+) m/s, no step outside, no set diverged", WIDE + "random.json",
     ("miss_m/mean", WIDE + "game.json::miss_m/mean", WIDE + "bias.json::miss_m/mean",
      "fuel_mps/mean", WIDE + "game.json::fuel_mps/mean", WIDE + "bias.json::fuel_mps/mean")),
    # docs/intercept.md: the Kalman filters on the Fig. 5 truths (``kvi compare``)
    (INT, r"\(median miss ([\d.]+) m \(EKF\) and ([\d.]+) m \(UKF\) against ([\d.]+) m\)", CMP,
     _row("ekf", "random", "miss_m/p50") + _row("ukf", "random", "miss_m/p50")
     + _row("infoset", "random", "miss_m/p50")),
    (INT, r"\(mean ([\d.]+) and ([\d.]+) m/s against ([\d.]+) m/s\)", CMP,
     _row("ekf", "random", "fuel_mps/mean") + _row("ukf", "random", "fuel_mps/mean")
     + _row("infoset", "random", "fuel_mps/mean")),
    (INT, r"\(median ([\d.]+) m \(EKF\) and ([\d.]+) m \(UKF\)\)", CMP,
     _row("ekf", "game", "miss_m/p50") + _row("ukf", "game", "miss_m/p50")),
    (INT, r"the set's mean miss grows from ([\d.]+) to ([\d.]+) m \(fuel ([\d.]+) -> "
     r"([\d.]+) m/s\)", CMP,
     _row("infoset", "random", "miss_m/mean") + _row("infoset", "game", "miss_m/mean")
     + _row("infoset", "random", "fuel_mps/mean") + _row("infoset", "game", "fuel_mps/mean")),
    (INT, r"errors \(mean miss ([\d.]+) -> ([\d.]+) m, fuel ([\d.]+) -> ([\d.]+) m/s\); under the "
     r"game the range finder makes the miss worse here \(([\d.]+) -> ([\d.]+) m, fuel ([\d.]+) -> "
     r"([\d.]+) m/s\)", FIG5,
     tuple(f"variants/[variant={v},noise={n}]/{k}" for n, k in
           (("random", "miss_m/mean"), ("random", "fuel_mps/mean"),
            ("game", "miss_m/mean"), ("game", "fuel_mps/mean"))
           for v in ("bearing only", "bearing + range"))),
    (INT, r"their median miss is ([\d.]+) m \(EKF\) and ([\d.]+) m \(UKF\) against the set's "
     r"([\d.]+) m\. The set does almost as well with a bias as with random errors \(median "
     r"([\d.]+) against ([\d.]+) m\) and spends less fuel \(mean ([\d.]+) against ([\d.]+) m/s\)",
     CMP, _row("ekf", "bias", "miss_m/p50") + _row("ukf", "bias", "miss_m/p50")
     + _row("infoset", "bias", "miss_m/p50") + _row("infoset", "bias", "miss_m/p50")
     + _row("infoset", "random", "miss_m/p50") + _row("infoset", "bias", "fuel_mps/mean")
     + _row("infoset", "random", "fuel_mps/mean")),
    # docs/intercept.md: the estimator families (kvi compare kp_fig5, eight estimators)
    (INT, r"under any kind \(from (\d+) to (\d+) steps outside a row\)", FAM,
     _row("ekf", "random", "truth_outside", path=FAM)
     + _row("ekf", "bias", "truth_outside", path=FAM)),
    (INT, r"misses by ([\d.]+) m \(game\) to ([\d.]+) m \(targeted\) on average, the ellipsoid "
     r"spends ([\d.]+) m/s against the set's ([\d.]+) m/s under random errors", FAM,
     _row("zonotope", "game", "miss_m/mean", path=FAM)
     + _row("zonotope", "targeted", "miss_m/mean", path=FAM)
     + _row("ellipsoid", "random", "fuel_mps/mean", path=FAM)
     + _row("infoset", "random", "fuel_mps/mean", path=FAM)),
    (INT, r"fires \(fuel ([\d.]+) m/s, the miss is the unguided one, ([\d.]+) m on average\); "
     r"late in the approach its kinematic bound outgrows the set, which is then reported "
     r"diverged \(in (\d+) of (\d+) runs", FAM,
     _row("box", "random", "fuel_mps/mean", "miss_m/mean", "diverged", path=FAM)
     + (FAM + "::runs",)),
    (INT, r"under a bias held at the bound the ellipsoid \(([\d.]+) m / ([\d.]+) m/s\) and the "
     r"H-infinity filter \(([\d.]+) m / ([\d.]+) m/s\), and under the seed's game the ellipsoid "
     r"\(([\d.]+) m / ([\d.]+) m/s against the set's ([\d.]+) m / ([\d.]+) m/s\)", FAM,
     _row("ellipsoid", "bias", *MISS_FUEL, path=FAM) + _row("hinf", "bias", *MISS_FUEL, path=FAM)
     + _row("ellipsoid", "game", *MISS_FUEL, path=FAM)
     + _row("infoset", "game", *MISS_FUEL, path=FAM)),
    (INT, r"estimators pay ([\d.]+) and ([\d.]+) m/s for that trust, and an adversary that aims "
     r"at them \(`targeted`\) makes them miss by ([\d.]+) m and ([\d.]+) m", FAM,
     _row("ellipsoid", "random", "fuel_mps/mean", path=FAM)
     + _row("hinf", "random", "fuel_mps/mean", path=FAM)
     + _row("ellipsoid", "targeted", "miss_m/mean", path=FAM)
     + _row("hinf", "targeted", "miss_m/mean", path=FAM)),
    (INT, r"closest of the filters to the set \(([\d.]+) m / ([\d.]+) m/s under random errors\) "
     r"but not a bound \((\d+) steps outside\), and the white-box adversary zeroes every "
     r"particle's weight at some step in (\d+) of (\d+) runs", FAM,
     _row("pf", "random", *MISS_FUEL, "truth_outside", path=FAM)
     + _row("pf", "targeted", "empty_set", path=FAM) + (FAM + "::runs",)),
    # docs/intercept.md: adversaries on the Fig. 5 truths (kvi adversaries kp_fig5 --runs 10)
    (INT, r"particle filter gave every particle zero weight at some step in (\d+), (\d+) and (\d+) "
     r"of the (\d+) runs", ADV5,
     tuple(f"rows/[estimator=pf,rule={r}]/empty_set" for r in ("game", "targeted", "lookahead"))
     + ("runs",)),
    (INT, r"Fig\. 3 fuel gap \(ours ([\d.]+) m/s, seed ([\d.]+) m/s\)", FIGS,
     (N + "kp_fig3/ours_miss_fuel/game/1", N + "kp_fig3/paper_miss_fuel/game/1")),
    (INT, r"the largest fuel any rule drew from the pursuer was ([\d.]+) m/s \(the seed's rule\)",
     ADV5, ("rows/[estimator=infoset,rule=game]/fuel_mps/max",)),
    (INT, r"\(Fig\. 5 mean ([\d.]+) -> ([\d.]+) m under `targeted`", ADV5,
     ("rows/[estimator=infoset,rule=game]/miss_m/mean",
      "rows/[estimator=infoset,rule=targeted]/miss_m/mean")),
    (INT, r"\(([\d.]+) m/s mean under the seed's rule, ([\d.]+) and ([\d.]+) under the white-box",
     ADV5, tuple(f"rows/[estimator=infoset,rule={r}]/fuel_mps/mean"
                 for r in ("game", "targeted", "lookahead"))),
    (INT, r"pays ([\d.]+) and ([\d.]+) m/s on average \(targeted, look-ahead\)", ADV5,
     ("rows/[estimator=hinf,rule=targeted]/fuel_mps/mean",
      "rows/[estimator=hinf,rule=lookahead]/fuel_mps/mean")),
    (INT, r"pay it in ([\d.]+) and ([\d.]+) of the runs under the look-ahead", ADV5,
     ("rows/[estimator=ekf,rule=lookahead]/runs_at_seed_fuel",
      "rows/[estimator=ukf,rule=lookahead]/runs_at_seed_fuel")),
    # docs/intercept.md: the range constraint (kvi compare kp_fig5_kalman_constrained)
    (INT, r"Under the game it cuts the EKF's mean miss from ([\d.]+) to ([\d.]+) m and the UKF's "
     r"from ([\d.]+) to ([\d.]+) m, and neither comes near the set's ([\d.]+) m", CMP,
     _row("ekf", "game", "miss_m/mean") + _row("ekf", "game", "miss_m/mean", path=CONS)
     + _row("ukf", "game", "miss_m/mean") + _row("ukf", "game", "miss_m/mean", path=CONS)
     + _row("infoset", "game", "miss_m/mean")),
    # docs/intercept.md: the node grid (kvi sweep kp_fig5 --key estimator.infoset.n_nodes)
    (INT, r"\(mean miss ([\d.]+)-([\d.]+) m, fuel ([\d.]+)-([\d.]+) m/s\)\. Under the game the "
     r"mean miss moves between ([\d.]+) and ([\d.]+) m in no clear direction and the fuel between "
     r"([\d.]+) and ([\d.]+) m/s", NODES,
     tuple(f"rows/[value={v},estimator=infoset,noise={n}]/{k}" for n, k, v in (
         ("random", "miss_m/mean", 8), ("random", "miss_m/mean", 6),
         ("random", "fuel_mps/mean", 16), ("random", "fuel_mps/mean", 12),
         ("game", "miss_m/mean", 16), ("game", "miss_m/mean", 12),
         ("game", "fuel_mps/mean", 12), ("game", "fuel_mps/mean", 8)))),
    # docs/intercept.md: the filters' noise inflated (kvi sweep kp_fig5_kalman_inflated)
    (INT, r"at `s = 30` the EKF's mean miss is ([\d.]+) m, the UKF's ([\d.]+) m", INFL,
     ("rows/[value=30,estimator=ekf,noise=game]/miss_m/mean",
      "rows/[value=30,estimator=ukf,noise=game]/miss_m/mean")),
    # docs/intercept.md: end-to-end with the attitude loop (run tables of kvi intercept)
    _e2e_row(r"\*\*end-to-end, random\*\*", "random",
             r" \| ([\d.]+) deg \| ([\d.]+) deg \|",
             ("attitude_max_pointing_error_deg", "pointing_residual_max_deg")),
    _e2e_row(r"\*\*end-to-end, game\*\*", "game"),
    (INT, r"\| Fig\. 3, random, no attitude loop \| ([\d.]+) \| ([\d.]+) \| (\d+) \|",
     F3 + "random.json", (*MISS_FUEL, "truth_outside")),
    (INT, r"\| Fig\. 3, game, no attitude loop \| ([\d.]+) \| ([\d.]+) \| (\d+) \|",
     F3 + "game.json", (*MISS_FUEL, "truth_outside")),
    (INT, r"guaranteed knowledge bound, ([\d.]+) deg, to the bearing", E2E + "random-s3.parquet",
     ("0/pointing_knowledge_bound_deg",)),
    # docs/infoset.md: the extreme-band trials with bearings only (kvi compare kp_fig5, the
    # option and the defaults, each measured twice)
    ("docs/infoset.md", r"the game's\s+mean miss reads ([\d.]+) m against ([\d.]+) m",
     SPEED + "trials-extreme_bands.json",
     ("rows/[noise=game]/miss_m/mean",
      f"{SPEED}trials-default.json::rows/[noise=game]/miss_m/mean")),
    # docs/infoset.md, fine steps: kvi intercept kp_fig3 --set model.dt_s=DT --noise NOISE
    # --runs 1 --json
    *[("docs/infoset.md", rf"\| {re.escape(dt)} \| {noise} \| ([\d.]+) \| ([\d.]+) \| (\d+) \|",
       f"docs/results/fine_steps/kp_fig3-dt{dt}-infoset-{noise}.json",
       ("miss_m/mean", "fuel_mps/mean", "truth_outside"))
      for dt, noise in (("0.1", "game"), ("0.075", "game"), ("0.05", "game"), ("0.05", "random"))],
    # docs/performance.md, side by side with 35e3739: /usr/bin/time of kvi fig5 --runs 20
    # and, on that commit, python -m experiments fig5 --runs 20, alternately (pairs)
    (PERF, r"today's `kvi fig5 --runs (\d+)`", VS, ("runs_per_variant",)),
    (PERF, r"Fig\. 5 with (\d+) runs per variant, today's", VS, ("runs_per_variant",)),
    (PERF, r"`docs/results/vs_35e3739.json`, measured with this release's code\): ([\d.]+), "
     r"([\d.]+) and ([\d.]+) CPU-s today against ([\d.]+), ([\d.]+) and ([\d.]+), i\.e\. "
     r"([\d.]+) times the runs per CPU-second", VS,
     ("cpu_s_now/0", "cpu_s_now/1", "cpu_s_now/2", "cpu_s_35e3739/0", "cpu_s_35e3739/1",
      "cpu_s_35e3739/2", "runs_per_cpu_s_ratio_mean")),
    (PERF, r"`docs/results/vs_35e3739_at_f15e898.json`\), the same comparison read ([\d.]+), "
     r"([\d.]+) and ([\d.]+) CPU-s against ([\d.]+), ([\d.]+) and ([\d.]+), ([\d.]+) times",
     "docs/results/vs_35e3739_at_f15e898.json",
     ("cpu_s_now/0", "cpu_s_now/1", "cpu_s_now/2", "cpu_s_35e3739/0", "cpu_s_35e3739/1",
      "cpu_s_35e3739/2", "runs_per_cpu_s_ratio_mean")),
    (PERF, r"`docs/results/vs_35e3739_at_5f9e157.json`\),\s+read ([\d.]+), ([\d.]+) and "
     r"([\d.]+) CPU-s against ([\d.]+), ([\d.]+) and ([\d.]+), ([\d.]+) times", VS_5F9,
     ("cpu_s_now/0", "cpu_s_now/1", "cpu_s_now/2", "cpu_s_35e3739/0", "cpu_s_35e3739/1",
      "cpu_s_35e3739/2", "runs_per_cpu_s_ratio_mean")),
    (PERF, r"first command there cost ([\d.]+) CPU-s and its next two ([\d.]+) and (\d+\.\d+)",
     VS_5F9, ("first_set/cpu_s_35e3739/0", "first_set/cpu_s_35e3739/1",
          "first_set/cpu_s_35e3739/2")),
    (PERF, r"`docs/results/vs_35e3739_at_e8e92a3.json`\), read ([\d.]+) and ([\d.]+) CPU-s "
     r"against ([\d.]+) and ([\d.]+), ([\d.]+) times", VS_E8E,
     ("cpu_s_now/0", "cpu_s_now/1", "cpu_s_35e3739/0", "cpu_s_35e3739/1",
      "runs_per_cpu_s_ratio_mean")),
    (PERF, r"range finder measured \(`docs/results/vs_35e3739_at_6ca6544.json`: ([\d.]+) and "
     r"([\d.]+) CPU-s against ([\d.]+) and ([\d.]+)\)", VS_6CA6544,
     ("cpu_s_now/0", "cpu_s_now/1", "cpu_s_35e3739/0", "cpu_s_35e3739/1")),
    (PERF, r"read ([\d.]+) with the per-piece replay only", VS_6CA6544,
     ("runs_per_cpu_s_ratio_mean",)),
    (PERF, r"and ([\d.]+) before it \(`docs/results/vs_35e3739_at_8790e49.json`: "
     r"([\d.]+) and ([\d.]+) CPU-s against ([\d.]+) and ([\d.]+)\)", VS_8790E49,
     ("runs_per_cpu_s_ratio_mean", "cpu_s_now/0", "cpu_s_now/1", "cpu_s_35e3739/0",
      "cpu_s_35e3739/1")),
    (PERF, r"it read ([\d.]+) \(`docs/results/vs_35e3739_before_trial_splits.json`: ([\d.]+) "
     r"and ([\d.]+) CPU-s against ([\d.]+) and ([\d.]+)\)", VS_BEFORE,
     ("runs_per_cpu_s_ratio_mean", "cpu_s_now/0", "cpu_s_now/1", "cpu_s_35e3739/0",
      "cpu_s_35e3739/1")),
    (PERF, r"`docs/results/vs_35e3739_slow_host.json`\): ([\d.]+) times the runs per "
     r"CPU-second pooled, ([\d.]+) to ([\d.]+) pair by pair", VS_SLOW,
     ("runs_per_cpu_s_ratio_pooled", "runs_per_cpu_s_ratio_min", "runs_per_cpu_s_ratio_max")),
    (PERF, r"`docs/results/vs_35e3739_third_host.json`\): ([\d.]+) times the runs per\s+"
     r"CPU-second pooled, ([\d.]+) to ([\d.]+) pair by pair, the old commit's command "
     r"costing ([\d.]+)\s+CPU-s in the first pair and ([\d.]+) in the third", VS_THIRD,
     ("runs_per_cpu_s_ratio_pooled", "runs_per_cpu_s_ratio_min", "runs_per_cpu_s_ratio_max",
      "cpu_s_35e3739/0", "cpu_s_35e3739/2")),
    (README, r"approach a set step costs ([\d.]+) of a UKF step, and the last tenth takes "
     r"([\d.]+) of the set's\s+CPU time", BENCH_TAIL,
     ("whole_approach_head_ratio", "whole_approach_tail_share/infoset")),
    # docs/performance.md: ``kvi bench``
    (PERF, r"mean over the first (\d+) steps of a Fig\. 3 approach", BENCH,
     ("steps_timed/infoset",)),
    (PERF, r"UKF over the whole approach \((\d+) steps, to the blind range\)", BENCH,
     ("whole_approach_steps/infoset",)),
    (PERF, r"whole approach's (\d+) steps the last (\d+) took\s+([\d.]+) of the set's CPU time "
     r"and ([\d.]+) of the UKF's; before them a set step cost (\d+) us\s+against the UKF's "
     r"(\d+) us \(ratio ([\d.]+)\), where over all \d+ it cost (\d+) against (\d+) us\s+"
     r"\(([\d.]+)\)", BENCH_TAIL,
     ("whole_approach_steps/infoset", "whole_approach_tail_steps/infoset",
      "whole_approach_tail_share/infoset", "whole_approach_tail_share/ukf",
      "whole_approach_head_step_us/infoset", "whole_approach_head_step_us/ukf",
      "whole_approach_head_ratio", "whole_approach_step_us/infoset",
      "whole_approach_step_us/ukf", "whole_approach_ratio")),
    (PERF, r"the set makes ([\d.]+) live nodes a step\s+before the last tenth of the approach "
     r"and ([\d.]+) a step in it, and ([\d.]+) of the latter are\s+gone one step later",
     BENCH_TAIL, ("whole_approach_nodes_made/head", "whole_approach_nodes_made/tail",
                  "whole_approach_nodes_made/tail_gone_in_a_step")),
    (PERF, r"\| `infoset` step \(node set\), first (\d+) steps \| (\d+) us", BENCH,
     ("steps_timed/infoset", "step_us/infoset")),
    (PERF, r"\| `ellipsoid` / `zonotope` / `box` step \(29 slabs\) \| (\d+) / "
     r"(\d+) / (\d+) us", BENCH, ("step_us/ellipsoid", "step_us/zonotope", "step_us/box")),
    (PERF, r"\| `ekf` / `ukf` step \(filterpy\) \| (\d+) / (\d+) us", BENCH,
     ("step_us/ekf", "step_us/ukf")),
    (PERF, r"\| `hinf` / `pf` step \(2000 particles\) \| (\d+) / (\d+) us", BENCH,
     ("step_us/hinf", "step_us/pf")),
    (PERF, r"\| infoset / UKF, first (\d+) steps \| ([\d.]+) \|", BENCH,
     ("steps_timed/ukf", "infoset_to_ukf_ratio")),
    (PERF, r"whole approach \((\d+) steps\) \| (\d+) / (\d+) us: ([\d.]+) \|",
     BENCH, ("whole_approach_steps/infoset", "whole_approach_step_us/infoset",
             "whole_approach_step_us/ukf", "whole_approach_ratio")),
    (PERF, r"the set makes ([\d.]+) live nodes a step\s+before the last tenth of the approach "
     r"and ([\d.]+) a step in it, and ([\d.]+) of the latter are\s+gone one step later",
     BENCH_TAIL, ("whole_approach_nodes_made/head", "whole_approach_nodes_made/tail",
                  "whole_approach_nodes_made/tail_gone_in_a_step")),
    (PERF, r"game / random \| (\d+) / (\d+) ms: (\d+) / (\d+) UKF steps", BENCH,
     ("engagement_ms", "engagement_random_ms", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps")),
    (PERF, r"\((\d+) / (\d+) / (\d+) steps\) \| ([\d.]+) \((\d+) / (\d+) / (\d+) ms\)",
     BENCH, ("cost_steps/0", "cost_steps/1", "cost_steps/2", "cost_exponent", "cost_ms/0",
             "cost_ms/1", "cost_ms/2")),
    (PERF, r"a slice has (\d+) / (\d+) /\s+(\d+) vertices on average \(at most (\d+) / (\d+) / "
     r"(\d+);", BENCH, ("cost_mean_vertices/0", "cost_mean_vertices/1", "cost_mean_vertices/2",
                       "cost_max_vertices/0", "cost_max_vertices/1", "cost_max_vertices/2")),
    (PERF, r"1 / 2 workers \| ([\d.]+) / ([\d.]+) \(peak (\d+) MB a worker\)", BENCH,
     ("runs_per_cpu_s/1", "runs_per_cpu_s/2", "worker_peak_rss_mb/1")),
    # (4 = half of bench's --mc-runs: the key of the second number)
    (PERF, r"2 workers, 1 / 4 runs a task \| ([\d.]+) / ([\d.]+) \|", BENCH,
     ("runs_per_cpu_s_by_chunk/1", "runs_per_cpu_s_by_chunk/4")),
    (PERF, r"`kvi COMMAND --help`, costliest command \| ([\d.]+) CPU-s \|", BENCH,
     ("help_cpu_s_max",)),
    (PERF, r"\| ([\d.]+) CPU-s compiling \(([\d.]+) CPU-s in all\)", BENCH,
     ("first_run_compile_s", "first_run_cpu_s")),
    # docs/performance.md: the same kvi bench --json on a slower host
    (PERF, r"`docs/results/bench_slow_host.json`, load average ([\d.]+);", BENCH_SLOW,
     ("machine/load_average",)),
    (PERF, r"a UKF step of (\d+) us and a set step of (\d+) us, and in UKF steps (\d+) / "
     r"(\d+) for the two engagements, ([\d.]+) for the whole approach and a cost exponent "
     r"of ([\d.]+):", BENCH_SLOW,
     ("step_us/ukf", "step_us/infoset", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps", "whole_approach_ratio", "cost_exponent")),
    (PERF, r"`kvi intercept --help` cost ([\d.]+) CPU-s there", BENCH_SLOW,
     ("help_cpu_s/intercept",)),
    (PERF, r"compiled for ([\d.]+) CPU-s, and the Monte Carlo ran ([\d.]+) / ([\d.]+) runs "
     r"per CPU-second", BENCH_SLOW,
     ("first_run_compile_s", "runs_per_cpu_s/1", "runs_per_cpu_s/2")),
    # docs/performance.md: kvi bench --json after the bands' trial splits (a third host)
    (PERF, r"`docs/results/bench_after_trial_splits.json`, load average ([\d.]+)\)", BENCH_NOW,
     ("machine/load_average",)),
    (PERF, r"read a UKF step of (\d+) us and a set step of (\d+) us; in UKF steps (\d+) / "
     r"(\d+) for the two engagements, ([\d.]+) for the whole approach and a cost exponent "
     r"of ([\d.]+); the costliest `--help` took ([\d.]+) CPU-s; the first run compiled for "
     r"([\d.]+) CPU-s; the Monte Carlo ran ([\d.]+) / ([\d.]+) runs per", BENCH_NOW,
     ("step_us/ukf", "step_us/infoset", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps", "whole_approach_ratio", "cost_exponent",
      "help_cpu_s_max", "first_run_compile_s", "runs_per_cpu_s/1", "runs_per_cpu_s/2")),
    # docs/performance.md: kvi bench --json on an AMD host, this release and an hour before
    (PERF, r"`docs/results/bench_amd_host.json`, load average ([\d.]+)\), the bench's UKF "
     r"step read (\d+) us and its set step (\d+) us; the engagements (\d+) / (\d+) UKF steps, "
     r"the whole approach ([\d.]+) and the cost exponent ([\d.]+); the costliest `--help` "
     r"([\d.]+) CPU-s; the first run's compilation ([\d.]+) CPU-s; the Monte Carlo ([\d.]+) / "
     r"([\d.]+) runs per CPU-second", "docs/results/bench_amd_host.json",
     ("machine/load_average", "step_us/ukf", "step_us/infoset", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps", "whole_approach_ratio", "cost_exponent",
      "help_cpu_s_max", "first_run_compile_s", "runs_per_cpu_s/1", "runs_per_cpu_s/2")),
    (PERF, r"read a UKF step of (\d+) us and a set step of (\d+) us, (\d+) / (\d+) UKF steps "
     r"for the engagements: within the hour", "docs/results/bench_amd_host_first.json",
     ("step_us/ukf", "step_us/infoset", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps")),
    (PERF, r"`kvi intercept --help` took ([\d.]+) CPU-s, the other commands ([\d.]+) to "
     r"([\d.]+): one start", "docs/results/bench_amd_host_first.json",
     ("help_cpu_s/intercept", "help_cpu_s/plot", "help_cpu_s/adversaries")),
    # docs/performance.md: kvi bench --json with the per-piece impulse replay
    (PERF, r"`docs/results/bench_per_piece.json`, load average ([\d.]+), nothing else",
     BENCH_PP, ("machine/load_average",)),
    (PERF, r"read a UKF step of (\d+) us and a set step of (\d+) us; in UKF steps (\d+) / "
     r"(\d+) for the two engagements, ([\d.]+) for the whole approach and a cost exponent "
     r"of ([\d.]+); the costliest `--help` took ([\d.]+) CPU-s \(over", BENCH_PP,
     ("step_us/ukf", "step_us/infoset", "engagement_in_ukf_steps",
      "engagement_random_in_ukf_steps", "whole_approach_ratio", "cost_exponent",
      "help_cpu_s_max")),
    (PERF, r"the first run compiled for ([\d.]+) CPU-s; the Monte Carlo ran ([\d.]+) / "
     r"([\d.]+) runs per CPU-second with 1 / 2 workers\. A first run", BENCH_PP,
     ("first_run_compile_s", "runs_per_cpu_s/1", "runs_per_cpu_s/2")),
    (PERF, r"`docs/results/bench_per_piece_first.json`\), read (\d+) / (\d+), ([\d.]+) and "
     r"([\d.]+):", "docs/results/bench_per_piece_first.json",
     ("engagement_in_ukf_steps", "engagement_random_in_ukf_steps", "whole_approach_ratio",
      "cost_exponent")),
    # docs/performance.md, the node set's speed options: kvi compare kp_fig5 --estimators
    # infoset --noise random,game --runs 50 --workers 2 [--set KEY=VALUE] --json
    *[(PERF, rf"\| {re.escape(label)} \| {noise} \| ([\d.]+) \| ([\d.]+) \| (\d+) \| ([\d.]+) \|",
       f"{SPEED}{name}.json", _row("infoset", noise, "miss_m/mean", "fuel_mps/mean",
                                   "truth_outside", "cpu_s", path=f"{SPEED}{name}.json"))
      for label, name in (("(defaults)", "default"),
                          ("`estimator.infoset.node_split_ratio=4`", "node_split_ratio_4"),
                          ("`estimator.infoset.max_vertices=64`", "max_vertices_64"),
                          ("`estimator.infoset.n_bands=2`", "n_bands_2"),
                          ("`estimator.infoset.n_bands=1`", "n_bands_1"),
                          ("`estimator.infoset.impulse_per_piece=false`", "impulse_per_band"))
      for noise in ("random", "game")],
    # the later day's two options, beside the defaults run before and after them
    (PERF, r"the defaults read ([\d.]+) and ([\d.]+) CPU-s random, ([\d.]+) and ([\d.]+) game",
     f"{SPEED}later-default.json",
     ("rows/[noise=random]/cpu_s", f"{SPEED}later-default-repeat.json::rows/[noise=random]/cpu_s",
      "rows/[noise=game]/cpu_s", f"{SPEED}later-default-repeat.json::rows/[noise=game]/cpu_s")),
    *[(PERF, rf"{re.escape(opt)}\) saved \d+ % and \d+ %[^;]*?, for (?:a mean miss of )?"
       rf"([\d.]+) / ([\d.]+) m and (?:fuel of )?([\d.]+) / ([\d.]+) m/s",
       f"{SPEED}later-{name}.json",
       ("rows/[noise=random]/miss_m/mean", "rows/[noise=game]/miss_m/mean",
        "rows/[noise=random]/fuel_mps/mean", "rows/[noise=game]/fuel_mps/mean"))
      for opt, name in (("`estimator.infoset.n_nodes=8`", "n_nodes_8"),
                        ("`estimator.infoset.min_live_nodes=4`", "min_live_nodes_4"))],
    (PERF, r"A repeat of the defaults right after the `n_bands=1` rows read ([\d.]+) / "
     r"([\d.]+) CPU-s for random / game",
     f"{SPEED}default-repeat.json",
     tuple(f"rows/[noise={n}]/cpu_s" for n in ("random", "game"))),
    (PERF, r"and a second one after the next row ([\d.]+) / ([\d.]+) \(",
     f"{SPEED}default-repeat2.json",
     tuple(f"rows/[noise={n}]/cpu_s" for n in ("random", "game"))),
    # docs/performance.md, the large study: kvi fig5 --runs 50 --workers 1|2 --json
    *[(PERF, rf"\| {re.escape(v)} \| {n} \| ([\d.]+) \| ([\d.]+) \|", STUDY + "w1.json",
       tuple(f"{f}variants/[variant={v},noise={n}]/cpu_s" for f in ("", f"{STUDY}w2.json::")))
      for v in ("bearing only", "bearing + range") for n in ("random", "game")],
    (PERF, r"Each worker peaked at (\d+) to (\d+) MB", STUDY + "w2.json",
     ("variants/0/worker_peak_rss_mb", "variants/2/worker_peak_rss_mb")),
    # docs/performance.md: the earlier readings of the bench table, and side by side
    (PERF, r"read a UKF step of (\d+) us and a set step of (\d+) us, where this one reads "
     r"(\d+) us and (\d+) us, so the engagements read (\d+) / (\d+) UKF steps there and "
     r"(\d+) / (\d+) here", BENCH_39E,
     ("step_us/ukf", "step_us/infoset", f"{BENCH}::step_us/ukf", f"{BENCH}::step_us/infoset",
      "engagement_in_ukf_steps", "engagement_random_in_ukf_steps",
      f"{BENCH}::engagement_in_ukf_steps", f"{BENCH}::engagement_random_in_ukf_steps")),
    (PERF, r"`docs/results/bench_at_1f4367d.json`\) read (\d+) us and (\d+) us", BENCH_PREV,
     ("step_us/ukf", "step_us/infoset")),
    (PERF, r"`kvi fig5 --runs (\d+)` \(three pairs, `docs/results/vs_1f4367d.json`\) cost "
     r"([\d.]+), ([\d.]+) and ([\d.]+) CPU-s with this code against ([\d.]+), ([\d.]+) and "
     r"([\d.]+) with the previous release's: ([\d.]+) times the runs per CPU-second", VS_1F4,
     ("runs_per_variant", "cpu_s_now/0", "cpu_s_now/1", "cpu_s_now/2", "cpu_s_1f4367d/0",
      "cpu_s_1f4367d/1", "cpu_s_1f4367d/2", "runs_per_cpu_s_ratio_mean")),
    # docs/performance.md and the README: a slow encounter (10 km/s against 58), the
    # closing speed known (as Fig. 3's) or known to within 1 %
    (PERF, r"measured two runs of the information set\s+at ([\d.]+) CPU-s and the UKF's at "
     r"([\d.]+) \(`docs/results/speed/kp_fig3-closing_10kmps-known\.json`\),\s+against "
     r"([\d.]+) and ([\d.]+) CPU-s at 58 km/s", SLOW10 + "10kmps-known.json",
     (*_row("infoset", "random", "cpu_s", path=SLOW10 + "10kmps-known.json"),
      *_row("ukf", "random", "cpu_s", path=SLOW10 + "10kmps-known.json"),
      *_row("infoset", "random", "cpu_s", path=SLOW10 + "58kmps.json"),
      *_row("ukf", "random", "cpu_s", path=SLOW10 + "58kmps.json"))),
    (PERF, r"the same command measured\s+the set's two runs at ([\d.]+) CPU-s, and the UKF's at "
     r"([\d.]+)\s+\(`docs/results/speed/kp_fig3-closing_10kmps\.json`\)", SLOW10 + "10kmps.json",
     _row("infoset", "random", "cpu_s", path=SLOW10 + "10kmps.json")
     + _row("ukf", "random", "cpu_s", path=SLOW10 + "10kmps.json")),
    (PERF, r"\((\d+) steps outside; the UKF's\s+3-sigma ellipsoid (\d+)\) and missed by ([\d.]+) "
     r"m for ([\d.]+) m/s\s+\(the UKF: ([\d.]+) m for ([\d.]+)\s+m/s\)", SLOW10 + "10kmps.json",
     (*_row("infoset", "random", "truth_outside", path=SLOW10 + "10kmps.json"),
      *_row("ukf", "random", "truth_outside", path=SLOW10 + "10kmps.json"),
      *_row("infoset", "random", "miss_m/mean", "fuel_mps/mean", path=SLOW10 + "10kmps.json"),
      *_row("ukf", "random", "miss_m/mean", "fuel_mps/mean", path=SLOW10 + "10kmps.json"))),
    (PERF, r"Capping the bands\s+\(`--set estimator\.infoset\.max_bands=8`, 64 by default\) made "
     r"the same two runs cost\s+([\d.]+) CPU-s, with a miss of ([\d.]+) m for ([\d.]+) m/s and the "
     r"truth inside at every step", SLOW10 + "10kmps-max_bands_8.json",
     _row("infoset", "random", "cpu_s", "miss_m/mean", "fuel_mps/mean",
          path=SLOW10 + "10kmps-max_bands_8.json")),
    (PERF, r"within ([\d.]+) of the exact set's width at 60, 200, 400 and 540 s of the first "
     r"run, where\s+the default read at most ([\d.]+)", SLOW_T + "max_bands_8.json",
     ("max_ratio", f"{SLOW_T}default.json::max_ratio")),
    (README, r"at 10 km/s instead of 58 \(an approach about six times longer\)\s+two Fig\. 3 "
     r"runs of the set took ([\d.]+) CPU-s with the speed known, against ([\d.]+), and ([\d.]+)"
     r"\s+CPU-s with it known to within 1 %", SLOW10 + "10kmps-known.json",
     (*_row("infoset", "random", "cpu_s", path=SLOW10 + "10kmps-known.json"),
      *_row("infoset", "random", "cpu_s", path=SLOW10 + "58kmps.json"),
      *_row("infoset", "random", "cpu_s", path=SLOW10 + "10kmps.json"))),
    # docs/attitude.md: the attitude sets against the exact set (kvi attitude-tightness)
    (ATT, r"On smallsat_rw the box's hull reaches ([\d.]+) times the exact width on the "
     r"attitude axes under random noise and ([\d.]+) under the game torque \(([\d.]+) and "
     r"([\d.]+) on the rates\), the zonotope's ([\d.]+) and ([\d.]+);",
     ATT_T.format("smallsat_rw", "pd-random"),
     ("estimators/box/max_ratio_attitude",
      ATT_T.format("smallsat_rw", "pd-game") + "::estimators/box/max_ratio_attitude",
      "estimators/box/max_ratio_rate",
      ATT_T.format("smallsat_rw", "pd-game") + "::estimators/box/max_ratio_rate",
      "estimators/zonotope/max_ratio_attitude",
      ATT_T.format("smallsat_rw", "pd-game") + "::estimators/zonotope/max_ratio_attitude")),
    (ATT, r"the box\s+reaches ([\d.]+) and ([\d.]+) times on the attitude axes and ([\d.]+) and "
     r"([\d.]+) on the rates, the\s+zonotope ([\d.]+) on the attitude axes under both noises",
     ATT_T.format("lqr_large_angle", "lqr-random"),
     ("estimators/box/max_ratio_attitude",
      ATT_T.format("lqr_large_angle", "lqr-game") + "::estimators/box/max_ratio_attitude",
      "estimators/box/max_ratio_rate",
      ATT_T.format("lqr_large_angle", "lqr-game") + "::estimators/box/max_ratio_rate",
      "estimators/zonotope/max_ratio_attitude")),
    (ATT, r"the box reaches ([\d.]+) times on the attitude axes under\s+random disturbances "
     r"and ([\d.]+) under the adversarial ones \(([\d.]+) and ([\d.]+) on the rates\),\s+the "
     r"zonotope ([\d.]+) and ([\d.]+)\.", ATT_T.format("gyrostat_game", "game-random"),
     ("estimators/box/max_ratio_attitude",
      ATT_T.format("gyrostat_game", "game-game") + "::estimators/box/max_ratio_attitude",
      "estimators/box/max_ratio_rate",
      ATT_T.format("gyrostat_game", "game-game") + "::estimators/box/max_ratio_rate",
      "estimators/zonotope/max_ratio_attitude",
      ATT_T.format("gyrostat_game", "game-game") + "::estimators/zonotope/max_ratio_attitude")),
    (ATT, r"energy-saving law's turn takes the box to\s+([\d.]+) times on the attitude axes "
     r"and ([\d.]+) on the rates under random errors,.*?and to ([\d.]+) and ([\d.]+) under "
     r"the adversary's torque; the zonotope\s+reaches ([\d.]+) and ([\d.]+) on the attitude "
     r"axes, the box's ratios on the rates\. The\s+Euler-axis turn stays closer: the box "
     r"([\d.]+) and ([\d.]+) on the attitude axes",
     ATT_T.format("resurs_p", "energy-random"),
     ("estimators/box/max_ratio_attitude", "estimators/box/max_ratio_rate",
      ATT_T.format("resurs_p", "energy-game") + "::estimators/box/max_ratio_attitude",
      ATT_T.format("resurs_p", "energy-game") + "::estimators/box/max_ratio_rate",
      "estimators/zonotope/max_ratio_attitude",
      ATT_T.format("resurs_p", "energy-game") + "::estimators/zonotope/max_ratio_attitude",
      ATT_T.format("resurs_p", "euler-random") + "::estimators/box/max_ratio_attitude",
      ATT_T.format("resurs_p", "euler-game") + "::estimators/box/max_ratio_attitude")),
    (PERF, r"\(`kvi bench --json`, the line kept in `docs/results/bench.json`; x86_64, "
     r"(\d+) CPUs, Linux, Python ([\d.]+), numpy ([\d.]+), load average ([\d.]+)\)", BENCH,
     ("machine/cpus", "machine/python", "machine/numpy", "machine/load_average")),
]  # fmt: skip
