"""dataset: the column contract (schema), Parquet shards + card (store), the authors' CSV layout
(uavcas_csv) and external IDS dataset loaders (external)."""
