"""External datasets mapped onto our `cic` feature names and units."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.dataset.external import (
    MAPPED_CICIDS2017,
    MAPPED_UNSW_NB15,
    ExternalFormatError,
    load_cicids2017,
    load_unsw_nb15,
)
from uavcas.flows.standards.cic import FEATURES


def test_original_cic_header_with_spaces(tmp_path):
    f = tmp_path / "cic.csv"
    f.write_text(" Destination Port, Flow Duration, Total Fwd Packets, Total Backward Packets, Flow IAT Mean, "
                 "Label\n80,2000000,3,2,500000,BENIGN\n443,1000,1,0,0,DDoS\n")
    df = load_cicids2017(f)
    # CICFlowMeter's own units (us) are the `cic` standard's: taken as they are
    assert df["Flow Duration"].tolist() == [2_000_000, 1000] and df["Flow IAT Mean"][0] == 500_000
    assert df["Total Fwd Packets"].tolist() == [3, 1] and df.label_binary.tolist() == [0, 1]
    assert df["Fwd Header Length"].isna().all()
    with pytest.raises(ExternalFormatError, match="Label"):
        (tmp_path / "x.csv").write_text("a,b\n1,2\n")
        load_cicids2017(tmp_path / "x.csv")


@pytest.mark.shared
def test_shared_samples(shared_data):
    cic = load_cicids2017(shared_data / "ids-samples" / "cicids2017-improved-rnd2500")
    assert len(cic) == 25127 and set(FEATURES) <= set(cic.columns)
    assert cic[list(MAPPED_CICIDS2017)].notna().all().all() and len(MAPPED_CICIDS2017) == 47
    assert 0 < cic.label_binary.mean() < 1 and (cic.label == "BENIGN").sum() == 2500
    assert 1e8 < np.nanmax(cic["Flow Duration"]) <= 121e6  # microseconds, up to the 120 s flow timeout
    unsw = load_unsw_nb15(shared_data / "ids-samples" / "unsw-nb15-testing-head4528")
    assert len(unsw) == 4528 and (unsw.label == "Normal").sum() == 243
    assert unsw[list(MAPPED_UNSW_NB15)].notna().all().all()
    assert unsw.label_binary.sum() == 4528 - 243
    sample_dir = shared_data / "ids-samples" / "unsw-nb15-testing-head4528"
    raw = __import__("pandas").read_csv(next(sample_dir.glob("*.csv")))
    assert np.allclose(unsw["Flow Duration"], raw["dur"] * 1e6)  # seconds -> us
