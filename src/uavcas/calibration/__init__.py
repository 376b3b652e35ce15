"""Calibration of the twin against AERPAW measurements (paper sec. 4; `uavcas calibrate`).

One concept per module:
    loaders      the AERPAW files (.mat v5/v7, v7.3 via h5py, CSV[.gz]) from any layout; typed records
    linkbudget   received power -> absolute, antenna-compensated path loss (EIRP_eff, rad_pat.mat gains)
    segments     held-out contiguous flight segments, local means, the moment-method K factor
    metrics      error metrics and bounded divergences on shared bins
    layer1_fit        close-in log-distance n(h)/sigma(h) with the effective antenna pattern, K(h),
                      shadowing decorrelation, two-ray, TR 36.777 UMa-AV (training segments only)
    layer1_pathloss   their held-out and cross-validation scores, per sample and per 5 s local mean
    layer2_mobility   AFAR flights -> mission parameters with the twin's own generators; JSD / KL
    layer3_link       AFAR trajectories replayed through the twin's Channel vs measured power
    layer4_fidelity   Hellinger between RSS distributions on one scale, held-out data only
    figures, report   PNG figures, JSON / markdown tables, summary against the paper
    pipeline          runs the layers, writes the outputs and, optionally, a TwinProfile with provenance
Every fit uses the code the twin runs (`uavcas.channel`, `uavcas.mobility`).
"""

from .loaders import CalibrationDataError
from .pipeline import LAYERS, run

__all__ = ["LAYERS", "CalibrationDataError", "run"]
