"""`uavcas doctor --vm`: the netem backend for real, in a stock Debian kernel under QEMU.

Kernels without `sch_netem` (like the CI's) can still run the netem backend: a stock Debian
kernel has it as a module. Recipe measured on this host: ../shared/docs/NETEM-VM.md.

* `prepare()` (run by scripts/setup.sh as root, idempotent): `apt-get download` the kernel
  package `linux-image-amd64` depends on, `dpkg -x` it under `VM_DIR`, `depmod -b`, and build a
  tiny initramfs (busybox-static + the modules the root mount needs, in dependency order).
* `doctor_in_vm()` boots it (`qemu-system-x86_64`, KVM when it works, else TCG) with the host's
  root file system shared over 9p **read-only** (QEMU refuses guest writes) and one dedicated
  output folder shared read-write; the guest's /run and /tmp are tmpfs. A guest script loads
  the modules the emulation needs (`modprobe -d`: the host has no /lib/modules for that
  kernel), runs `uavcas doctor --json` from this very checkout, writes its result into the
  output folder and powers off. The host reads the JSON.

KVM: /dev/kvm may open and still hang the guest at boot (nested virtualisation under
Firecracker here), so "auto" gives KVM `KVM_BOOT_S` to print the init marker, then falls back
to TCG (and remembers that for this boot of the host in `KVM_BROKEN`). TCG emulates the CPU,
several times slower: the guest is a place to prove that netem's requests are accepted and
that rate, delay and loss come out right on light traffic, not for timing-heavy runs, and its
CPU-contention reading is informational (an emulated CPU always looks contended).
"""

from __future__ import annotations

import hashlib
import json
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from uavcas.emulation import kernel

VM_DIR = Path(os.environ.get("UAVCAS_VM_DIR", "/var/cache/uavcas/vm"))
META_PACKAGE = "linux-image-amd64"
QEMU = "qemu-system-x86_64"
BUSYBOX = Path("/bin/busybox")
KVM_BROKEN = Path("/run/uavcas-vm-kvm-broken")
KVM_BOOT_S = 25.0  # a KVM guest prints the init marker within seconds; a hung one never does
BOOT_MODULES = ("virtio_pci", "9pnet_virtio", "9p")  # the 9p root mount (dependencies added)
GUEST_MODULES = ("veth", "bridge", "br_netfilter", "sch_htb", "sch_netem", "sch_tbf", "nf_tables", "nft_numgen",
                 "nfnetlink_queue", "nft_queue", "xt_NFQUEUE", "xt_physdev", "iptable_filter", "nft_compat")
INIT_MARKER = "uavcas-vm: init"
GUEST_OUT = "/run/uavcas-vm/out"  # the output folder, as the guest sees it
TIMEOUT_S = 600.0  # whole round trip, TCG included (measured: see docs/architecture.md)


class VmError(RuntimeError):
    """The VM could not be prepared or booted; one line."""


@dataclass(frozen=True)
class GuestKernel:
    root: Path  # `dpkg -x` of the kernel package
    version: str  # e.g. 6.1.0-56-amd64

    @property
    def vmlinuz(self) -> Path:
        return self.root / "boot" / f"vmlinuz-{self.version}"

    @property
    def modules(self) -> Path:
        return self.root / "lib" / "modules" / self.version

    @property
    def initrd(self) -> Path:
        """Named after what it holds: a change of the init script or modules builds a new one."""
        init = init_script(module_chain((self.modules / "modules.dep").read_text(), BOOT_MODULES))
        return self.root / f"uavcas-initrd-{hashlib.sha256(init.encode()).hexdigest()[:12]}.gz"


def kernel_package() -> str:
    """The concrete image package the meta package points at (e.g. linux-image-6.1.0-56-amd64)."""
    out = subprocess.run(["apt-cache", "depends", META_PACKAGE], capture_output=True, text=True, timeout=60).stdout
    for line in out.splitlines():
        word = line.strip().split()
        if len(word) == 2 and word[0] == "Depends:" and word[1].startswith("linux-image-"):
            return word[1]
    raise VmError(f"apt-cache knows no kernel behind {META_PACKAGE}")


def installed() -> GuestKernel | None:
    """The prepared guest kernel (the newest, if several), or None."""
    for d in sorted(VM_DIR.glob("linux-image-*"), reverse=True):
        version = d.name.removeprefix("linux-image-")
        k = GuestKernel(d, version)
        if k.vmlinuz.is_file() and (k.modules / "modules.dep").is_file():
            return k
    return None


