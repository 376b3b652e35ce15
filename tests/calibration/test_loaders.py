"""Loaders: .mat and CSV forms agree, any layout is found, malformed files are refused clearly."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
import scipy.io

from uavcas.calibration.loaders import CalibrationDataError, load_afar, load_maeng, load_multibw, read_table

from .synthetic import write_maeng


def test_mat_and_csv_forms_give_the_same_samples(tmp_path):
    write_maeng(tmp_path / "a", n=50, fmt="mat")
    write_maeng(tmp_path / "b", n=50, fmt="csv")
    a, b = load_maeng(tmp_path / "a"), load_maeng(tmp_path / "b")
    assert [s.altitude_m for s in a] == [30, 50, 70, 90, 110]
    for sa, sb in zip(a, b):
        assert sa.source.suffix == ".mat" and sb.source.name.endswith(".csv.gz")
        np.testing.assert_allclose(sa.rx_dbm, sb.rx_dbm)
        np.testing.assert_allclose(sa.d3d_m, sb.d3d_m)


def test_mat_preferred_when_both_forms_exist(tmp_path):
    write_maeng(tmp_path, n=20, fmt="mat")
    write_maeng(tmp_path, n=30, fmt="csv")
    assert all(s.source.suffix == ".mat" and len(s) == 20 for s in load_maeng(tmp_path))


def test_flat_folder_layout(tmp_path):
    write_maeng(tmp_path / "nested", n=20, fmt="mat")
    flat = tmp_path / "flat"
    flat.mkdir()
    for p in (tmp_path / "nested").rglob("*.mat"):
        (flat / p.name).write_bytes(p.read_bytes())
    assert len(load_maeng(flat)) == 5


def _one_line(e: pytest.ExceptionInfo) -> str:
    msg = str(e.value)
    assert "\n" not in msg
    return msg


def test_missing_column_is_refused_naming_file_and_column(tmp_path):
    p = tmp_path / "filtererd_data_with_dist_ori_30_meas_rad.mat"
    scipy.io.savemat(p, {"RSRP_s": np.zeros(5), "dist_3D_s": np.ones(5)})
    with pytest.raises(CalibrationDataError) as e:
        load_maeng(tmp_path)
    msg = _one_line(e)
    assert p.name in msg and "RSRP_PL_free_s" in msg


def test_garbage_mat_is_refused(tmp_path):
    p = tmp_path / "results_useful_ori_exp_300_loc_1.mat"
    p.write_bytes(b"this is not a MATLAB file at all" * 10)
    with pytest.raises(CalibrationDataError) as e:
        load_afar(tmp_path)
    assert p.name in _one_line(e)


def test_matlab_v73_gets_a_clear_message(tmp_path):
    p = tmp_path / "x.mat"
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
    p.write_bytes(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM" + b"\x00" * 64)
    with pytest.raises(CalibrationDataError) as e:
        read_table(p)
    msg = _one_line(e)
    assert "v7.3" in msg and str(p) in msg


def test_non_numeric_and_ragged_csv_are_refused(tmp_path):
    p = tmp_path / "multibw_processed_data_results_cole_with_tworay_tilt_src_alt_40m_fs5MHz.csv.gz"
    with gzip.open(p, "wt") as fh:
        fh.write("power_all,RSRP_PL_free,dist_3D,dist_2D_new,h_all\n1,2,3,4,5\nx,2,3,4,5\n")
    with pytest.raises(CalibrationDataError) as e:
        load_multibw(tmp_path)
    assert "power_all" in _one_line(e) and p.name in str(e.value)
    q = tmp_path / "broken.csv"
    q.write_bytes(b"\x00\xff\x00garbage")
    with pytest.raises(CalibrationDataError):
        read_table(tmp_path / "missing.csv")
    with pytest.raises(CalibrationDataError):
        read_table(tmp_path / "file.txt")


def test_empty_folder_says_what_is_missing(tmp_path):
    for loader, word in ((load_maeng, "Maeng"), (load_multibw, "multi-band"), (load_afar, "AFAR")):
        with pytest.raises(CalibrationDataError) as e:
            loader(tmp_path)
        assert word in _one_line(e)
    with pytest.raises(CalibrationDataError):
        load_maeng(tmp_path / "nope")
