"""The runner keeps whole chunks: a command stopped while it takes a finished chunk's
rows saves all of them or none (a vectorised attitude chunk is one value; its runs are
never split between the saved table and a rerun)."""

from __future__ import annotations

import pandas as pd
import pytest
from kalman_vs_infoset.experiments import runner


def _task(runs: list[int]) -> list[tuple[int, dict]]:
    return [(j, {"status": "ok", "error": "", "x": float(j) ** 2}) for j in runs]


class _StopAfterFirstUpdate:
    """A progress bar that is Ctrl-C'd as soon as the first rows are counted."""

    def update(self, n: int) -> None:
        raise KeyboardInterrupt

    def close(self) -> None:
        pass


@pytest.mark.parametrize("chunk", [1, 4, 8])
def test_a_stop_while_rows_come_in_saves_whole_chunks(tmp_path, monkeypatch, chunk):
    job = runner.Job("toy", "t", 1, {"scenario": "toy"}, {"scenario": "toy"}, _task, chunk)
    monkeypatch.setattr(runner, "progress_bar", lambda *a, **k: _StopAfterFirstUpdate())
    with pytest.raises(KeyboardInterrupt):
        runner.run_job(job, 3 * chunk, tmp_path, workers=1, progress=False)
    saved = pd.read_parquet(runner.job_path(tmp_path, job))
    assert sorted(saved["run"]) == list(range(chunk))  # the first chunk, whole
    monkeypatch.undo()
    done = runner.run_job(job, 3 * chunk, tmp_path, workers=1, progress=False)
    assert list(done["run"]) == list(range(3 * chunk))
    assert list(done["x"]) == [float(j) ** 2 for j in range(3 * chunk)]