def prepare(log=print) -> GuestKernel:
    """Fetch (apt), unpack and index the guest kernel and build its initramfs; idempotent."""
    pkg = kernel_package()
    version = pkg.removeprefix("linux-image-")
    k = GuestKernel(VM_DIR / pkg, version)
    if not (k.vmlinuz.is_file() and (k.modules / "modules.dep").is_file()):
        VM_DIR.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=VM_DIR, prefix=".fetch-") as tmp:
            log(f"apt-get download {pkg}")
            _run(["apt-get", "download", "-q", "-o", "APT::Sandbox::User=root", pkg], cwd=tmp)
            deb = next(Path(tmp).glob("*.deb"))
            unpacked = Path(tmp) / "root"
            _run(["dpkg", "-x", str(deb), str(unpacked)])
            _run(["depmod", "-b", str(unpacked), version])
            shutil.rmtree(k.root, ignore_errors=True)
            os.replace(unpacked, k.root)
    if not k.initrd.is_file():
        log(f"initramfs for {version}")
        build_initramfs(k)
    return k


def _run(argv: list[str], **kw) -> None:
    r = subprocess.run(argv, capture_output=True, text=True, timeout=600, **kw)
    if r.returncode != 0:
        raise VmError(f"{' '.join(argv[:3])} -> rc {r.returncode}: {r.stderr.strip()[-300:]}")


def module_chain(modules_dep: str, names: tuple[str, ...]) -> list[str]:
    """Module paths (relative to the modules dir) to insmod, dependencies first, each once."""
    deps: dict[str, list[str]] = {}
    by_name: dict[str, str] = {}
    for line in modules_dep.splitlines():
        if ":" not in line:
            continue
        mod, rest = line.split(":", 1)
        deps[mod] = rest.split()
        by_name[Path(mod).name.split(".ko")[0].replace("-", "_")] = mod
    order: list[str] = []

    def visit(mod: str) -> None:
        if mod in order:
            return
        for d in reversed(deps.get(mod, [])):  # modules.dep lists the deepest dependency last
            visit(d)
        order.append(mod)

    for name in names:
        if name not in by_name:
            raise VmError(f"module {name} is not in this kernel")
        visit(by_name[name])
    return order


def init_script(modules: list[str]) -> str:
    """/init of the initramfs (busybox sh): 9p root read-only, tmpfs, output share, switch_root."""
    ins = "\n".join(f"insmod /lib/{Path(m).name}" for m in modules)
    opts = "trans=virtio,version=9p2000.L,msize=512000"
    return f"""#!/bin/busybox sh
/bin/busybox --install -s /bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
echo "{INIT_MARKER}" > /dev/console
{ins}
mkdir -p /newroot
mount -t 9p -o {opts},ro,cache=loose hostroot /newroot || {{ echo "uavcas-vm: no root" > /dev/console; poweroff -f; }}
mount -t tmpfs -o mode=755 tmpfs /newroot/run
mount -t tmpfs -o mode=1777 tmpfs /newroot/tmp
mkdir -p {GUEST_OUT}
mkdir -p /newroot{GUEST_OUT}
mount -t 9p -o {opts} vmout /newroot{GUEST_OUT}
mount --move /proc /newroot/proc
mount --move /sys /newroot/sys
mount --move /dev /newroot/dev
exec switch_root /newroot /bin/sh {GUEST_OUT}/guest.sh
"""


def build_initramfs(k: GuestKernel) -> Path:
    if not BUSYBOX.is_file():
        raise VmError(f"{BUSYBOX} missing: apt-get install busybox-static (scripts/setup.sh)")
    mods = module_chain((k.modules / "modules.dep").read_text(), BOOT_MODULES)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for d in ("bin", "lib", "proc", "sys", "dev", "newroot"):
            (root / d).mkdir()
        shutil.copy2(BUSYBOX, root / "bin" / "busybox")
        for m in mods:
            shutil.copy2(k.modules / m, root / "lib" / Path(m).name)
        init = root / "init"
        init.write_text(init_script(mods))
        init.chmod(0o755)
        files = subprocess.run(["find", "."], cwd=root, capture_output=True, text=True, check=True).stdout
        cpio = subprocess.run(["cpio", "-o", "-H", "newc", "--quiet"], cwd=root, input=files.encode(),
                              capture_output=True, check=True).stdout
        for old in k.root.glob("uavcas-initrd*.gz"):
            old.unlink()
        tmp_out = k.initrd.with_suffix(".tmp")
        gz = subprocess.run(["gzip", "-9"], input=cpio, capture_output=True, check=True).stdout
        tmp_out.write_bytes(gz)
        os.replace(tmp_out, k.initrd)
    return k.initrd


