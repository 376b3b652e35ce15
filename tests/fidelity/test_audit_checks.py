"""The root tests' rule for a failed delay check the host explains (`helpers.audit_checks`)."""

from __future__ import annotations

from helpers.audit_checks import late_share

# a gps_spoof run of stop 38 (run.json delay_daemon.lag_hist_us): 6,887 frames
HIST = {"25": 5382, "50": 700, "100": 255, "200": 170, "500": 190, "1000": 119, "2000": 67, "5000": 4,
        "10000": 0, "1000000000": 0}


def test_only_buckets_wholly_past_the_limit_count():
    # past 0.5 ms: the 500-1000, 1000-2000 and 2000-5000 us buckets (the 200-500 one may be on time)
    assert late_share(HIST, 0.5) == (119 + 67 + 4) / 6887
    assert late_share(HIST, 0.2) == (190 + 119 + 67 + 4) / 6887
    assert late_share(HIST, 0.3) == late_share(HIST, 0.5)  # 0.3 ms falls inside a bucket: not proven late
    # the first bucket starts at 0
    assert late_share({}, 0.5) == 0.0 and late_share({"25": 10, "50": 5}, 0.01) == 5 / 15
