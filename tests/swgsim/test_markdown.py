"""swgsim.base.markdown.md_table: the one writer of the reports' markdown tables."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from swgsim.base.markdown import md_table


def test_a_table_its_cells_and_its_alignment():
    text = md_table([None, "a", "b"], [["x", 1, 0.123456], ["", np.float32(2.5), None],
                                       ["z", float("nan"), True]], "lrr")
    assert text == ("| | a | b |\n|---|---:|---:|\n| x | 1 | 0.123 |\n|  | 2.5 | |\n"
                    "| z | nan | True |")


def test_a_data_frame_with_nan_as_a_dash():
    df = pd.DataFrame({"fault": ["tip"], "rate": [np.nan], "n": [3]})
    assert md_table(df.columns, df.itertuples(index=False), nan="-") == \
        "| fault | rate | n |\n|---|---|---|\n| tip | - | 3 |"


def test_no_rows_gives_the_head_alone():
    assert md_table(["a"], []) == "| a |\n|---|"


@pytest.mark.parametrize("align", ["l", "lrx"])
def test_a_bad_alignment_is_refused(align):
    with pytest.raises(ValueError, match="one letter l or r per column"):
        md_table(["a", "b"], [], align)