def unavailable() -> str | None:
    """Why the VM cannot run here at all (None: it can)."""
    if os.geteuid() != 0:
        return "the VM doctor needs root (9p passthrough of the host's root, namespaces in the guest)"
    if shutil.which(QEMU) is None:
        return f"{QEMU} is not installed (scripts/setup.sh installs qemu-system-x86)"
    if installed() is None:
        return f"no guest kernel under {VM_DIR} (scripts/setup.sh fetches it with apt)"
    return None


def kvm_worth_trying() -> bool:
    try:
        fd = os.open("/dev/kvm", os.O_RDWR | os.O_CLOEXEC)
    except OSError:
        return False
    os.close(fd)
    return not KVM_BROKEN.exists()


def _reveal(repo: Path) -> str:
    """Guest shell lines that make a checkout under /tmp visible again: the guest's /tmp is its own
    tmpfs (the 9p root is read-only), which hides a clone made with `mktemp -d`. A second mount of
    the root (a plain bind does not carry the tmpfs above it) bound over the path shows it
    (read-only, as the rest of the host)."""
    if not (repo == Path("/tmp") or Path("/tmp") in repo.parents):
        return ""
    r = shlex.quote(str(repo))
    return f"mkdir -p /run/hostroot {r} && mount --bind / /run/hostroot && mount --bind /run/hostroot{r} {r}\n"


def guest_script(k: GuestKernel, repo: Path, argv: list[str]) -> str:
    """What the guest runs after switch_root: modules, the command, its exit status, power off."""
    cmd = " ".join(shlex.quote(a) for a in argv)
    return f"""#!/bin/sh
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/tmp PYTHONDONTWRITEBYTECODE=1
OUT={GUEST_OUT}
up() {{ read -r s _ < /proc/uptime; echo "uavcas-vm: $1 at $s s" > /dev/console; }}
up "guest kernel $(uname -r), root mounted"
modprobe -d {shlex.quote(str(k.root))} -a {' '.join(GUEST_MODULES)} > $OUT/modprobe.log 2>&1
up "modules loaded"
{_reveal(repo)}cd {shlex.quote(str(repo))}
{cmd} > $OUT/command.out 2>&1
echo $? > $OUT/command.rc
up "done"
echo o > /proc/sysrq-trigger
sleep 30
"""


def qemu_argv(k: GuestKernel, out_dir: Path, accel: str, memory_mb: int = 2048, cpus: int = 2) -> list[str]:
    """The host's / shared read-only (QEMU refuses every guest write), `out_dir` read-write."""
    return [QEMU, "-accel", accel, "-cpu", "host" if accel == "kvm" else "max", "-m", str(memory_mb),
            "-smp", str(cpus), "-nographic", "-no-reboot", "-nodefaults", "-serial", "stdio",
            "-kernel", str(k.vmlinuz), "-initrd", str(k.initrd), "-append", "console=ttyS0 panic=-1 quiet",
            "-fsdev", "local,id=root,path=/,security_model=passthrough,multidevs=remap,readonly=on",
            "-device", "virtio-9p-pci,fsdev=root,mount_tag=hostroot",
            "-fsdev", f"local,id=out,path={out_dir},security_model=passthrough",
            "-device", "virtio-9p-pci,fsdev=out,mount_tag=vmout"]


@dataclass(frozen=True)
class GuestRun:
    accel: str
    wall_s: float
    rc: int | None  # the command's exit status in the guest (None: it never finished)
    out_dir: Path
    console: str


