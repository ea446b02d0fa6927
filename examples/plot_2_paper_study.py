"""
The paper's study on the tiny grid
==================================

The study of *Fault detection in gauge-sensorized strain wave gears* (its Table III
features, Table VI classifiers, 4-fold cross-validation over groups) run with
:func:`learn.paper.task.run_paper_study` on the tiny data set, for Table VII and two of
its classifiers, and set beside the paper's numbers. The main job (``swgsim-paper``) runs
all four tables under two acquisitions on the paper's full grid.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

from learn.paper.results import CELL_COLUMNS, our_cells, paper_cells
from learn.paper.tables import StudyOptions
from learn.paper.task import run_paper_study
from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate

scratch = tempfile.TemporaryDirectory(prefix="swg-example-")  # removed at the end
work = Path(scratch.name)
generate(dataset_config(dataset_preset("tiny")), work / "tiny", progress=False)
run_paper_study(work / "tiny", work / "report",
                StudyOptions(tables=["VII"], models=["rf", "knn"], figures=False),
                track=False, progress=False)
results = pd.read_csv(work / "report" / "results.csv")
print(results.groupby(["selection", "model"]).test_accuracy.mean().unstack().round(3))

# %%
# Each cell beside the paper's (Table VII: test score, mean over the four folds). The
# tiny grid has 4 variants per class instead of 60 and one speed instead of two, so
# these are not a reproduction: ``reports/summary.md`` of the main job is.

cells = paper_cells().merge(our_cells(results), on=list(CELL_COLUMNS))
cells = cells[cells.table == "VII"]
fig, ax = plt.subplots(figsize=(7, 3.5))
labels = [f"{m.upper()}\n{s.replace('selection', 'Sel. ')}"
          for s, m in zip(cells.selection, cells.model, strict=True)]
x = range(len(cells))
ax.bar([i - 0.2 for i in x], cells.paper, 0.4, label="paper")
ax.bar([i + 0.2 for i in x], cells.ours, 0.4, label="ours, tiny grid")
ax.set_xticks(list(x), labels, fontsize=8)
ax.set_ylabel("test score [%]")
ax.set_ylim(0, 105)
ax.legend(fontsize=8, loc="lower right")
ax.set_title("Table VII: 4-fold cross-validation on clean windows", fontsize=10)
fig.tight_layout()

# %%
# The simulated files were only for this page: remove them.
scratch.cleanup()
