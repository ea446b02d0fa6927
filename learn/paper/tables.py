"""The paper's study as data: its tables (Tables VII-X) and the options of a run.

============  =============  ==============  =======================  ===========
table         protocol       selections      models                   splits
============  =============  ==============  =======================  ===========
VII           cv_clean       1, 2, 3         MLP, SVM, RF, KNN, NB    4 folds
VIII          cv_disturbed   1, 2, 3         MLP, SVM, RF, KNN, NB    4 folds
IX            ood_clean      1, 2, 3         MLP, SVM, RF, KNN, NB    3 gears
X             ood_disturbed  1, 3            MLP, RF, KNN, NB         3 gears
============  =============  ==============  =======================  ===========

:data:`PAPER_TABLES` is the one registry of the tables (the study runs it, the reports
title and order their tables by it, :mod:`swgcli.schema` generates the ``table_*``
experiments from it); :class:`StudyOptions` is what a run of the study may change, the
one place of its defaults (``study`` of ``swgsim-paper`` and ``swgsim-train``).
"""

from __future__ import annotations

from dataclasses import dataclass

from learn.inputs.features import selection_name
from learn.learners.models import MODELS, PAPER_MODELS

#: The paper's five models in the order of its tables (Table VI).
M5: tuple[str, ...] = tuple(PAPER_MODELS)
#: Table X's four (the paper leaves SVM out there).
M4: tuple[str, ...] = tuple(m for m in M5 if m != "svm")


@dataclass(frozen=True)
class PaperTable:
    """One of the paper's result tables.

    Attributes
    ----------
    name : str
        Roman numeral, "VII" .. "X".
    title : str
        The paper's caption.
    protocol : str
        Key of :data:`learn.studies.protocols.PROTOCOLS`.
    selections : tuple of int
        Feature selections (paper Table III), registered in
        :data:`learn.inputs.features.SELECTIONS`.
    models : tuple of str
        Model names (:data:`learn.learners.models.MODELS`).
    """

    name: str
    title: str
    protocol: str
    selections: tuple[int, ...]
    models: tuple[str, ...]

    @property
    def selection_names(self) -> tuple[str, ...]:
        """Config names of the selections, ``selection1`` ..."""
        return tuple(selection_name(k) for k in self.selections)


#: The paper's tables, by name, in the paper's order.
PAPER_TABLES: dict[str, PaperTable] = {
    t.name: t for t in (
        PaperTable("VII", "Score on training and test set for different selections",
                   "cv_clean", (1, 2, 3), M5),
        PaperTable("VIII", "Score on training and test set for disturbed data",
                   "cv_disturbed", (1, 2, 3), M5),
        PaperTable("IX", "Avg. score in per cent on out-of-distribution classification",
                   "ood_clean", (1, 2, 3), M5),
        PaperTable("X", "Avg. score in per cent on out-of-distribution classification on "
                   "disturbed data for four selected classifiers",
                   "ood_disturbed", (1, 3), M4),
    )
}


@dataclass
class StudyOptions:
    """What a run of the paper's study (:func:`learn.paper.task.run_paper_study`) may
    change; the defaults are the paper's study.

    Attributes
    ----------
    tables : list of str or None
        Subset of :data:`PAPER_TABLES`; None: all four.
    models : list of str or None
        None: each table's paper models. Else the paper models of each table that are
        listed, plus every listed model that is not one of the paper's (registered with
        :func:`learn.learners.models.register_model`) in every table.
    scale : bool
        StandardScaler before each classifier (the paper names scikit-learn's standard
        settings and no scaling).
    figures : bool
        Draw the paper's Fig. 6-8 from the data set.
    """

    tables: list[str] | None = None
    models: list[str] | None = None
    scale: bool = False
    figures: bool = True

    def check(self, where: str = "study") -> None:
        """Refuse unknown tables and models (run by
        :func:`swgsim.base.typed.check_tree` as any config part's).

        Parameters
        ----------
        where : str
            Full name of the options for messages.

        Raises
        ------
        ValueError
            ``<where>.tables`` or ``<where>.models`` naming what is not registered.
        """
        bad = sorted(set(self.tables or ()) - set(PAPER_TABLES))
        if bad:
            raise ValueError(f"{where}.tables must be among {list(PAPER_TABLES)}, got {bad}")
        bad = sorted(set(self.models or ()) - set(MODELS))
        if bad:
            raise ValueError(f"{where}.models must be among {list(MODELS)}, got {bad}")

    def selected_tables(self) -> list[PaperTable]:
        """The tables to run, in the paper's order of :data:`PAPER_TABLES` as given."""
        names = list(PAPER_TABLES) if self.tables is None else [str(t) for t in self.tables]
        return [PAPER_TABLES[t] for t in names]

    def table_models(self, table: PaperTable) -> list[str]:
        """Models of one table under these options (see :attr:`models`)."""
        if self.models is None:
            return list(table.models)
        chosen = [str(m) for m in self.models]
        extra = [m for m in chosen if m not in PAPER_MODELS]
        return [m for m in table.models if m in chosen] + extra
