"""stats: statistics shared by the analyses and the calibration, owned by neither (divergences)."""
