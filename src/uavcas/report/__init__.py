"""report: the dataset report page and its figures (topology, fidelity, distributions); they draw
through `uavcas.figure`, the one place matplotlib is set up for every package that draws."""
