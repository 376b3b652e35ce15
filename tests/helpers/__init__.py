"""Helper modules shared by several test directories, imported as `helpers.<module>`.

`tests/` is on sys.path because pytest (default `prepend` import mode) puts the directory of the
rootdir conftest, `tests/conftest.py`, there; no test edits sys.path (`tests/test_repository.py`).
"""
