"""External datasets mapped onto our feature names."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.dataset.external import MAPPED_CICIDS2017, MAPPED_UNSW_NB15, ExternalFormatError, load_cicids2017, load_unsw_nb15
from uavcas.schema import FEATURES


def test_original_cic_header_with_spaces(tmp_path):
    f = tmp_path / "cic.csv"
    f.write_text(" Destination Port, Flow Duration, Total Fwd Packets, Total Backward Packets, Flow IAT Mean, Label\n80,2000000,3,2,500000,BENIGN\n443,1000,1,0,0,DDoS\n")
    df = load_cicids2017(f)
    assert df["Flow Duration"].tolist() == [2.0, 0.001] and df["Flow IAT Mean"][0] == 0.5
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
    assert np.nanmax(cic["Flow Duration"]) <= 121  # microseconds converted to seconds
    unsw = load_unsw_nb15(shared_data / "ids-samples" / "unsw-nb15-testing-head4528")
    assert len(unsw) == 4528 and (unsw.label == "Normal").sum() == 243
    assert unsw[list(MAPPED_UNSW_NB15)].notna().all().all()
    assert unsw.label_binary.sum() == 4528 - 243
