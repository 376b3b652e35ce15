"""The VM doctor's pieces without booting anything: module order, init, guest script, QEMU argv."""

from __future__ import annotations

from pathlib import Path

import pytest

from uavcas.diagnostics import vm

DEP = """kernel/fs/9p/9p.ko: kernel/net/9p/9pnet.ko kernel/fs/fscache/fscache.ko kernel/fs/netfs/netfs.ko
kernel/fs/fscache/fscache.ko: kernel/fs/netfs/netfs.ko
kernel/fs/netfs/netfs.ko:
kernel/net/9p/9pnet.ko:
kernel/net/9p/9pnet_virtio.ko: kernel/net/9p/9pnet.ko kernel/drivers/virtio/virtio.ko kernel/drivers/virtio/virtio_ring.ko
kernel/drivers/virtio/virtio.ko: kernel/drivers/virtio/virtio_ring.ko
kernel/drivers/virtio/virtio_ring.ko:
kernel/drivers/virtio/virtio_pci.ko: kernel/drivers/virtio/virtio_pci_legacy_dev.ko kernel/drivers/virtio/virtio_pci_modern_dev.ko kernel/drivers/virtio/virtio.ko kernel/drivers/virtio/virtio_ring.ko
kernel/drivers/virtio/virtio_pci_legacy_dev.ko:
kernel/drivers/virtio/virtio_pci_modern_dev.ko:
"""  # noqa: E501 (modules.dep lines: one module per line, they cannot wrap)


def test_module_chain_puts_every_dependency_first_once():
    order = [Path(m).stem for m in vm.module_chain(DEP, vm.BOOT_MODULES)]
    assert sorted(order) == sorted(set(order))  # each once
    for mod, deps in (("9p", ["9pnet", "fscache", "netfs"]), ("9pnet_virtio", ["9pnet", "virtio", "virtio_ring"]),
                      ("virtio_pci", ["virtio_pci_legacy_dev", "virtio", "virtio_ring"]), ("fscache", ["netfs"])):
        assert all(order.index(d) < order.index(mod) for d in deps), (mod, order)
    with pytest.raises(vm.VmError, match="not in this kernel"):
        vm.module_chain(DEP, ("sch_netem",))


def test_guest_may_write_only_tmpfs_and_its_output_folder(tmp_path):
    init = vm.init_script(vm.module_chain(DEP, vm.BOOT_MODULES))
    assert "ro,cache=loose hostroot /newroot" in init  # the host's root: read-only in the guest ...
    assert "mount -t tmpfs -o mode=755 tmpfs /newroot/run" in init and "tmpfs /newroot/tmp" in init
    assert f"vmout /newroot{vm.GUEST_OUT}" in init and vm.INIT_MARKER in init
    k = vm.GuestKernel(tmp_path, "6.1.0-1-amd64")
    (k.modules).mkdir(parents=True)
    (k.modules / "modules.dep").write_text(DEP)
    argv = vm.qemu_argv(k, tmp_path / "out", "tcg")
    fsdevs = [argv[i + 1] for i, a in enumerate(argv) if a == "-fsdev"]
    assert fsdevs[0].startswith("local,id=root,path=/,") and "readonly=on" in fsdevs[0]  # ... and refused by QEMU
    assert fsdevs[1] == f"local,id=out,path={tmp_path / 'out'},security_model=passthrough"
    assert argv[argv.index("-accel") + 1] == "tcg" and argv[argv.index("-cpu") + 1] == "max"
    assert "readonly" not in fsdevs[1] and len(fsdevs) == 2


def test_initrd_name_follows_its_content(tmp_path):
    k = vm.GuestKernel(tmp_path, "6.1.0-1-amd64")
    k.modules.mkdir(parents=True)
    (k.modules / "modules.dep").write_text(DEP)
    name = k.initrd.name
    assert name.startswith("uavcas-initrd-") and name == k.initrd.name
    (k.modules / "modules.dep").write_text(DEP.replace("netfs.ko:", "netfs.ko: kernel/fs/x.ko\nkernel/fs/x.ko:"))
    assert k.initrd.name != name


def test_guest_script_loads_modules_runs_and_powers_off(tmp_path):
    k = vm.GuestKernel(tmp_path / "k", "6.1.0-1-amd64")
    script = vm.guest_script(k, Path("/repo dir"), ["/venv/bin/python", "-m", "uavcas.diagnostics.doctor"])
    assert f"modprobe -d {tmp_path / 'k'} -a " in script and "sch_netem" in script
    assert "cd '/repo dir'" in script and "/venv/bin/python -m uavcas.diagnostics.doctor > $OUT/command.out" in script
    assert script.index("command.rc") < script.index("echo o > /proc/sysrq-trigger")