def boot(k: GuestKernel, out_dir: Path, script: str, accel: str, timeout_s: float = TIMEOUT_S,
         boot_deadline_s: float | None = None, memory_mb: int = 2048, cpus: int = 2) -> GuestRun | None:
    """Boot the guest once; None if `boot_deadline_s` passed without the init marker."""
    (out_dir / "guest.sh").write_text(script)
    console_path = out_dir / "console.log"
    # under `timeout` too: a guest outlives nothing, not even a SIGKILLed parent
    argv = kernel.timed(qemu_argv(k, out_dir, accel, memory_mb, cpus), timeout_s + 30)
    t0 = time.monotonic()
    with open(console_path, "wb") as console:
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=console, stderr=subprocess.STDOUT,
                                start_new_session=True)
        try:
            if boot_deadline_s is not None:
                while INIT_MARKER not in console_path.read_text(errors="replace"):
                    if proc.poll() is not None or time.monotonic() - t0 > boot_deadline_s:
                        return None
                    time.sleep(0.2)
            proc.wait(max(1.0, timeout_s - (time.monotonic() - t0)))
        except subprocess.TimeoutExpired:
            pass
        finally:
            if proc.poll() is None:
                proc.terminate()  # `timeout` passes it on to QEMU
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
    rc_path = out_dir / "command.rc"
    rc = int(rc_path.read_text().strip()) if rc_path.exists() and rc_path.read_text().strip() else None
    return GuestRun(accel, time.monotonic() - t0, rc, out_dir, console_path.read_text(errors="replace"))


def run_in_vm(python_args, out_dir: Path, accel: str = "auto", timeout_s: float = TIMEOUT_S,
              log=lambda s: None) -> GuestRun:
    """`python <python_args(accel)>` (this interpreter, this checkout) inside the guest; the
    files it writes under GUEST_OUT land in `out_dir`."""
    why = unavailable()
    if why:
        raise VmError(why)
    k = installed()
    if not k.initrd.is_file():
        log(f"building the initramfs for {k.version}")
        build_initramfs(k)
    repo = Path(__file__).resolve().parents[3]

    def script(acc: str) -> str:
        return guest_script(k, repo, [sys.executable, *python_args(acc)])

    if accel in ("auto", "kvm") and (accel == "kvm" or kvm_worth_trying()):
        log("booting with KVM")
        run = boot(k, out_dir, script("kvm"), "kvm", timeout_s, boot_deadline_s=KVM_BOOT_S)
        if run is not None:
            return run
        if accel == "kvm":
            raise VmError(f"a KVM guest did not reach its init within {KVM_BOOT_S:g} s")
        KVM_BROKEN.touch()
        log(f"KVM guest hung before init ({KVM_BOOT_S:g} s): TCG from now on (until {KVM_BROKEN} goes)")
    log("booting with TCG (emulated CPU)")
    run = boot(k, out_dir, script("tcg"), "tcg", timeout_s)
    assert run is not None
    return run


def doctor_in_vm(accel: str = "auto", timeout_s: float = TIMEOUT_S, log=lambda s: None,
                 keep: Path | None = None) -> tuple[dict | None, GuestRun | None, str | None]:
    """(the guest doctor's JSON, the guest run, an error line). The output folder is a fresh
    temporary one (or `keep`): the only host place the guest may write."""
    out_dir = Path(keep) if keep else Path(tempfile.mkdtemp(prefix="uavcas-vm-"))
    out_dir.mkdir(parents=True, exist_ok=True)
    try:
        def args(acc: str) -> list[str]:  # an emulated CPU gets the light profile
            return ["-m", "uavcas.diagnostics.doctor", "--json", f"{GUEST_OUT}/doctor.json", "--profile",
                    "native" if acc == "kvm" else "emulated-cpu"]

        run = run_in_vm(args, out_dir, accel, timeout_s, log)
        try:
            return json.loads((out_dir / "doctor.json").read_text()), run, None
        except (OSError, ValueError):
            out = out_dir / "command.out"
            tail = (out.read_text(errors="replace") if out.exists() else run.console)[-400:].strip()
            return None, run, f"the guest doctor wrote no result (exit {run.rc}, {run.wall_s:.0f} s): {tail}"
    except VmError as e:
        return None, None, str(e)
    finally:
        if keep is None:
            shutil.rmtree(out_dir, ignore_errors=True)


def main(argv: list[str] | None = None) -> None:
    args = argv if argv is not None else sys.argv[1:]
    if args != ["prepare"]:
        raise SystemExit("usage: python -m uavcas.diagnostics.vm prepare")
    k = prepare(lambda s: print(f"[vm] {s}", file=sys.stderr))
    print(f"[vm] guest kernel {k.version} ready under {k.root}", file=sys.stderr)


if __name__ == "__main__":
    main()
