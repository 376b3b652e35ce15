"""Dataset analysis: bounded IAT divergences (and the authors' legacy variant), diversity tables,
internal diversity per configuration axis, separability statistics and figures."""
