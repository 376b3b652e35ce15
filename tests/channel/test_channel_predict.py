"""`uavcas.channel.predict`: a user's geometry table checked, predicted by the link chain and written
(the library under `uavcas channel predict`)."""

from __future__ import annotations

import pandas as pd
import pytest

from uavcas.channel import LinkChain, LinkGeometry, predict_links
from uavcas.channel.predict import OUTPUT, GeometryError, predict_frame, prediction_csv, read_geometry
from uavcas.twin.profile import PAPER_PROFILE


def _csv(tmp_path, text: str):
    path = tmp_path / "geom.csv"
    path.write_text(text)
    return path


def test_a_table_is_read_with_its_rounding_clamped_and_other_columns_kept(tmp_path):
    df, clamped = read_geometry(_csv(tmp_path, "d3d_m,d2d_m,h_uav_m,h_bs_m,name\n100,100.4,30,25,a\n200,150,40,25,b\n"))
    assert clamped == 1 and df["d2d_m"].tolist() == [100.0, 150.0] and df["name"].tolist() == ["a", "b"]
    assert all(df[c].dtype == float for c in ("d3d_m", "d2d_m", "h_uav_m", "h_bs_m"))


@pytest.mark.parametrize("text, message", [
    ("d3d_m,d2d_m,h_uav_m\n1,1,1\n", "missing column(s) h_bs_m"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m\n", "no rows"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m,snr_db\n1,1,1,1,0\n", "already has output column(s) snr_db"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m\n1,1,x,1\n", "column h_uav_m row 1: not a finite number ('x')"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m\n1,1,1,1\n1,1,1,-2\n", "column h_bs_m row 2: negative (-2.0)"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m,fc_ghz\n1,1,1,1,0\n", "column fc_ghz row 1: must be > 0"),
    ("d3d_m,d2d_m,h_uav_m,h_bs_m\n100,101,30,25\n", "row 1: d2d_m 101 exceeds d3d_m 100 by more than 0.5 m"),
])
def test_bad_tables_are_one_line_naming_the_file(tmp_path, text, message):
    path = _csv(tmp_path, text)
    with pytest.raises(GeometryError) as exc:
        read_geometry(path)
    assert str(exc.value).startswith(f"{path}: {message}") and "\n" not in str(exc.value), str(exc.value)
    with pytest.raises(GeometryError, match="no such file"):
        read_geometry(tmp_path / "absent.csv")


def test_the_prediction_is_the_link_chain_on_the_profile_and_is_written_as_read(tmp_path):
    df, _ = read_geometry(_csv(tmp_path, "d3d_m,d2d_m,h_uav_m,h_bs_m,fc_ghz\n500,499,30,25,3.51\n80,60,60,25,2.4\n"))
    out = predict_frame(df, "freespace", PAPER_PROFILE, tx_dbm=20.0, noise_dbm=-95.0)
    assert list(out.columns) == [*df.columns, *OUTPUT] and len(out) == 2
    geom = LinkGeometry(d3d_m=df["d3d_m"].to_numpy(), d2d_m=df["d2d_m"].to_numpy(), h_ground_m=df["h_bs_m"].to_numpy(),
                        h_air_m=df["h_uav_m"].to_numpy(), air_to_air=pd.Series([False, False]).to_numpy())
    chain = LinkChain.build(tx_power_dbm=20.0, noise_dbm=-95.0, **PAPER_PROFILE.chain_kwargs())
    want = predict_links("freespace", PAPER_PROFILE.pathloss, df["fc_ghz"].to_numpy(), geom, chain)
    assert out["pathloss_db"].tolist() == list(want.pathloss_db) and out["mcs"].tolist() == list(want.mcs)
    assert out["snr_db"].tolist() == list(want.snr_db) and out["loss"].tolist() == list(want.loss)
    (tmp_path / "out.csv").write_text(prediction_csv(out))
    back = pd.read_csv(tmp_path / "out.csv")
    assert list(back.columns) == list(out.columns)
    assert back["pathloss_db"].tolist() == pytest.approx(out["pathloss_db"].tolist(), rel=1e-9)
