"""dataset: Parquet shards + card (store, parquet), the one reader of every flow format (read),
the authors' CSV layout (uavcas_csv) and external IDS dataset loaders (external). The column
contract itself is `uavcas.schema`."""
