from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from uavcas.analysis.iat import flow_iats, iats_of_sequences


def test_zero_and_negative_iats_are_counted_not_dropped():
    r = iats_of_sequences(pd.Series([np.array([0.0, 0.0, 1.0, 0.5]), np.array([5.0]), np.array([0.0, 2.0])]))
    assert r.n_negative == 1 and r.n_flows_no_iat == 1
    assert r.n_zero == 2  # one real zero + the clipped negative
    assert np.allclose(r.pooled, [0.0, 1.0, 0.0, 2.0])


def test_arrow_backed_lists_match_object_lists_and_limit():
    seqs = [[0.0, 0.1, 0.3, 0.6], [0.0, 1.0], [], [0.0, 0.5, 0.7]]
    obj = iats_of_sequences(pd.Series([np.array(s) for s in seqs]), limit=2)
    arrow = pd.Series(pd.arrays.ArrowExtensionArray(pa.array(seqs, type=pa.list_(pa.float64()))))
    arr = iats_of_sequences(arrow, limit=2)
    assert np.allclose(obj.pooled, arr.pooled) and np.allclose(arr.pooled, [0.1, 0.2, 1.0, 0.5, 0.2])
    assert arr.n_flows_no_iat == 1


def test_fallback_to_mean_iat_feature_is_recorded():
    df = pd.DataFrame({"Flow IAT Mean": [0.1, np.nan, 0.3], "label": ["a", "b", "c"]})
    r = flow_iats(df, source="flow-mean")
    assert r.source == "Flow IAT Mean" and r.n_flows_no_iat == 1 and len(r.per_flow) == 2
    assert r.rows.tolist() == [0, 2]
    with pytest.raises(ValueError, match="flow-mean"):
        flow_iats(df, source="packet")  # no sequences: per-packet IATs do not exist
