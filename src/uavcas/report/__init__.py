"""report: the dataset report page and topology figures; `figure` is the one place matplotlib is
set up (no display, atomic PNGs) for every package that draws."""
