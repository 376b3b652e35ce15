"""The delay stage's compiled verdict loop (nfqdelay.c): where it lives and how it is built.

Built with the system C compiler on first use (or ahead: `python -m uavcas.emulation.nfqdelay
--build`, which scripts/setup.sh runs), named by the hash of its source so an edit rebuilds it,
and kept beside the interpreter (`<prefix>/libexec/uavcas/`, or ~/.cache/uavcas where that is
not writable). Without a compiler `build_helper` returns None and the daemon runs its
pure-Python loop.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

SOURCE = Path(__file__).with_name("nfqdelay.c")


def helper_path() -> Path:
    """Where the helper for this source lives (the source's hash names it: edits rebuild it)."""
    digest = hashlib.sha256(SOURCE.read_bytes()).hexdigest()[:12]
    base = Path(sys.prefix) / "libexec" / "uavcas"
    if not os.access(base if base.exists() else Path(sys.prefix), os.W_OK):
        base = Path.home() / ".cache" / "uavcas"
    return base / f"uavcas-nfqdelay-{digest}"


def build_helper(force: bool = False) -> Path | None:
    """Compile the helper if needed; None when there is no C compiler or it fails (-> Python)."""
    path = helper_path()
    if path.exists() and not force:
        return path
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    res = subprocess.run([cc, "-O2", "-Wall", "-o", str(tmp), str(SOURCE)], capture_output=True, text=True)
    if res.returncode != 0:
        tmp.unlink(missing_ok=True)
        print(f"nfqdelay: C helper did not build, using the Python loop: {res.stderr.strip()[-300:]}",
              file=sys.stderr)
        return None
    os.replace(tmp, path)  # atomic: a concurrent run sees the old binary or the new one
    return path
