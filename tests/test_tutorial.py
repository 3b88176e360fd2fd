"""The tutorial notebook runs: its code cells, in order, as the docs build executes them."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

NOTEBOOK = Path(__file__).parents[1] / "docs" / "tutorials" / "first-steps.md"


def test_the_first_steps_notebook_runs(tmp_path, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))  # its scratch folder lands here
    cells = re.findall(r"```\{code-cell\} python\n(.*?)```", NOTEBOOK.read_text(), flags=re.S)
    assert len(cells) >= 6
    namespace: dict = {}
    for i, cell in enumerate(cells):
        exec(compile(cell, f"{NOTEBOOK.name}, cell {i + 1}", "exec"), namespace)
    result, figures = namespace["result"], namespace["figures"]
    assert sorted(result.radius.values.tolist()) == [4.0, 8.0, 12.0]
    assert "fig3" in figures.files and "fig3" not in figures.skipped
    assert not list(tmp_path.glob("softcell-tutorial-*"))  # the last cell cleans up
    assert (result.sel(body="cell").mean_go_duration > 0).all()
