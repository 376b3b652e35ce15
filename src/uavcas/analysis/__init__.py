"""Dataset analysis: IAT diversity tables (bounded divergences from `uavcas.stats`, and the
authors' legacy variant), internal diversity per configuration axis, separability statistics and
figures."""
