"""`uavcas doctor --vm` for real: a stock Debian kernel under QEMU runs the netem backend.

Root tests; skipped with the reason only where QEMU cannot run at all (no qemu-system-x86_64,
or no guest kernel: scripts/setup.sh installs both). Slow: each boots a guest (TCG here, about
0.5-2 min; KVM where it works).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from uavcas.diagnostics import vm

pytestmark = pytest.mark.root
UAVCAS = str(Path(sys.executable).parent / "uavcas")


@pytest.fixture(scope="module", autouse=True)
def _qemu_runs():
    why = vm.unavailable()
    if why:
        pytest.skip(f"QEMU cannot run here: {why}")


def test_doctor_vm_passes_with_the_netem_backend(tmp_path):
    """The guest uses netem. It must pass on a quiet host; on a busy one (an emulated CPU is as
    fast as the host lets it be) a failure must name the host's measured contention."""
    r = subprocess.run([UAVCAS, "doctor", "--vm", "--json", str(tmp_path / "vm.json")], capture_output=True,
                       text=True, timeout=vm.TIMEOUT_S + 120)
    d = json.loads((tmp_path / "vm.json").read_text())
    assert d["backend"] == "netem" and d["features"]["netem"] is True and d["error"] is None
    assert d["vm"]["accel"] in ("kvm", "tcg") and d["vm"]["kernel"] == vm.installed().version
    names = [c["name"] for c in d["checks"]]
    assert names[0] == "TCP goodput" and "one-way delay p50" in names and names[-1].startswith("loss")
    host = d["vm"]["host_contention"]["level"]
    if r.returncode != 0:
        assert host != "quiet" and f"the host was {host}" in r.stderr, r.stdout[-3000:] + r.stderr
    else:
        assert d["ok"] is True and all(c["ok"] is True for c in d["checks"]) and "doctor --vm: ok" in r.stdout


def test_guest_writes_only_its_output_folder(tmp_path):
    """The host's root is read-only in the guest (QEMU refuses the write), /tmp is the guest's
    own tmpfs, and the output folder is written through."""
    host_dir = Path(tempfile.mkdtemp(dir="/var/tmp", prefix="uavcas-vm-test-"))  # the guest's /tmp is its own
    target = host_dir / "host-file"
    code = ("import os, pathlib\n"
            f"out = pathlib.Path('{vm.GUEST_OUT}')\n"
            "try:\n"
            f"    pathlib.Path('{target}').write_text('guest')\n"
            "    (out / 'root').write_text('written')\n"
            "except OSError as e:\n"
            "    (out / 'root').write_text(f'refused {e.errno}')\n"
            "pathlib.Path('/tmp/scratch').write_text('x')\n"
            "(out / 'tmp').write_text(str(os.statvfs('/tmp').f_fsid) + ' ' + "
            "pathlib.Path('/tmp/scratch').read_text())\n")
    out = tmp_path / "out"
    out.mkdir()
    run = vm.run_in_vm(lambda accel: ["-c", code], out, timeout_s=vm.TIMEOUT_S)
    assert run.rc == 0, (out / "command.out").read_text()[-2000:] if (out / "command.out").exists() else run.console
    try:
        assert (out / "root").read_text() == "refused 30"  # EROFS
        assert not target.exists() and not Path("/tmp/scratch").exists()
        assert (out / "tmp").read_text().endswith(" x")
    finally:
        shutil.rmtree(host_dir)
